#include "inhand/ros/messages.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand::ros {

std::string NormaliseTypeName(const std::string& type_name) {
  const std::size_t a = type_name.find("/msg/");
  if (a == std::string::npos) return type_name;
  return type_name.substr(0, a) + "/" + type_name.substr(a + 5);
}

MsgType MsgTypeOf(const std::string& type_name) {
  const std::string t = NormaliseTypeName(type_name);
  if (t == "sensor_msgs/JointState") return MsgType::kJointState;
  if (t == "sensor_msgs/Image") return MsgType::kImage;
  if (t == "sensor_msgs/CompressedImage") return MsgType::kCompressedImage;
  if (t == "sensor_msgs/CameraInfo") return MsgType::kCameraInfo;
  if (t == "tf2_msgs/TFMessage" || t == "tf/tfMessage") return MsgType::kTf;
  if (t == "geometry_msgs/PoseStamped") return MsgType::kPoseStamped;
  if (t == "geometry_msgs/TransformStamped") return MsgType::kTransformStamped;
  if (t == "nav_msgs/Odometry") return MsgType::kOdometry;
  return MsgType::kOther;
}

Quat MessageQuaternion(double w, double x, double y, double z, const std::string& context) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3) {
    std::ostringstream s;
    s << context << ": quaternion (w " << w << ", x " << x << ", y " << y << ", z " << z
      << ") is not a unit quaternion";
    throw InputError(s.str());
  }
  // Unit to rounding: kept bit-identical (a round trip through a recording is exact).
  if (std::abs(n - 1.0) <= 1e-9) return Quat(w, x, y, z);
  return Quat(w / n, x / n, y / n, z / n);
}

std::vector<int> ColumnsByName(const std::vector<std::string>& wanted,
                               const std::vector<std::string>& names,
                               std::vector<std::string>& missing) {
  std::vector<int> column(wanted.size(), -1);
  for (std::size_t j = 0; j < wanted.size(); ++j) {
    const auto it = std::find(names.begin(), names.end(), wanted[j]);
    if (it == names.end())
      missing.push_back(wanted[j]);
    else
      column[j] = static_cast<int>(it - names.begin());
  }
  return column;
}

}  // namespace inhand::ros
