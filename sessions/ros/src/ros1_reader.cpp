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
#include <set>

#include "cdr.hpp"
#include "inhand/core/error.hpp"
#include "mapped_file.hpp"
#include "recordings.hpp"

namespace inhand::ros {

namespace {

// The MD5 of the standard definition of each decoded type (Debian's message headers): a bag whose
// connection declares the same type name with another definition is refused, not misread.
const char* StandardMd5(MsgType type) {
  switch (type) {
    case MsgType::kJointState:
      return ::ros::message_traits::MD5Sum<sensor_msgs::JointState>::value();
    case MsgType::kImage:
      return ::ros::message_traits::MD5Sum<sensor_msgs::Image>::value();
    case MsgType::kCompressedImage:
      return ::ros::message_traits::MD5Sum<sensor_msgs::CompressedImage>::value();
    case MsgType::kCameraInfo:
      return ::ros::message_traits::MD5Sum<sensor_msgs::CameraInfo>::value();
    case MsgType::kTf:
      return ::ros::message_traits::MD5Sum<tf2_msgs::TFMessage>::value();
    case MsgType::kPoseStamped:
      return ::ros::message_traits::MD5Sum<geometry_msgs::PoseStamped>::value();
    case MsgType::kTransformStamped:
      return ::ros::message_traits::MD5Sum<geometry_msgs::TransformStamped>::value();
    case MsgType::kOdometry:
      return ::ros::message_traits::MD5Sum<nav_msgs::Odometry>::value();
    case MsgType::kOther:
      break;
  }
  return "*";
}

// rosbag reads the container (chunks, compression, index); the message body is decoded by our
// bounds-checked reader (cdr.hpp), the same for ROS 1 and ROS 2.
Payload Decode(const rosbag::MessageInstance& mi, MsgType type, bool decode_images,
               const std::string& context, std::vector<std::uint8_t>* buffer) {
  if (type == MsgType::kOther) return std::monostate();
  const char* md5 = StandardMd5(type);
  if (mi.getMD5Sum() != md5 && mi.getMD5Sum() != "*")
    throw InputError(context + ": " + mi.getDataType() + " with another definition (md5 " +
                     mi.getMD5Sum() + ", the standard one is " + md5 + ")");
  buffer->resize(mi.size());
  ::ros::serialization::OStream out(buffer->data(), static_cast<std::uint32_t>(buffer->size()));
  mi.write(out);
  return DecodeRos1(type, buffer->data(), buffer->size(), decode_images, context);
}

// The bag's structure checked before rosbag sees it: rosbag trusts every length and offset in
// the file. Under AddressSanitizer its header parser (cpp_common's ros::Header::parse) read past
// its buffer on a corrupt field length, and a corrupt message offset in an index record made it
// read outside the chunk (a segfault in readHeaderFromBuffer). Records are
// <header_len><header><data_len><data>, a header a sequence of <field_len><name=value>;
// uncompressed chunks hold records of the same form. Checked: every length fits, every field has
// its '=', index entries point at message records of the chunk before them, chunk infos at
// chunks, the bag header's index_pos at a record. (Inside compressed chunks rosbag is on its own.)
std::uint32_t Le32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}
std::uint64_t Le64(const std::string& v) {
  std::uint64_t x = 0;
  for (std::size_t i = 0; i < 8 && i < v.size(); ++i)
    x |= std::uint64_t{static_cast<std::uint8_t>(v[i])} << (8 * i);
  return v.size() == 8 ? x : ~std::uint64_t{0};
}

struct BagLayout {
  std::set<std::uint64_t> records, chunks;  // file offsets of top-level records and chunk records
  std::set<std::uint32_t> chunk_messages;   // offsets of message records in the last chunk
  bool chunk_known = false;                 // the last chunk was uncompressed (and so checked)
  std::uint64_t index_pos = 0;
  std::vector<std::pair<std::size_t, std::uint64_t>> chunk_infos;  // (at, chunk_pos)
};

void CheckRecords(const std::string& path, const std::uint8_t* d, std::size_t n, std::size_t base,
                  BagLayout* top, std::set<std::uint32_t>* messages) {
  std::size_t pos = 0;
  const auto fail = [&](std::size_t at, const std::string& what) {
    throw InputError(path + ": corrupt ROS 1 bag at byte " + std::to_string(base + at) + " (" +
                     what + ")");
  };
  while (pos < n) {
    if (n - pos < 4) fail(pos, "a record is cut off");
    const std::uint32_t header_len = Le32(d + pos);
    if (header_len > n - pos - 4)
      fail(pos, "a record header of " + std::to_string(header_len) + " bytes runs past the end");
    const std::uint8_t* h = d + pos + 4;
    std::map<std::string, std::string> fields;
    for (std::size_t f = 0; f < header_len;) {
      if (header_len - f < 4) fail(pos + 4 + f, "a header field length is cut off");
      const std::uint32_t field_len = Le32(h + f);
      if (field_len > header_len - f - 4)
        fail(pos + 4 + f,
             "a header field of " + std::to_string(field_len) + " bytes runs past its header");
      const auto* field = reinterpret_cast<const char*>(h + f + 4);
      const char* eq = static_cast<const char*>(std::memchr(field, '=', field_len));
      if (eq == nullptr) fail(pos + 4 + f, "a header field without '='");
      fields[std::string(field, eq)] = std::string(eq + 1, field + field_len);
      f += 4 + field_len;
    }
    const std::size_t data_at = pos + 4 + header_len;
    if (n - data_at < 4) fail(data_at, "a record's data length is cut off");
    const std::uint32_t data_len = Le32(d + data_at);
    if (data_len > n - data_at - 4)
      fail(data_at, "record data of " + std::to_string(data_len) + " bytes runs past the end");
    const std::string op = fields.count("op") ? fields["op"] : std::string();
    const std::uint8_t* data = d + data_at + 4;
    if (messages != nullptr) {
      if (op == std::string(1, '\x02')) messages->insert(static_cast<std::uint32_t>(pos));
    } else {
      top->records.insert(base + pos);
      if (op == std::string(1, '\x03')) {
        top->index_pos = Le64(fields["index_pos"]);
      } else if (op == std::string(1, '\x05')) {
        top->chunks.insert(base + pos);
        top->chunk_messages.clear();
        top->chunk_known = fields["compression"] == "none";
        if (top->chunk_known)
          CheckRecords(path, data, data_len, base + data_at + 4, nullptr, &top->chunk_messages);
      } else if (op == std::string(1, '\x04') && top->chunk_known) {
        const std::string& count_field = fields["count"];
        const std::uint32_t count =
            count_field.size() == 4
                ? Le32(reinterpret_cast<const std::uint8_t*>(count_field.data()))
                : ~0u;
        if (count_field.size() != 4 || std::uint64_t{count} * 12 != data_len)
          fail(pos, "an index record whose count does not match its data");
        for (std::uint32_t i = 0; i < count; ++i)
          if (!top->chunk_messages.count(Le32(data + 12 * i + 8)))
            fail(data_at + 4 + 12 * i, "an index entry that points at no message of its chunk");
      } else if (op == std::string(1, '\x06')) {
        top->chunk_infos.emplace_back(pos, Le64(fields["chunk_pos"]));
      }
    }
    pos = data_at + 4 + data_len;
  }
}

void CheckBag(const std::string& path) {
  const MappedFile file(path);
  constexpr std::size_t kMagic = 13;  // "#ROSBAG V2.0\n"
  if (file.size() < kMagic)
    throw InputError(path + ": not a ROS 1 bag (shorter than its magic line)");
  BagLayout layout;
  CheckRecords(path, file.data() + kMagic, file.size() - kMagic, kMagic, &layout, nullptr);
  if (layout.index_pos != 0 && !layout.records.count(layout.index_pos))
    throw InputError(path + ": corrupt ROS 1 bag (its index position " +
                     std::to_string(layout.index_pos) + " is no record)");
  for (const auto& [at, chunk_pos] : layout.chunk_infos)
    if (!layout.chunks.count(chunk_pos))
      throw InputError(path + ": corrupt ROS 1 bag at byte " + std::to_string(kMagic + at) +
                       " (a chunk info that points at no chunk)");
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
      for (const rosbag::ConnectionInfo* c : view.getConnections())
        by_name[c->topic] = TopicInfo{c->topic, c->datatype, 0, 0, 0};
      for (auto& [name, t] : by_name) {
        rosbag::View v(bag_, rosbag::TopicQuery(name));
        t.count = v.size();
        if (t.count > 0)
          t.first_ns = static_cast<std::int64_t>(v.getBeginTime().toNSec()),
          t.last_ns = static_cast<std::int64_t>(v.getEndTime().toNSec());
      }
    } catch (const std::exception& e) {
      throw InputError(path_ + ": cannot read the bag's index (" + e.what() + ")");
    }
    std::vector<TopicInfo> out;
    for (auto& [name, t] : by_name) out.push_back(t);
    return out;
  }

  void Read(const std::vector<std::string>& topics, bool decode_images,
            const std::function<void(Message&)>& on_message,
            const std::function<void(double)>& progress) override {
    try {
      rosbag::View view(bag_, rosbag::TopicQuery(topics));
      const std::uint32_t total = view.size();
      std::uint32_t done = 0;
      std::map<std::string, std::pair<std::string, std::uint64_t>>
          seen;                          // topic → normalised type, messages so far
      std::vector<std::uint8_t> buffer;  // one message's serialised bytes, reused
      for (const rosbag::MessageInstance& mi : view) {
        auto& [type, index] = seen[mi.getTopic()];
        if (type.empty()) type = NormaliseTypeName(mi.getDataType());
        auto topic_it = seen.find(mi.getTopic());
        Message m;
        m.topic = &topic_it->first;
        m.type = &type;
        m.log_ns = static_cast<std::int64_t>(mi.getTime().toNSec());
        m.payload = Decode(
            mi, MsgTypeOf(type), decode_images,
            path_ + ": topic " + mi.getTopic() + ", message " + std::to_string(index++), &buffer);
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

std::unique_ptr<Recording> OpenRos1Bag(const std::string& path) {
  return std::make_unique<Ros1Recording>(path);
}

}  // namespace inhand::ros
