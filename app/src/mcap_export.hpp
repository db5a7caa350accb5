#pragma once
// replay --mcap: the replay as an MCAP file for Foxglove and Lichtblick. Every channel is a ros2msg
// schema with CDR messages, which both viewers decode natively: each set's pose
// (foxglove_msgs/msg/PoseInFrame on /inhand/pose/SET), the transforms palm -> object_SET,
// object_truth and camera (FrameTransform on /tf), the camera images (CompressedImage: the
// session's PNG or JPEG bytes as they are), the Fig.-1 overlays (ImageAnnotations), the contacts
// and forces (SceneUpdate), the events as log lines (Log on /inhand/log); and two types of ours,
// defined in the file's schemas: each set's errors, sigmas and health at joint rate
// (inhand_msgs/msg/State on /inhand/errors) and the events as events.csv has them
// (inhand_msgs/msg/Event on /inhand/events). The file is chunked, zstd-compressed and indexed
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
  std::uint16_t tf_ = 0, errors_ = 0, image_ = 0, annotations_ = 0, scene_ = 0, events_ = 0,
                log_ = 0;
};

}  // namespace inhand::app
