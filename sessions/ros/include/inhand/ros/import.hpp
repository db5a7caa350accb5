#pragma once
// `inhand import`: a ROS recording (ROS 1 bag, ROS 2 MCAP or .db3) → an inhand session.
// Joints by name against the URDF, images + intrinsics + the camera's pose from TF, optional
// ground truth from a motion-capture topic; staged and renamed into place like every output.
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "inhand/core/so3.hpp"

namespace inhand::ros {

struct ImportOptions {
  std::string recording;  // file (or ROS 2 bag folder)
  std::string out;        // the session folder to write
  bool overwrite = false;
  std::string hand_urdf;
  std::map<std::string, std::string> packages;  // NAME → DIR
  std::string object;                           // object JSON or single-link URDF
  std::string joints_topic;                     // "": the recording's only JointState topic
  bool effort_is_external = false;              // effort → tau columns; otherwise no torques
  std::string image_topic;                      // "": the only Image/CompressedImage topic, if any
  bool no_images = false;                       // import joints (and truth) only
  std::string camera_info_topic;                // "": beside the image topic, or the only one
  std::string palm_frame;                       // "": the URDF's root link
  std::string camera_frame;                     // "": the images' frame_id
  std::string object_pose_topic;                // "": no ground truth
  std::optional<Transform> initial_pose;        // palm frame; else the first ground truth
  std::optional<std::array<double, 3>>
      initial_sigma;  // position [m], orientation [rad], bias [rad]
  std::map<std::string, double>
      joint_stiffness;  // [N m/rad] by joint, "*": the rest (session.json's hand.joint_stiffness)
  std::optional<double> start_s, end_s;  // window, seconds after the first joint sample
  std::optional<double>
      time_origin_s;          // stamp [s] that becomes t = 0 (default: the first joint sample's)
  double max_tf_gap_s = 0.1;  // extrapolation of a TF edge beyond its samples
};

struct ImportReport {
  std::string format;
  std::uint64_t joint_messages = 0, samples = 0, out_of_order = 0, duplicates = 0, non_finite = 0,
                outside_window = 0;
  std::uint64_t image_messages = 0, frames = 0, frames_without_tf = 0, frame_duplicates = 0;
  std::uint64_t truth_messages = 0, truth_samples = 0, truth_without_tf = 0;
  std::int64_t origin_ns = 0;      // the stamp at t = 0
  double t_first = 0, t_last = 0;  // [s] joint samples' span
  bool torques = false;
  std::string joints_topic, image_topic, camera_info_topic, object_pose_topic, palm_frame,
      camera_frame;
  // The lines printed at the end.
  std::vector<std::string> Summary() const;
};

// Throws InputError (naming the file, topic, message or frame) on every bad input; nothing is
// left at `out` then. `progress` gets the fraction done. Raises glibc's mmap and trim thresholds
// for the process (frame buffers are reused instead of mapped afresh).
ImportReport ImportRecording(const ImportOptions& options,
                             const std::function<void(double)>& progress = {});

// `--list`: every topic with type, count, rate and span, and the TF frames with their parents.
std::string ListRecording(const std::string& recording);

}  // namespace inhand::ros
