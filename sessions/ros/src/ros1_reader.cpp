// ROS 1 bags through Debian's rosbag_storage and the roscpp message types.
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

#include "inhand/core/error.hpp"
#include "recordings.hpp"

namespace inhand::ros {

namespace {

Header Convert(const std_msgs::Header& h) { return {static_cast<std::int64_t>(h.stamp.toNSec()), h.frame_id}; }

Pose Convert(const geometry_msgs::Vector3& t, const geometry_msgs::Quaternion& q, const std::string& context) {
  return {Vec3(t.x, t.y, t.z), MessageQuaternion(q.w, q.x, q.y, q.z, context)};
}
Pose Convert(const geometry_msgs::Point& t, const geometry_msgs::Quaternion& q, const std::string& context) {
  return {Vec3(t.x, t.y, t.z), MessageQuaternion(q.w, q.x, q.y, q.z, context)};
}

StampedTransform Convert(const geometry_msgs::TransformStamped& m, const std::string& context) {
  return {Convert(m.header), m.child_frame_id, Convert(m.transform.translation, m.transform.rotation, context)};
}

template <class T>
boost::shared_ptr<T> Instantiate(const rosbag::MessageInstance& mi, const std::string& context) {
  boost::shared_ptr<T> m = mi.instantiate<T>();
  if (!m) throw InputError(context + ": cannot be read as " + mi.getDataType() + " (its definition differs from sensor_msgs' / geometry_msgs')");
  return m;
}

Payload Decode(const rosbag::MessageInstance& mi, MsgType type, bool decode_images, const std::string& context) {
  switch (type) {
    case MsgType::kJointState: {
      auto m = Instantiate<sensor_msgs::JointState>(mi, context);
      return JointStateMsg{Convert(m->header), m->name, m->position, m->velocity, m->effort};
    }
    case MsgType::kImage: {
      auto m = Instantiate<sensor_msgs::Image>(mi, context);
      ImageMsg out{Convert(m->header), m->height, m->width, m->encoding, m->is_bigendian, m->step, {}};
      if (decode_images) out.data = std::move(m->data);
      return out;
    }
    case MsgType::kCompressedImage: {
      auto m = Instantiate<sensor_msgs::CompressedImage>(mi, context);
      CompressedImageMsg out{Convert(m->header), m->format, {}};
      if (decode_images) out.data = std::move(m->data);
      return out;
    }
    case MsgType::kCameraInfo: {
      auto m = Instantiate<sensor_msgs::CameraInfo>(mi, context);
      CameraInfoMsg out;
      out.header = Convert(m->header);
      out.height = m->height;
      out.width = m->width;
      out.distortion_model = m->distortion_model;
      out.d = m->D;
      std::copy(m->K.begin(), m->K.end(), out.k.begin());
      std::copy(m->R.begin(), m->R.end(), out.r.begin());
      std::copy(m->P.begin(), m->P.end(), out.p.begin());
      return out;
    }
    case MsgType::kTf: {
      auto m = Instantiate<tf2_msgs::TFMessage>(mi, context);
      TfMsg out;
      for (const auto& t : m->transforms) out.transforms.push_back(Convert(t, context));
      return out;
    }
    case MsgType::kTransformStamped:
      return Convert(*Instantiate<geometry_msgs::TransformStamped>(mi, context), context);
    case MsgType::kPoseStamped: {
      auto m = Instantiate<geometry_msgs::PoseStamped>(mi, context);
      return StampedTransform{Convert(m->header), "", Convert(m->pose.position, m->pose.orientation, context)};
    }
    case MsgType::kOdometry: {
      auto m = Instantiate<nav_msgs::Odometry>(mi, context);
      return StampedTransform{Convert(m->header), m->child_frame_id, Convert(m->pose.pose.position, m->pose.pose.orientation, context)};
    }
    case MsgType::kOther:
      break;
  }
  return std::monostate();
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
      for (const rosbag::MessageInstance& mi : view) {
        auto& [type, index] = seen[mi.getTopic()];
        if (type.empty()) type = NormaliseTypeName(mi.getDataType());
        auto topic_it = seen.find(mi.getTopic());
        Message m;
        m.topic = &topic_it->first;
        m.type = &type;
        m.log_ns = static_cast<std::int64_t>(mi.getTime().toNSec());
        m.payload = Decode(mi, MsgTypeOf(type), decode_images, path_ + ": topic " + mi.getTopic() + ", message " + std::to_string(index++));
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
