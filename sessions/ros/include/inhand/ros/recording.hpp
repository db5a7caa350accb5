#pragma once
// A ROS recording opened for import: a ROS 1 bag (Debian's rosbag_storage), a ROS 2 MCAP file or
// a ROS 2 sqlite3 .db3 (our own readers; CDR messages). One interface: the topics with their
// types, counts and time spans, and the messages of chosen topics, decoded.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "inhand/ros/messages.hpp"

namespace inhand::ros {

struct TopicInfo {
  std::string name;
  std::string type;  // normalised (pkg/Type)
  std::uint64_t count = 0;
  std::int64_t first_ns = 0, last_ns = 0;  // log times
  double Rate() const {
    return count > 1 && last_ns > first_ns
               ? (count - 1) * 1e9 / static_cast<double>(last_ns - first_ns)
               : 0.0;
  }
};

struct Message {
  const std::string* topic = nullptr;
  const std::string* type = nullptr;  // normalised
  std::int64_t log_ns = 0;
  Payload payload;  // decoded for the types of MsgType; monostate otherwise
};

class Recording {
 public:
  virtual ~Recording() = default;
  // "ROS 1 bag", "MCAP", "sqlite3 .db3".
  virtual std::string format() const = 0;
  const std::string& path() const { return path_; }
  // Every topic, sorted by name.
  virtual std::vector<TopicInfo> Topics() = 0;
  // Calls `on_message` for each message on `topics`: ROS 1 bags and .db3 in log-time order,
  // MCAP in file order (recorders write it in log-time order; the importer sorts by stamp
  // anyway). The callback may move the payload out. `decode_images` false leaves the pixel data
  // of Image and CompressedImage empty (stamps, sizes and encodings are decoded). `progress`
  // gets the fraction read.
  virtual void Read(const std::vector<std::string>& topics, bool decode_images,
                    const std::function<void(Message&)>& on_message,
                    const std::function<void(double)>& progress = {}) = 0;

 protected:
  std::string path_;
};

// Opens `path` by its contents (a ROS 1 bag, an MCAP file, a sqlite3 database) or, for a
// directory, the one .mcap or .db3 inside it (a ROS 2 bag folder). Throws InputError naming the
// file when it is none of them, is truncated or corrupt.
std::unique_ptr<Recording> OpenRecording(const std::string& path);

}  // namespace inhand::ros
