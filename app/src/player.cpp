#include "inhand/app/player.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <sstream>
#include <thread>

#include "inhand/core/error.hpp"
#include "inhand/core/time.hpp"

namespace inhand::app {

SessionPlayer::SessionPlayer(const Session& session, const TrackerParams& params,
                             std::vector<ModalitySet> sets)
    : session_(session),
      models_(LoadSessionModels(session, true)),
      params_(params),
      sets_(std::move(sets)) {
  params_.Validate();
  if (sets_.empty())
    sets_ = ParseModalities(DefaultModalities(
        session_.has_torques(), session_.info().camera.has_value(), !models_.object.tags.empty()));
  for (const ModalitySet& s : sets_) {
    if (s.torque && !session_.has_torques())
      throw InputError(session_.Resolve("joints.csv") + ": modality " + s.name +
                       " needs joint torques, the session has no tau: columns (try " +
                       DefaultModalities(false, session_.info().camera.has_value(),
                                         !models_.object.tags.empty()) +
                       ")");
    if ((s.tags || s.features) && !session_.info().camera)
      throw InputError(session_.dir() + ": modality " + s.name +
                       " needs camera images, the session has none");
    TrackerOptions options;
    options.history_samples = 8;  // frames arrive in capture order: nothing to go back for
    trackers_.push_back(
        std::make_unique<Tracker>(models_.hand, models_.object, s.modalities(), params_, options));
  }
  const SessionInfo& info = session_.info();
  if (session_.num_samples() > 0)
    for (auto& tracker : trackers_)
      tracker->Start(
          session_.t(0), info.initial_T_PO,
          StartSigmas{info.sigma_position, info.sigma_orientation, info.sigma_joint_bias, {}});
  state_.last.resize(sets_.size());
  q_.setZero(models_.hand.num_q());
  tau_.setZero(models_.hand.num_q());
  set_q_.assign(sets_.size(), q_);
  set_tau_.assign(sets_.size(), tau_);

  // The report of what will not be used.
  const int n = session_.num_samples();
  for (int k = 0; k < n; ++k) {
    Gather(k, q_, tau_);
    const RejectedJoint r = ScreenJointSample(models_.hand, params_.joint_limit_margin, q_, tau_);
    if (r.joint >= 0)
      report_.rejected_samples.push_back(
          {k, r.joint, r.torque, r.torque ? tau_[r.joint] : q_[r.joint]});
  }
  if (n > 0 && report_.rejected_samples.size() == static_cast<std::size_t>(n))
    throw InputError(
        session_.Resolve("joints.csv") + ": none of its " + std::to_string(n) +
        " joint samples can be fused; the first: " +
        report_.Describe(session_, models_, params_, report_.rejected_samples.front()));
  for (const CameraFrame& f : session_.camera_frames())
    report_.frames_before_first_sample += n > 0 && f.t < session_.t(0) - kTimeTolerance;
  if (session_.has_groundtruth() && n > 0) {
    report_.truth_from = session_.groundtruth().front().t;
    report_.truth_to = session_.groundtruth().back().t;
    for (int k = 0; k < n; ++k) report_.samples_without_truth += !TruthCovers(session_.t(k));
  }
}

void SessionPlayer::Gather(int k, Eigen::VectorXd& q_out, Eigen::VectorXd& tau_out) const {
  const auto q = session_.q(k);
  for (std::size_t j = 0; j < models_.joint_columns.size(); ++j)
    q_out[static_cast<long>(j)] = q[models_.joint_columns[j]];
  if (!session_.has_torques()) return;  // tau stays zero: no set with t runs on such a session
  const auto tau = session_.tau(k);
  for (std::size_t j = 0; j < models_.joint_columns.size(); ++j)
    tau_out[static_cast<long>(j)] = tau[models_.joint_columns[j]];
}

bool SessionPlayer::TruthCovers(double t) const {
  return session_.has_groundtruth() && t >= session_.groundtruth().front().t - kTimeTolerance &&
         t <= session_.groundtruth().back().t + kTimeTolerance;
}

std::string SessionPlayer::InputReport::Describe(const Session& session,
                                                 const SessionModels& models,
                                                 const TrackerParams& params, const Rejected& r) {
  const Joint& joint = models.hand.QJoint(r.joint);
  std::ostringstream line;
  line << session.Resolve("joints.csv") << ":" << r.sample + 2 << ": " << (r.torque ? "tau:" : "q:")
       << models.hand.QNames()[static_cast<std::size_t>(r.joint)] << " = " << r.value;
  if (r.torque || !std::isfinite(r.value))
    line << " is not a number";
  else if (joint.has_limits)
    line << " is beyond its limits [" << joint.lower << ", " << joint.upper << "] by more than "
         << params.joint_limit_margin;
  else
    line << " is beyond +-1000";
  return line.str();
}

std::vector<std::string> SessionPlayer::InputReport::Warnings(const Session& session,
                                                              const SessionModels& models,
                                                              const TrackerParams& params) const {
  std::vector<std::string> out = session.LimitWarnings(models.hand, models.joint_columns);
  for (std::string& line : out)
    line += params.joint_clamp_to_limits ? "; clamped to the limit"
                                         : "; kept as measured (joints.clamp_to_limits to clamp)";
  for (std::size_t i = 0; i < rejected_samples.size() && i < 5; ++i)
    out.push_back(Describe(session, models, params, rejected_samples[i]) + "; sample dropped");
  if (rejected_samples.size() > 5)
    out.push_back(session.Resolve("joints.csv") + ": " + std::to_string(rejected_samples.size()) +
                  " joint samples dropped in all");
  if (frames_before_first_sample > 0)
    out.push_back(
        session.Resolve("camera.csv") + ": " + std::to_string(frames_before_first_sample) +
        " frames captured before the first joint sample (t = " + FormatDouble(session.t(0)) +
        " s) are not fused");
  if (samples_without_truth > 0)
    out.push_back(session.Resolve("groundtruth.csv") + ": covers " + FormatDouble(truth_from) +
                  " to " + FormatDouble(truth_to) + " s, not the joint samples' " +
                  FormatDouble(session.t(0)) + " to " +
                  FormatDouble(session.t(session.num_samples() - 1)) + " s: no errors for the " +
                  std::to_string(samples_without_truth) + " samples outside it");
  return out;
}

const VisualStep& SessionPlayer::last_feature_step() const {
  for (std::size_t i = sets_.size(); i-- > 0;)
    if (sets_[i].features) return trackers_[i]->last_visual();
  return no_features_;
}

SessionPlayer::Checkpoint SessionPlayer::Save(bool light) const {
  Checkpoint c;
  for (const auto& t : trackers_) {
    c.trackers.push_back(t->Save());
    if (light) {
      VisualStep& v = c.trackers.back().visual;
      v.virtual_view = RenderOutput();
      v.match.debug = MatchDebug();
    }
  }
  c.state = state_;
  if (light) c.state.image = Image8();
  return c;
}

bool SessionPlayer::CapturesFrame(int k) const {
  const auto& frames = session_.camera_frames();
  return state_.next_frame < frames.size() &&
         frames[state_.next_frame].t <= session_.t(k) + kTimeTolerance;
}

void SessionPlayer::Restore(const Checkpoint& c) {
  INHAND_CHECK(c.trackers.size() == trackers_.size(),
               "checkpoint of a player with other modality sets");
  for (std::size_t i = 0; i < trackers_.size(); ++i) trackers_[i]->Restore(c.trackers[i]);
  state_ = c.state;
}

std::size_t SessionPlayer::LoadFramesOf(int k) {
  const auto& frames = session_.camera_frames();
  const double t = session_.t(k);
  const std::size_t first = state_.next_frame;
  images_.clear();
  state_.last_frame = -1;
  // The images are read only for sets that see them (the pictures read their own).
  bool needed = false;
  for (const ModalitySet& s : sets_) needed = needed || s.tags || s.features;
  while (state_.next_frame < frames.size() && frames[state_.next_frame].t <= t + kTimeTolerance) {
    state_.last_frame = static_cast<int>(state_.next_frame++);
    if (needed) images_.push_back(session_.LoadImage(state_.last_frame));
  }
  if (!images_.empty()) state_.image = images_.back();
  return first;
}

void SessionPlayer::StepSet(std::size_t i, int k, std::size_t first_frame, std::size_t end_frame,
                            EstimateRecord& r) {
  const double t = session_.t(k);
  Eigen::VectorXd& q = set_q_[i];
  Eigen::VectorXd& tau = set_tau_[i];
  Gather(k, q, tau);
  Tracker& tracker = *trackers_[i];
  const auto start = std::chrono::steady_clock::now();
  tracker.AddJointSample(t, q, tau);
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  r.t = t;
  r.step_time_us = us;
  r.events.clear();
  RecordContacts(tracker.trace(), r);
  r.visual_ms = -1.0;
  r.visual_used = 0;
  // Camera frames captured by this sample.
  if (sets_[i].tags || sets_[i].features) {
    const auto& frames = session_.camera_frames();
    for (std::size_t f = first_frame; f < end_frame; ++f) {
      const long before = tracker.last_visual().sequence;
      tracker.AddImage(frames[f].t, images_[f - first_frame], frames[f].T_PC,
                       *session_.info().camera);
      const VisualStep& v = tracker.last_visual();
      if (v.sequence == before) continue;
      r.visual_ms = v.ms;
      r.visual_used = v.used;
      r.visual_mahalanobis = v.mean_mahalanobis;
    }
  }
  RecordTrackerState(tracker, r);
  tracker.TakeEvents(r.events);
  if (TruthCovers(t))
    CompareWithTruth(session_.GroundTruthAt(t), tracker.claimed_pose_covariance(), r);
  else
    r = WithoutTruth(r);
  WatchNees(r);
}

void SessionPlayer::WatchNees(EstimateRecord& r) {
  if (!std::isfinite(r.nees)) {
    r.nees_beyond = false;
    return;
  }
  if (r.nees > kNeesBound99) {
    r.nees_within_since = -1.0;
    if (r.nees_beyond) return;
    r.nees_beyond = true;
    TrackerEvent e;
    e.t = r.t;
    e.kind = EventKind::kNeesBeyondBound;
    e.value = r.nees;
    r.events.push_back(e);
    return;
  }
  if (!r.nees_beyond) return;
  if (r.nees_within_since < 0.0) r.nees_within_since = r.t;
  if (r.t - r.nees_within_since >= kNeesSettle - kTimeTolerance) r.nees_beyond = false;
}

void SessionPlayer::CloseEvents(std::size_t i, std::vector<TrackerEvent>& out) {
  trackers_[i]->CloseEvents();
  trackers_[i]->TakeEvents(out);
}

void SessionPlayer::Step(int k) {
  const std::size_t first = LoadFramesOf(k);
  for (std::size_t i = 0; i < trackers_.size(); ++i)
    StepSet(i, k, first, state_.next_frame, state_.last[i]);
}

int SessionPlayer::StepBlock(int k, int max_samples, int jobs,
                             std::vector<EstimateRecord>& records) {
  INHAND_CHECK(k >= 0 && k < session_.num_samples() && max_samples >= 1 && jobs >= 1,
               "StepBlock: bad arguments");
  // The block: up to the first sample that captures a frame.
  const auto& frames = session_.camera_frames();
  int end = k;
  while (end < session_.num_samples() && end - k < max_samples) {
    const bool captures = state_.next_frame < frames.size() &&
                          frames[state_.next_frame].t <= session_.t(end) + kTimeTolerance;
    ++end;
    if (captures) break;
  }
  const int count = end - k;
  const std::size_t sets = trackers_.size();
  records.resize(static_cast<std::size_t>(count) * sets);
  // Only the block's last sample can capture frames: load them first, for every set.
  const std::size_t first_frame = LoadFramesOf(end - 1), end_frame = state_.next_frame;
  const auto run_set = [&](std::size_t i) {
    for (int s = k; s < end; ++s) {
      EstimateRecord& r = records[static_cast<std::size_t>(s - k) * sets + i];
      r = state_.last[i];  // the fields a step leaves as they were
      const bool last = s == end - 1;
      StepSet(i, s, first_frame, last ? end_frame : first_frame, r);
      state_.last[i] = r;
    }
  };
  const int threads = std::min<int>(jobs, static_cast<int>(sets));
  if (threads <= 1) {
    for (std::size_t i = 0; i < sets; ++i) run_set(i);
    return count;
  }
  // The heaviest sets (the last: with images) are taken first; a set runs wholly on one thread.
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto worker = [&] {
    for (std::size_t n; (n = next++) < sets;) {
      try {
        run_set(sets - 1 - n);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(worker);
  worker();
  for (std::thread& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  return count;
}

}  // namespace inhand::app
