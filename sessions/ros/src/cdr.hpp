#pragma once
// Decoding of the imported message types from CDR (ROS 2's serialization: an encapsulation
// header, then XCDR1 with alignment relative to the end of that header). Internal.
#include <cstddef>
#include <cstdint>
#include <string>

#include "inhand/ros/messages.hpp"

namespace inhand::ros {

// `context` names the message in errors ("FILE: topic /joints, message 12"). Throws
// InputError for truncated or malformed data. Image data is skipped when `decode_images` is
// false (stamps, sizes and encodings are still decoded).
Payload DecodeCdr(MsgType type, const std::uint8_t* data, std::size_t size, bool decode_images, const std::string& context);

}  // namespace inhand::ros
