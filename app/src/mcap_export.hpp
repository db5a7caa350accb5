#pragma once
// replay --mcap: the replay as an MCAP file for Foxglove and Lichtblick. Each set's pose
// (foxglove_msgs/msg/PoseInFrame on /inhand/pose/SET), the transforms palm -> object_SET,
// object_truth and camera (foxglove_msgs/msg/FrameTransform on /tf) and the camera images
// (foxglove_msgs/msg/CompressedImage: the session's PNG or JPEG bytes as they are) are ros2msg
// schemas with CDR messages, which both viewers decode natively; each set's errors and sigmas
// (/inhand/errors, at joint rate), the Fig.-1 overlays (foxglove.ImageAnnotations), the contacts
// and forces (foxglove.SceneUpdate) and the events (foxglove.Log on /inhand/events, name
// "inhand/SET", the event's own fields beside the log's, logged at the sample that reported them)
// are still JSON with JSON schemas. The file is chunked, zstd-compressed and indexed
// (ros/mcap_writer.hpp).
#include <memory>
#include <string>

#include "inhand/app/player.hpp"

namespace inhand::ros {
class McapWriter;
}

namespace inhand::app {

class McapExport {
 public:
  McapExport(const std::string& path, const SessionPlayer& player);
  ~McapExport();
  // Sample k with every set's record (records[i] for set i); `frame` >= 0: the camera frame it
  // captured, whose overlays are drawn from the player's current state (it must stand at k).
  void AddSample(int k, const EstimateRecord* records, int frame);
  // Set i's events, logged at t [s].
  void AddEvents(std::size_t i, const std::vector<TrackerEvent>& events, double t);
  void Close();

 private:
  void AddFrame(int frame, double t);
  const SessionPlayer& p_;
  std::unique_ptr<ros::McapWriter> w_;
  std::vector<std::uint16_t> pose_channels_;
  std::uint16_t tf_ = 0, errors_ = 0, image_ = 0, annotations_ = 0, scene_ = 0, events_ = 0;
};

}  // namespace inhand::app
