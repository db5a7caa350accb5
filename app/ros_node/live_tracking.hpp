#pragma once
// The live ROS node's estimator side, without ROS: one Tracker per modality set fed from the
// decoded messages of a robot's topics (inhand/ros/messages.hpp): joint states by name, camera
// images at their header stamp with the intrinsics of the newest CameraInfo and the camera's pose
// from TF. The node (main.cpp) subscribes, converts and publishes; this part decides.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/ros/messages.hpp"
#include "inhand/ros/tf_tree.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::ros {

struct LiveOptions {
  std::vector<std::string> sets{"jt"};  // modality sets, one Tracker each
  TrackerParams params;
  bool threaded = true;             // vision off the callback thread (Tracker's threaded mode)
  bool effort_is_external = false;  // JointState.effort → τ; otherwise τ = 0 (sets with t refused)
  std::string palm_frame;           // "": the URDF's root link
  std::string camera_frame;         // "": each image's header frame_id
  std::optional<Transform> start_T_PO;  // the object's pose in the palm frame at the start
  std::string start_frame;  // or: the pose of this TF frame in the palm frame at the first sample
  StartSigmas start_sigmas;
  std::optional<std::int64_t> time_origin_ns;  // stamp of t = 0 (default: the first joint sample)
  double tf_window = 10.0;  // [s] how much TF history is kept (camera on a moving arm)
  double horizon = 0.5;     // [s] TrackerOptions::horizon
};

// A set's estimate after a joint sample.
struct LivePose {
  std::size_t set = 0;  // index into LiveTracking::sets()
  std::int64_t stamp_ns = 0;
  Transform T_PO = Transform::Identity();
  Mat6 covariance = Mat6::Identity();  // of (δp, δθ), δθ about the palm frame's axes
  Health health;
  bool health_changed = false;  // since the previous sample (and at the first)
};

struct LiveEvent {
  std::size_t set = 0;  // index into LiveTracking::sets()
  std::int64_t stamp_ns = 0;
  TrackerEvent event;
  std::string message;  // EventMessage
};

// The newest image the trackers were given, with the camera it was taken from.
struct LiveImage {
  std::int64_t stamp_ns = 0;
  Transform T_PC = Transform::Identity();
  Intrinsics K;
};

class LiveTracking {
 public:
  // The models must outlive this. Throws InputError for a set the options cannot run (torques
  // without --effort-is external) or a frame the hand does not have.
  LiveTracking(const HandModel& hand, const ObjectModel& object, LiveOptions options);
  ~LiveTracking();

  // Each returns what it did not use as an error message (empty: used); a message that cannot
  // be used is never fatal for a node that runs for hours. `context` names the topic.
  // A joint state: the hand's joints by name. Appends each set's pose to `poses` and the events
  // found to `events`.
  std::string OnJointState(const JointStateMsg& m, const std::string& context,
                           std::vector<LivePose>& poses, std::vector<LiveEvent>& events);
  std::string OnCameraInfo(const CameraInfoMsg& m, const std::string& context);
  // An image whose camera TF has not reached its stamp yet waits for it (one image at most):
  // it is fused by the OnTf that brings that TF, or, holding the newest TF as before, by the
  // first joint state more than kTfWait after it or by the next image. Returns "" then.
  std::string OnImage(const Header& header, const Image8& image, const std::string& context);
  // Returns what a waiting image that it released could not use (empty: nothing, or used).
  std::string OnTf(const TfMsg& m, bool is_static);
  static constexpr std::int64_t kTfWait = 100000000;  // [ns] TfTree::Lookup's hold

  bool started() const { return started_; }
  std::int64_t origin_ns() const { return origin_ns_; }
  const std::vector<std::string>& sets() const { return options_.sets; }
  const Tracker& tracker(std::size_t i) const { return *trackers_[i]; }
  std::string palm_frame() const { return palm_; }
  const HandModel& hand() const { return hand_; }
  const std::optional<LiveImage>& last_image() const { return last_image_; }
  // The time [s] since the origin of a stamp.
  double T(std::int64_t stamp_ns) const;
  // One line per set: samples, images fused, dropped and late, relocalizations, health.
  std::vector<std::string> Summary() const;

 private:
  const HandModel& hand_;
  const ObjectModel& object_;
  LiveOptions options_;
  std::string palm_;
  std::vector<std::unique_ptr<Tracker>> trackers_;
  std::vector<Health> last_health_;
  TfTree tf_;
  std::optional<Intrinsics> K_;
  bool started_ = false;
  std::int64_t origin_ns_ = 0, newest_tf_ns_ = 0;
  std::vector<std::string> column_names_;
  std::vector<int> column_;
  Eigen::VectorXd q_, tau_;
  std::vector<TrackerEvent> taken_;
  std::optional<LiveImage> last_image_;
  struct WaitingImage {
    Header header;
    Image8 image;
    std::string context, camera;
  };
  std::optional<WaitingImage> waiting_;

  std::string Fuse(const Header& header, const Image8& image, const std::string& context,
                   const std::string& camera);
  std::string ReleaseWaiting();

  std::string MapColumns(const JointStateMsg& m, const std::string& context);
  std::optional<Transform> StartPose(std::int64_t stamp_ns, std::string& error) const;
};

}  // namespace inhand::ros
