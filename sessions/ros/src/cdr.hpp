#pragma once
// Decoding of the imported message types from CDR (ROS 2's serialization: an encapsulation
// header, then XCDR1 with alignment relative to the end of that header) and from ROS 1's
// serialization (bag records). Bounds-checked: a corrupt length is an InputError before any
// allocation (roscpp's own deserialisers resize arrays to whatever count the bytes claim: a
// fuzzed bag took 132 s and gigabytes of zeroed memory to be refused). Internal.
#include <cstddef>
#include <cstdint>
#include <string>

#include "inhand/ros/messages.hpp"

namespace inhand::ros {

// `context` names the message in errors ("FILE: topic /joints, message 12"). Throws
// InputError for truncated or malformed data. Image data is skipped when `decode_images` is
// false (stamps, sizes and encodings are still decoded).
Payload DecodeCdr(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
                  const std::string& context);
// The same from ROS 1's serialisation (the message body of a bag record).
Payload DecodeRos1(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
                   const std::string& context);
// Both, by `ros1`.
Payload Decode(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images,
               const std::string& context, bool ros1);

}  // namespace inhand::ros
