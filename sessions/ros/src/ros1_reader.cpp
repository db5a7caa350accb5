// ROS 1 bags through Debian's rosbag_storage (the container); message bodies by cdr.hpp's
// bounds-checked reader, checked against the standard definitions' MD5 from Debian's headers.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>

#include <map>

#include "cdr.hpp"
#include "inhand/core/error.hpp"
#include "recordings.hpp"

namespace inhand::ros {

namespace {

// The MD5 of the standard definition of each decoded type (Debian's message headers): a bag whose
// connection declares the same type name with another definition is refused, not misread.
const char* StandardMd5(MsgType type) {
  switch (type) {
    case MsgType::kJointState: return ::ros::message_traits::MD5Sum<sensor_msgs::JointState>::value();
    case MsgType::kImage: return ::ros::message_traits::MD5Sum<sensor_msgs::Image>::value();
    case MsgType::kCompressedImage: return ::ros::message_traits::MD5Sum<sensor_msgs::CompressedImage>::value();
    case MsgType::kCameraInfo: return ::ros::message_traits::MD5Sum<sensor_msgs::CameraInfo>::value();
    case MsgType::kTf: return ::ros::message_traits::MD5Sum<tf2_msgs::TFMessage>::value();
    case MsgType::kPoseStamped: return ::ros::message_traits::MD5Sum<geometry_msgs::PoseStamped>::value();
    case MsgType::kTransformStamped: return ::ros::message_traits::MD5Sum<geometry_msgs::TransformStamped>::value();
    case MsgType::kOdometry: return ::ros::message_traits::MD5Sum<nav_msgs::Odometry>::value();
    case MsgType::kOther: break;
  }
  return "*";
}

// rosbag reads the container (chunks, compression, index); the message body is decoded by our
// bounds-checked reader (cdr.hpp), the same for ROS 1 and ROS 2.
Payload Decode(const rosbag::MessageInstance& mi, MsgType type, bool decode_images, const std::string& context, std::vector<std::uint8_t>* buffer) {
  if (type == MsgType::kOther) return std::monostate();
  const char* md5 = StandardMd5(type);
  if (mi.getMD5Sum() != md5 && mi.getMD5Sum() != "*")
    throw InputError(context + ": " + mi.getDataType() + " with another definition (md5 " + mi.getMD5Sum() + ", the standard one is " + md5 + ")");
  buffer->resize(mi.size());
  ::ros::serialization::OStream out(buffer->data(), static_cast<std::uint32_t>(buffer->size()));
  mi.write(out);
  return DecodeRos1(type, buffer->data(), buffer->size(), decode_images, context);
}

class Ros1Recording final : public Recording {
 public:
  explicit Ros1Recording(const std::string& path) {
    path_ = path;
    try {
      bag_.open(path, rosbag::bagmode::Read);
    } catch (const std::exception& e) {
      throw InputError(path + ": not a readable ROS 1 bag (" + e.what() + ")");
    }
  }
  std::string format() const override { return "ROS 1 bag"; }

  std::vector<TopicInfo> Topics() override {
    std::map<std::string, TopicInfo> by_name;
    try {
      rosbag::View view(bag_);
      for (const rosbag::ConnectionInfo* c : view.getConnections()) by_name[c->topic] = TopicInfo{c->topic, c->datatype, 0, 0, 0};
      for (auto& [name, t] : by_name) {
        rosbag::View v(bag_, rosbag::TopicQuery(name));
        t.count = v.size();
        if (t.count > 0) t.first_ns = static_cast<std::int64_t>(v.getBeginTime().toNSec()), t.last_ns = static_cast<std::int64_t>(v.getEndTime().toNSec());
      }
    } catch (const std::exception& e) {
      throw InputError(path_ + ": cannot read the bag's index (" + e.what() + ")");
    }
    std::vector<TopicInfo> out;
    for (auto& [name, t] : by_name) out.push_back(t);
    return out;
  }

  void Read(const std::vector<std::string>& topics, bool decode_images, const std::function<void(Message&)>& on_message,
            const std::function<void(double)>& progress) override {
    try {
      rosbag::View view(bag_, rosbag::TopicQuery(topics));
      const std::uint32_t total = view.size();
      std::uint32_t done = 0;
      std::map<std::string, std::pair<std::string, std::uint64_t>> seen;  // topic → normalised type, messages so far
      std::vector<std::uint8_t> buffer;  // one message's serialised bytes, reused
      for (const rosbag::MessageInstance& mi : view) {
        auto& [type, index] = seen[mi.getTopic()];
        if (type.empty()) type = NormaliseTypeName(mi.getDataType());
        auto topic_it = seen.find(mi.getTopic());
        Message m;
        m.topic = &topic_it->first;
        m.type = &type;
        m.log_ns = static_cast<std::int64_t>(mi.getTime().toNSec());
        m.payload = Decode(mi, MsgTypeOf(type), decode_images, path_ + ": topic " + mi.getTopic() + ", message " + std::to_string(index++), &buffer);
        on_message(m);
        if (progress && (++done & 1023) == 0) progress(static_cast<double>(done) / total);
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(path_ + ": cannot read the bag (" + e.what() + "; truncated or corrupt?)");
    }
    if (progress) progress(1.0);
  }

 private:
  rosbag::Bag bag_;
};

}  // namespace

std::unique_ptr<Recording> OpenRos1Bag(const std::string& path) { return std::make_unique<Ros1Recording>(path); }

}  // namespace inhand::ros
