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

#include <cstring>
#include <map>

#include "cdr.hpp"
#include "mapped_file.hpp"
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

// The bag's record structure checked before rosbag sees it: rosbag's header parser (cpp_common's
// ros::Header::parse) reads past its buffer when a field length is corrupt (AddressSanitizer on
// a fuzzed bag). Records are <header_len><header><data_len><data>, a header a sequence of
// <field_len><name=value>; uncompressed chunks hold records of the same form. Lengths must fit,
// every field must have its '='. (Compressed chunks are left to rosbag.)
std::uint32_t Le32(const std::uint8_t* p) { return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24; }

void CheckRecords(const std::string& path, const std::uint8_t* d, std::size_t n, std::size_t base, bool top_level) {
  std::size_t pos = 0;
  const auto fail = [&](std::size_t at, const std::string& what) {
    throw InputError(path + ": corrupt ROS 1 bag at byte " + std::to_string(base + at) + " (" + what + ")");
  };
  while (pos < n) {
    if (n - pos < 4) fail(pos, "a record is cut off");
    const std::uint32_t header_len = Le32(d + pos);
    if (header_len > n - pos - 4) fail(pos, "a record header of " + std::to_string(header_len) + " bytes runs past the end");
    const std::uint8_t* h = d + pos + 4;
    std::string op, compression;
    for (std::size_t f = 0; f < header_len;) {
      if (header_len - f < 4) fail(pos + 4 + f, "a header field length is cut off");
      const std::uint32_t field_len = Le32(h + f);
      if (field_len > header_len - f - 4) fail(pos + 4 + f, "a header field of " + std::to_string(field_len) + " bytes runs past its header");
      const auto* field = reinterpret_cast<const char*>(h + f + 4);
      const char* eq = static_cast<const char*>(std::memchr(field, '=', field_len));
      if (eq == nullptr) fail(pos + 4 + f, "a header field without '='");
      const std::string name(field, eq), value(eq + 1, field + field_len);
      if (name == "op") op = value;
      if (name == "compression") compression = value;
      f += 4 + field_len;
    }
    const std::size_t data_at = pos + 4 + header_len;
    if (n - data_at < 4) fail(data_at, "a record's data length is cut off");
    const std::uint32_t data_len = Le32(d + data_at);
    if (data_len > n - data_at - 4) fail(data_at, "record data of " + std::to_string(data_len) + " bytes runs past the end");
    if (top_level && op == std::string(1, '\x05') && compression == "none") CheckRecords(path, d + data_at + 4, data_len, base + data_at + 4, false);
    pos = data_at + 4 + data_len;
  }
}

void CheckBag(const std::string& path) {
  const MappedFile file(path);
  constexpr std::size_t kMagic = 13;  // "#ROSBAG V2.0\n"
  if (file.size() < kMagic) throw InputError(path + ": not a ROS 1 bag (shorter than its magic line)");
  CheckRecords(path, file.data() + kMagic, file.size() - kMagic, kMagic, true);
}

class Ros1Recording final : public Recording {
 public:
  explicit Ros1Recording(const std::string& path) {
    path_ = path;
    CheckBag(path);
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
