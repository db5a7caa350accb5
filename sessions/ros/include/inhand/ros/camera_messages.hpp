#pragma once
// A camera's ROS messages as inhand's types: the same conversions for a recording being imported
// and for the live node's topics.
#include <string>

#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/ros/messages.hpp"

namespace inhand::ros {

// sensor_msgs/Image (rgb8, bgr8, rgba8, bgra8, mono8, mono16) as RGB. Throws InputError naming
// `context` and the encoding, or the sizes that do not fit.
Image8 ImageOf(const ImageMsg& m, const std::string& context);
// sensor_msgs/CompressedImage (format naming jpeg or png) decoded. Throws InputError naming
// `context` when the format is another or the bytes do not decode.
Image8 ImageOf(const CompressedImageMsg& m, const std::string& context);
// sensor_msgs/CameraInfo's pinhole and plumb_bob distortion. Throws InputError naming `context`
// for a skew term, another distortion model or intrinsics that are not valid.
Intrinsics IntrinsicsOf(const CameraInfoMsg& m, const std::string& context);

}  // namespace inhand::ros
