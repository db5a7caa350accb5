#include "live_tracking.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/ros/camera_messages.hpp"

namespace inhand::ros {

namespace {

std::string Join(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

LiveTracking::LiveTracking(const HandModel& hand, const ObjectModel& object, LiveOptions options)
    : hand_(hand), object_(object), options_(std::move(options)) {
  palm_ = options_.palm_frame.empty() ? hand_.links[static_cast<std::size_t>(hand_.root_link)].name
                                      : options_.palm_frame;
  if (options_.sets.empty()) throw InputError("--sets: no modality set given");
  if (!options_.start_T_PO && options_.start_frame.empty())
    throw InputError("--start or --start-frame: the object's pose at the start is needed");
  options_.start_sigmas.Validate("--start-sigma");
  TrackerOptions tracker_options;
  tracker_options.threaded = options_.threaded;
  tracker_options.horizon = options_.horizon;
  for (const std::string& set : options_.sets) {
    const Modalities m = Modalities::Parse(set, "--sets");
    if (m.torque && !options_.effort_is_external)
      throw InputError("--sets: set " + set +
                       " needs joint torques; pass --effort-is external when JointState.effort "
                       "holds the external torques");
    trackers_.push_back(
        std::make_unique<Tracker>(hand_, object_, m, options_.params, tracker_options));
  }
  last_health_.resize(trackers_.size());
  q_.setZero(hand_.num_q());
  tau_.setZero(hand_.num_q());
}

LiveTracking::~LiveTracking() = default;

double LiveTracking::T(std::int64_t stamp_ns) const {
  return static_cast<double>(stamp_ns - origin_ns_) / 1e9;
}

std::string LiveTracking::MapColumns(const JointStateMsg& m, const std::string& context) {
  if (m.name == column_names_) return "";
  std::vector<std::string> missing;
  std::vector<int> column = ColumnsByName(hand_.QNames(), m.name, missing);
  if (!missing.empty())
    return context + ": the hand's joint" + (missing.size() > 1 ? "s " : " ") + Join(missing) +
           (missing.size() > 1 ? " are" : " is") + " not in the message, which names " +
           Join(m.name);
  column_names_ = m.name;
  column_ = std::move(column);
  return "";
}

std::optional<Transform> LiveTracking::StartPose(std::int64_t stamp_ns, std::string& error) const {
  if (options_.start_T_PO) return options_.start_T_PO;
  try {
    const std::optional<Pose> p = tf_.Lookup(palm_, options_.start_frame, stamp_ns, true);
    if (p) return p->ToTransform();
    error = "--start-frame " + options_.start_frame + ": no TF sample near the first joint sample";
  } catch (const InputError& e) {
    error = std::string("--start-frame: ") + e.what();
  }
  return std::nullopt;
}

std::string LiveTracking::OnJointState(const JointStateMsg& m, const std::string& context,
                                       std::vector<LivePose>& poses,
                                       std::vector<LiveEvent>& events) {
  if (std::string error = MapColumns(m, context); !error.empty()) return error;
  if (m.position.size() != m.name.size())
    return context + ": " + std::to_string(m.name.size()) + " names but " +
           std::to_string(m.position.size()) + " positions";
  if (options_.effort_is_external && m.effort.size() != m.name.size())
    return context + ": --effort-is external, but the message has " +
           std::to_string(m.effort.size()) + " efforts for " + std::to_string(m.name.size()) +
           " joints";
  for (std::size_t j = 0; j < column_.size(); ++j) {
    const auto c = static_cast<std::size_t>(column_[j]);
    q_[static_cast<long>(j)] = m.position[c];
    if (options_.effort_is_external) tau_[static_cast<long>(j)] = m.effort[c];
  }
  const std::int64_t stamp = m.header.stamp_ns;
  if (!started_) {
    std::string error;
    tf_.Finish();  // the start frame's samples in order
    origin_ns_ = options_.time_origin_ns.value_or(stamp);
    const std::optional<Transform> start = StartPose(stamp, error);
    if (!start) return error;
    for (auto& tracker : trackers_) tracker->Start(T(stamp), *start, options_.start_sigmas);
    started_ = true;
  }
  std::string waited;
  if (waiting_ && stamp - waiting_->header.stamp_ns > kTfWait) waited = ReleaseWaiting();
  const double t = T(stamp);
  for (std::size_t i = 0; i < trackers_.size(); ++i) {
    Tracker& tracker = *trackers_[i];
    const long fused = tracker.stats().samples;
    tracker.AddJointSample(t, q_, tau_);
    taken_.clear();
    tracker.TakeEvents(taken_);
    for (const TrackerEvent& e : taken_)
      events.push_back({i, origin_ns_ + std::llround(e.t * 1e9), e, EventMessage(e, hand_)});
    if (tracker.stats().samples == fused) continue;  // dropped or rejected: no new estimate
    LivePose p;
    p.set = i;
    p.stamp_ns = stamp;
    p.T_PO = tracker.T_PO();
    p.covariance = tracker.claimed_pose_covariance();
    p.health = tracker.health();
    p.health_changed = fused == 0 || !(p.health == last_health_[i]);
    last_health_[i] = p.health;
    poses.push_back(std::move(p));
  }
  return waited;
}

std::string LiveTracking::OnCameraInfo(const CameraInfoMsg& m, const std::string& context) {
  try {
    K_ = IntrinsicsOf(m, context);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string LiveTracking::OnImage(const Header& header, const Image8& image,
                                  const std::string& context) {
  if (!started_) return "";  // before the first joint sample: nothing to fuse it with
  if (!K_) return context + ": no CameraInfo yet; the image is not used";
  const std::string camera =
      options_.camera_frame.empty() ? header.frame_id : options_.camera_frame;
  if (camera.empty())
    return context + ": the image has no frame_id; give the camera's frame (--camera-frame)";
  std::string error = ReleaseWaiting();
  tf_.Finish();
  if (!tf_.Covers(palm_, camera, header.stamp_ns)) {
    waiting_ = WaitingImage{header, image, context, camera};
    return error;
  }
  const std::string e = Fuse(header, image, context, camera);
  return error.empty() ? e : e.empty() ? error : error + "; " + e;
}

std::string LiveTracking::ReleaseWaiting() {
  if (!waiting_) return "";
  const WaitingImage w = std::move(*waiting_);
  waiting_.reset();
  return Fuse(w.header, w.image, w.context, w.camera);
}

std::string LiveTracking::Fuse(const Header& header, const Image8& image,
                               const std::string& context, const std::string& camera) {
  std::optional<Pose> T_PC;
  try {
    tf_.Finish();
    T_PC = tf_.Lookup(palm_, camera, header.stamp_ns, true, kTfWait);
  } catch (const InputError& e) {
    return context + ": the camera's pose: " + e.what();
  }
  if (!T_PC) return context + ": no TF from " + palm_ + " to " + camera + " near the image's stamp";
  const Transform pose = T_PC->ToTransform();
  try {
    for (auto& tracker : trackers_) tracker->AddImage(T(header.stamp_ns), image, pose, *K_);
  } catch (const InputError& e) {
    return context + ": " + e.what();
  }
  last_image_ = LiveImage{header.stamp_ns, pose, *K_};
  return "";
}

std::string LiveTracking::OnTf(const TfMsg& m, bool is_static) {
  for (const StampedTransform& t : m.transforms) {
    tf_.Add(t, is_static);
    if (!is_static && t.header.stamp_ns > newest_tf_ns_ + 1000000000) {
      // Once a second of stamps: TF older than the window goes.
      newest_tf_ns_ = t.header.stamp_ns;
      tf_.Finish();
      tf_.Forget(newest_tf_ns_ - std::llround(options_.tf_window * 1e9));
    }
  }
  if (!waiting_) return "";
  tf_.Finish();
  if (!tf_.Covers(palm_, waiting_->camera, waiting_->header.stamp_ns)) return "";
  return ReleaseWaiting();
}

std::vector<std::string> LiveTracking::Summary() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < trackers_.size(); ++i) {
    const TrackerStats s = trackers_[i]->stats();
    std::ostringstream line;
    line << options_.sets[i] << ": " << s.samples << " joint samples (" << s.samples_dropped
         << " dropped, " << s.samples_rejected << " rejected), " << s.images_fused << " of "
         << s.images_added << " images fused (" << s.images_dropped_late << " too late, "
         << s.images_dropped_busy << " while busy, " << s.rewinds << " behind later samples), "
         << s.relocalizations << " relocalizations; "
         << HealthMessage(trackers_[i]->health(), hand_);
    out.push_back(line.str());
  }
  return out;
}

}  // namespace inhand::ros
