#include "inhand/app/player.hpp"

#include <chrono>

#include "inhand/core/error.hpp"

namespace inhand::app {

SessionPlayer::SessionPlayer(const Session& session, const TrackerParams& params, std::vector<ModalitySet> sets)
    : session_(session), models_(LoadSessionModels(session, true)), params_(params), sets_(std::move(sets)) {
  params_.Validate();
  if (sets_.empty())
    sets_ = ParseModalities(!session_.info().camera ? "j,jt" : models_.object.tags.empty() ? "j,jt,jtf" : "j,jt,jta,jtf");
  for (const ModalitySet& s : sets_) {
    if ((s.tags || s.features) && !session_.info().camera)
      throw InputError(session_.dir() + ": modality " + s.name + " needs camera images, the session has none");
    TrackerOptions options;
    options.history_samples = 8;  // frames arrive in capture order: nothing to go back for
    trackers_.push_back(std::make_unique<Tracker>(models_.hand, models_.object, s.modalities(), params_, options));
  }
  const SessionInfo& info = session_.info();
  if (session_.num_samples() > 0)
    for (auto& tracker : trackers_)
      tracker->Start(session_.t(0), info.initial_T_PO, StartSigmas{info.sigma_position, info.sigma_orientation, info.sigma_joint_bias, {}});
  state_.last.resize(sets_.size());
  q_.setZero(models_.hand.num_q());
  tau_.setZero(models_.hand.num_q());
}

const VisualStep& SessionPlayer::last_feature_step() const {
  for (std::size_t i = sets_.size(); i-- > 0;)
    if (sets_[i].features) return trackers_[i]->last_visual();
  return no_features_;
}

SessionPlayer::Checkpoint SessionPlayer::Save() const {
  Checkpoint c;
  for (const auto& t : trackers_) c.trackers.push_back(t->Save());
  c.state = state_;
  return c;
}

void SessionPlayer::Restore(const Checkpoint& c) {
  INHAND_CHECK(c.trackers.size() == trackers_.size(), "checkpoint of a player with other modality sets");
  for (std::size_t i = 0; i < trackers_.size(); ++i) trackers_[i]->Restore(c.trackers[i]);
  state_ = c.state;
}

void SessionPlayer::Step(int k) {
  const double t = session_.t(k);
  const auto q = session_.q(k), tau = session_.tau(k);
  for (std::size_t j = 0; j < models_.joint_columns.size(); ++j) {
    q_[static_cast<long>(j)] = q[models_.joint_columns[j]];
    tau_[static_cast<long>(j)] = tau[models_.joint_columns[j]];
  }
  for (std::size_t i = 0; i < trackers_.size(); ++i) {
    Tracker& tracker = *trackers_[i];
    const auto start = std::chrono::steady_clock::now();
    tracker.AddJointSample(t, q_, tau_);
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    EstimateRecord& r = state_.last[i];
    r.t = t;
    r.step_time_us = us;
    r.contacts = static_cast<int>(tracker.trace().contacts.size());
    r.constraints = tracker.trace().num_constraints;
    r.visual_ms = -1.0;
    r.visual_used = 0;
  }

  // Camera frames captured by this sample.
  const auto& frames = session_.camera_frames();
  state_.last_frame = -1;
  while (state_.next_frame < frames.size() && frames[state_.next_frame].t <= t + 1e-9) {
    const int f = static_cast<int>(state_.next_frame++);
    const CameraFrame& frame = frames[static_cast<std::size_t>(f)];
    state_.last_frame = f;
    state_.image = session_.LoadImage(f);
    for (std::size_t i = 0; i < trackers_.size(); ++i) {
      if (!sets_[i].tags && !sets_[i].features) continue;
      Tracker& tracker = *trackers_[i];
      const long before = tracker.last_visual().sequence;
      tracker.AddImage(frame.t, state_.image, frame.T_PC, *session_.info().camera);
      const VisualStep& v = tracker.last_visual();
      if (v.sequence == before) continue;
      EstimateRecord& r = state_.last[i];
      r.visual_ms = v.ms;
      r.visual_used = v.used;
      r.visual_mahalanobis = v.mean_mahalanobis;
    }
  }
  for (std::size_t i = 0; i < trackers_.size(); ++i) {
    const Tracker& tracker = *trackers_[i];
    EstimateRecord& r = state_.last[i];
    r.T_PO = tracker.T_PO();
    const auto P = tracker.filter().covariance();
    r.sigma_position = P.diagonal().head<3>().cwiseSqrt();
    r.sigma_orientation = P.diagonal().segment<3>(3).cwiseSqrt();
    r.biases = tracker.biases();
    r.gated = tracker.trace().num_gated;  // contacts and visual features of this sample
    if (session_.has_groundtruth()) CompareWithTruth(session_.GroundTruthAt(t), P.topLeftCorner<6, 6>(), r);
  }
}

}  // namespace inhand::app
