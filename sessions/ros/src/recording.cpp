#include "inhand/ros/recording.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "inhand/core/error.hpp"
#include "recordings.hpp"

namespace fs = std::filesystem;

namespace inhand::ros {

std::unique_ptr<Recording> OpenRecording(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {  // a ROS 2 bag folder: metadata.yaml + one storage file
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(path, ec))
      if (e.path().extension() == ".mcap" || e.path().extension() == ".db3")
        files.push_back(e.path().string());
    if (files.size() != 1)
      throw InputError(path + ": a folder must hold exactly one .mcap or .db3 file (found " +
                       std::to_string(files.size()) + "); name the file instead");
    return OpenRecording(files[0]);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path + ": cannot open (" +
                     (fs::exists(path, ec) ? "not readable" : "no such file") + ")");
  char head[16] = {};
  in.read(head, sizeof head);
  const std::size_t got = static_cast<std::size_t>(in.gcount());
  if (got >= 13 && std::memcmp(head, "#ROSBAG V2.0\n", 13) == 0) return OpenRos1Bag(path);
  if (got >= 8 && std::memcmp(head, "\x89MCAP0\r\n", 8) == 0) return OpenMcap(path);
  if (got >= 16 && std::memcmp(head, "SQLite format 3\0", 16) == 0) return OpenDb3(path);
  throw InputError(path +
                   ": not a ROS recording (expected a ROS 1 bag, an MCAP file or a rosbag2 .db3)");
}

}  // namespace inhand::ros
