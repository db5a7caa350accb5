#pragma once
// The ROS messages inhand imports, decoded into plain structs that do not depend on ROS: the
// same struct whether the message came from a ROS 1 bag (Debian's roscpp types) or a ROS 2
// recording (our CDR decoder). Times are nanoseconds since the epoch.
#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "inhand/core/so3.hpp"

namespace inhand::ros {

struct Header {
  std::int64_t stamp_ns = 0;  // 0: unset (the importer then uses the log time)
  std::string frame_id;
};

struct JointStateMsg {  // sensor_msgs/JointState
  Header header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};

struct ImageMsg {  // sensor_msgs/Image
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;
  std::vector<std::uint8_t> data;
};

struct CompressedImageMsg {  // sensor_msgs/CompressedImage
  Header header;
  std::string format;  // "jpeg", "png", "rgb8; jpeg compressed bgr8", ...
  std::vector<std::uint8_t> data;
};

struct CameraInfoMsg {  // sensor_msgs/CameraInfo (ROS 1 D, K, R, P are ROS 2's d, k, r, p)
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
};

// A rigid transform kept as the message carries it (translation + quaternion), so that a pose
// read from a recording and written into a session comes out digit for digit; composition and
// inversion in quaternion arithmetic (exact when one side is the identity).
struct Pose {
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  Pose operator*(const Pose& o) const { return {p + q * o.p, q * o.q}; }
  Pose Inverse() const {
    const Quat qi = q.conjugate();
    return {-(qi * p), qi};
  }
  Transform ToTransform() const { return MakeTransform(p, q); }  // normalises q
};

// A pose of `child_frame_id` in `header.frame_id`: geometry_msgs/TransformStamped (one entry of
// tf2_msgs/TFMessage), geometry_msgs/PoseStamped (no child) or nav_msgs/Odometry's pose.
struct StampedTransform {
  Header header;
  std::string child_frame_id;
  Pose T;
};

struct TfMsg {  // tf2_msgs/TFMessage (ROS 1's tf/tfMessage has the same layout)
  std::vector<StampedTransform> transforms;
};

using Payload = std::variant<std::monostate, JointStateMsg, ImageMsg, CompressedImageMsg,
                             CameraInfoMsg, TfMsg, StampedTransform>;

// The message types inhand decodes, by their ROS 1 names (ROS 2's "pkg/msg/Type" is normalised
// to "pkg/Type"). Everything else in a recording is listed but not decoded.
enum class MsgType {
  kOther,
  kJointState,
  kImage,
  kCompressedImage,
  kCameraInfo,
  kTf,
  kPoseStamped,
  kTransformStamped,
  kOdometry
};
MsgType MsgTypeOf(const std::string& type_name);
// "sensor_msgs/msg/JointState" → "sensor_msgs/JointState"; ROS 1 names stay as they are.
std::string NormaliseTypeName(const std::string& type_name);

// A unit quaternion from a message, or an InputError naming `context` when it is not one
// (within 1e-3: recorders round; beyond 1e-9 it is normalised, closer it is kept as it is).
Quat MessageQuaternion(double w, double x, double y, double z, const std::string& context);

// A JointState's columns for the hand's joints, by name: where each of `wanted` stands in
// `names` (-1 where absent); the absent ones are appended to `missing`.
std::vector<int> ColumnsByName(const std::vector<std::string>& wanted,
                               const std::vector<std::string>& names,
                               std::vector<std::string>& missing);

}  // namespace inhand::ros
