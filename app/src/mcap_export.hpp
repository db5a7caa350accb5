#pragma once
// replay --mcap: the replay as an MCAP file for Foxglove and Lichtblick. JSON messages with their
// JSON schemas (no protobuf): each set's pose (foxglove.PoseInFrame on /inhand/pose/SET and a
// foxglove.FrameTransform palm -> object_SET on /tf) and its errors and sigmas (plain JSON on
// /inhand/errors) at joint rate; at each camera frame the image (foxglove.CompressedImage), its
// Fig.-1 overlays as foxglove.ImageAnnotations, and the contacts and forces as a
// foxglove.SceneUpdate. Each set's events (tracker/events.hpp) as foxglove.Log on /inhand/events
// (name "inhand/SET"; the event's own fields beside the log's), logged at the sample that reported
// them. The file is chunked, zstd-compressed and indexed (ros/mcap_writer.hpp).
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
