// The tracker's shell: the caller's side (joint samples, images in capture order), the worker
// thread and what both share under one mutex (the history, the statistics, the queue). What is
// fused where: history.hpp keeps a checkpoint after every joint sample; image_fusion.hpp fuses
// an image at its capture time on copies of the slots since, on the caller's filter
// (deterministic) or on the worker's, which catches up with the samples that arrived meanwhile,
// writes the slots back and leaves its filter state for the caller to adopt at its next call.
#include "inhand/tracker/tracker.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <ostream>
#include <thread>
#include <utility>

#include "history.hpp"
#include "image_fusion.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/joint_samples.hpp"
#include "inhand/filter/plausibility.hpp"

namespace inhand {

std::string Modalities::Name() const {
  return std::string("j") + (torque ? "t" : "") + (tags ? "a" : "") + (features ? "f" : "");
}

Modalities Modalities::Parse(const std::string& text, const std::string& context) {
  const std::string expected =
      "expected j followed by any of t (torques), a (AprilTags), f (extracted features): j, jt, "
      "ja, jf, jta, jtf, jaf, jtaf";
  if (text.empty() || text[0] != 'j') throw InputError(context + ": '" + text + "': " + expected);
  Modalities m;
  for (std::size_t i = 1; i < text.size(); ++i) {
    bool* flag = text[i] == 't'   ? &m.torque
                 : text[i] == 'a' ? &m.tags
                 : text[i] == 'f' ? &m.features
                                  : nullptr;
    if (flag == nullptr)
      throw InputError(context + ": '" + text + "': unknown letter '" + text[i] + "'; " + expected);
    if (*flag) throw InputError(context + ": '" + text + "': letter '" + text[i] + "' given twice");
    *flag = true;
  }
  return m;
}

namespace {

struct Job {
  double t_capture = 0.0;
  Image8 image;
  Transform T_PC = Transform::Identity();
  Intrinsics K;
};

}  // namespace

struct Tracker::Impl {
  Impl(const HandModel& h, const ObjectModel& o, const Modalities& m, const TrackerParams& p,
       const TrackerOptions& opt)
      : hand(h),
        object(o),
        modalities(m),
        params(p),
        options(opt),
        query(h, o),
        filter(h, query, p.filter, tracker_detail::FilterOptionsFor(o, m)),
        health(p.health),
        press(h),
        plausibility(h, query),
        centre_O(o.Bounds().Center()),
        detector(h, p.health.slip_hold) {
    params.Validate();
    ValidateJointStiffness(h);
    deflect = m.torque && HasElasticJoints(h);
    if (!(options.horizon >= 0.0) || options.history_samples < 1 || options.max_queued_images < 1)
      throw InputError(
          "tracker options: horizon must be >= 0 s, history_samples and max_queued_images >= 1");
    history.Resize(options.history_samples);
    events.reserve(64);
    // Configuration errors surface here, not on the worker.
    fusion = std::make_unique<tracker_detail::ImageFusion>(h, o, m, params,
                                                           options.threaded ? nullptr : &filter);
    if (options.threaded) worker = std::thread([this] { WorkerLoop(); });
  }

  ~Impl() {
    if (worker.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        stop = true;
      }
      work_cv.notify_all();
      worker.join();
    }
  }

  Eigen::VectorXd q_used;  // the sample as fused (undeflected, clamped to the limits when asked)
  bool deflect = false;    // sets with torques on a hand with joint stiffness

  // --- the caller's side
  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& tau) {
    INHAND_CHECK(start_set, "Tracker::AddJointSample before Start");
    INHAND_CHECK(q.size() == hand.num_q() && tau.size() == hand.num_q(),
                 "joint sample size does not match the hand");
    Adopt();
    if (!std::isfinite(t) || (started && !(t > last_t)) ||
        (!started && !(t >= start_t - kTimeTolerance))) {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.samples_dropped;
      detector.OnSampleDropped(t, events);
      return;
    }
    if (const RejectedJoint r = ScreenJointSample(hand, params.joint_limit_margin, q, tau);
        r.joint >= 0) {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.samples_rejected;
      detector.OnSampleRejected(t, r.joint, r.torque ? tau[r.joint] : q[r.joint], events);
      return;
    }
    // Images captured before this sample belong after the previous one.
    while (!early.empty() && early.front().t_capture + kTimeTolerance < t) {
      Job job = std::move(early.front());
      early.pop_front();
      if (started)
        Submit(std::move(job));
      else
        DropLate(job.t_capture);
    }
    if (q_used.size() != q.size()) q_used.resize(q.size());  // once
    q_used = q;
    if (deflect) Undeflect(hand, tau, q_used);
    if (params.joint_clamp_to_limits) ClampToLimits(hand, q_used);
    const double dt = started ? t - last_t : 0.0;
    if (!started) {
      Begin(t, tau);
      started = true;
      std::lock_guard<std::mutex> lock(mutex);
      history.Preallocate(hand.num_q(), filter.state());
    }
    filter.Step(q_used, tau, dt);
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (adopt_pending) {
        // The worker published while this sample was being fused: its state is at the previous
        // sample (it publishes only when it has every committed one), so fuse this one again on it.
        AdoptLocked();
        filter.Step(q_used, tau, dt);
      }
      TrackedSample& s = history.Push();
      s.t = t;
      s.dt = dt;
      s.q = q_used;
      s.tau = tau;
      s.after_sample = filter.state();
      s.fused.clear();
      ++stats.samples;
      DrainEvidenceLocked();
    }
    last_t = t;
    Judge(t, tau);
    std::lock_guard<std::mutex> lock(mutex);
    detector.OnSample(t, filter.trace(), health.health(), events);
  }

  // The filter's start. A start with a link deep inside the object is first settled onto the
  // hand, on the palm's grasp side (HandPlausibility::SettleStart), its position's σ widened by
  // a third of the move, and says so (EventKind::kStartSettled).
  void Begin(double t, const Eigen::Ref<const Eigen::VectorXd>& tau) {
    filter.Reset(start_T_PO, q_used, start_sigmas);
    const HandPlausibility::StartChoice choice =
        plausibility.SettleStart(modalities.torque ? Eigen::VectorXd(tau) : Eigen::VectorXd(),
                                 filter.kinematics().link_poses(), start_T_PO, centre_O,
                                 start_sigmas.position, params.health, params.health.recover_reach);
    if (choice.hypothesis < 0) return;
    const double jump = (choice.T_PO.translation() - start_T_PO.translation()).norm();
    StartSigmas sigmas = start_sigmas;
    sigmas.position = std::hypot(sigmas.position, jump / 3.0);
    filter.Reset(choice.T_PO, q_used, sigmas);
    TrackerEvent e;
    e.t = t;
    e.kind = EventKind::kStartSettled;
    e.subject = choice.link;
    e.value = jump;
    std::lock_guard<std::mutex> lock(mutex);
    events.push_back(e);
  }

  // The health at the sample just fused: the press check when due (sets with torques), then
  // the state.
  void Judge(double t, const Eigen::Ref<const Eigen::VectorXd>& tau) {
    if (modalities.torque && t >= next_press_t - kTimeTolerance) {
      health.OnPress(t, press.Measure(tau, filter.kinematics().link_poses(), filter.T_PO(),
                                      filter.trace(), query, params.health));
      next_press_t = t + params.health.press_period;
    }
    const auto P = filter.covariance();
    health.OnSample(t, filter.trace(), P.diagonal().head<3>().cwiseSqrt(),
                    P.diagonal().segment<3>(3).cwiseSqrt());
  }

  // Under the lock: what the images fused since the last call said, into the monitor.
  void DrainEvidenceLocked() {
    for (const EventDetector::Image& image : evidence) {
      health.OnImage(image.evidence);
      detector.OnImage(image, events);
    }
    evidence.clear();
  }

  void AddImage(double t_c, const Image8& image, const Transform& T_PC, const Intrinsics& K) {
    INHAND_CHECK(start_set, "Tracker::AddImage before Start");
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.images_added;
    }
    if (!std::isfinite(t_c) || !T_PC.matrix().allFinite() || image.empty()) {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.images_rejected;
      TrackerEvent e;
      e.t = std::isfinite(t_c) ? t_c : last_t;
      e.kind = EventKind::kImageRejected;
      events.push_back(e);
      return;
    }
    health.OnImageAdded(t_c, ImageFingerprint(image.data.data(), image.data.size()));
    if (!started || t_c > last_t + kTimeTolerance) {
      if (t_c + kTimeTolerance < start_t) return DropLate(t_c);
      // Waits for the samples up to its capture time, in capture order.
      Job job{t_c, image, T_PC, K};
      auto it = std::upper_bound(early.begin(), early.end(), t_c,
                                 [](double v, const Job& j) { return v < j.t_capture; });
      early.insert(it, std::move(job));
      return;
    }
    if (BeyondHorizon(t_c)) return DropLate(t_c);
    if (!options.threaded) {
      Process(t_c, image, T_PC, K);  // no copy of the image
      std::lock_guard<std::mutex> lock(mutex);
      DrainEvidenceLocked();
      health.Decide(last_t);
      detector.OnHealth(last_t, health.health(), events);
      return;
    }
    Submit(Job{t_c, image, T_PC, K});
  }

  bool BeyondHorizon(double t_c) const { return t_c < last_t - options.horizon - kTimeTolerance; }

  void Submit(Job job) {
    if (BeyondHorizon(job.t_capture)) return DropLate(job.t_capture);
    if (!options.threaded) {
      Process(job.t_capture, job.image, job.T_PC, job.K);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (static_cast<int>(queue.size()) >= options.max_queued_images) {
        PushImageDroppedLocked(queue.front().t_capture, 1);
        queue.pop_front();
        ++stats.images_dropped_busy;
      }
      queue.push_back(std::move(job));
    }
    work_cv.notify_one();
  }

  void DropLate(double t_c) {
    std::lock_guard<std::mutex> lock(mutex);
    ++stats.images_dropped_late;
    PushImageDroppedLocked(t_c, 0);
  }

  // Under the lock: the event of an image dropped (`worker_busy` 1: the worker was behind).
  void PushImageDroppedLocked(double t_c, int worker_busy) {
    TrackerEvent e;
    e.t = t_c;
    e.kind = EventKind::kImageDropped;
    e.subject = worker_busy;
    e.value = t_c;
    events.push_back(e);
  }

  // Threaded: take over the worker's filter state (it includes every sample so far).
  void Adopt() {
    if (!options.threaded) return;
    std::lock_guard<std::mutex> lock(mutex);
    if (worker_error) std::rethrow_exception(std::exchange(worker_error, nullptr));
    if (adopt_pending) AdoptLocked();
  }

  void AdoptLocked() {
    filter.Restore(adopt_state);
    std::swap(last_visual, adopt_visual);
    memory = adopt_memory;
    adopt_pending = false;
  }

  // Under the lock, with the worker idle (WaitForImages, the queue emptied): the visual step
  // continues with `m`.
  void RecallLocked(const VisualMemory& m, long images_sequence) {
    memory = m;
    fusion->Recall(m);
    sequence = images_sequence;
  }

  void WaitForImages() {
    if (!options.threaded) return;
    {
      std::unique_lock<std::mutex> lock(mutex);
      idle_cv.wait(lock, [&] { return (queue.empty() && !busy) || worker_error; });
    }
    Adopt();
  }

  // --- the worker
  void WorkerLoop() {
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex);
        work_cv.wait(lock, [&] { return stop || !queue.empty(); });
        if (stop) return;
        job = std::move(queue.front());
        queue.pop_front();
        busy = true;
      }
      try {
        Process(job.t_capture, job.image, job.T_PC, job.K);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        worker_error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex);
        busy = false;
      }
      idle_cv.notify_all();
    }
  }

  // Fuses one image at its capture time (image_fusion.hpp) on copies of the slots since, then
  // catches up with the samples that arrived meanwhile, writes the slots back and publishes.
  void Process(double t_c, const Image8& image, const Transform& T_PC, const Intrinsics& K) {
    long a, upto;
    {
      std::lock_guard<std::mutex> lock(mutex);
      a = history.LastAtOrBefore(t_c);
      if (a < history.first()) {
        ++stats.images_dropped_late;
        PushImageDroppedLocked(t_c, 0);
        return;
      }
      upto = history.last();
      history.CopyOut(a, a, upto, fusion->slots());
    }
    fusion->Fuse(t_c, image, T_PC, K, upto - a);
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex);
      if (history.last() > upto) {
        const long from = upto + 1;
        upto = history.last();
        history.CopyOut(a, from, upto, fusion->slots());
        lock.unlock();
        fusion->Replay(from - a, upto - a);
        continue;
      }
      history.WriteBack(a, upto, fusion->slots());
      Publish(t_c, upto - a);
      return;
    }
  }

  // Under the lock: the statistics of a fused image, and its result for the caller.
  void Publish(double t_c, long replayed) {
    VisualStep& step = fusion->step();
    ++stats.images_fused;
    const VisualMemory after = fusion->Memory();
    stats.images_features_lost += after.features_lost();
    stats.images_tags_elsewhere += after.tag_disagreements > 0;
    if (step.relocalized > 0.0) {
      ++stats.relocalizations;
      if (step.recovered) ++stats.recoveries;
      stats.last_relocalization_t = t_c;
      stats.last_relocalized = step.relocalized;
    }
    stats.shifts_refused += step.shifts_refused;
    if (replayed > 0) ++stats.rewinds, stats.samples_replayed += replayed;
    EventDetector::Image im;
    ImageEvidence& e = im.evidence;
    e.t_capture = t_c;
    e.offered = step.offered;
    e.used = step.used;
    e.features_lost = after.features_lost();
    e.tags_elsewhere = after.tag_disagreements > 0;
    e.relocalized = step.relocalized;
    e.displacement = step.displacement;
    im.newest_t = history.At(history.last()).t;
    im.replayed = replayed;
    im.recovered = step.recovered;
    im.shifts_refused = step.shifts_refused;
    evidence.push_back(im);
    step.sequence = ++sequence;
    if (options.threaded) {
      adopt_state = fusion->filter().state();
      std::swap(adopt_visual, step);
      adopt_memory = after;
      adopt_pending = true;
    } else {
      std::swap(last_visual, step);
      memory = after;
    }
  }

  const HandModel& hand;
  const ObjectModel& object;
  Modalities modalities;
  TrackerParams params;
  TrackerOptions options;
  BulletContactQuery query;
  Filter filter;  // the caller's
  VisualStep last_visual;
  VisualMemory memory;   // after last_visual
  HealthMonitor health;  // the caller's
  PressCheck press;
  HandPlausibility plausibility;  // the start's
  Vec3 centre_O;                  // the object's bounds' centre
  double next_press_t = 0.0;
  EventDetector detector;  // the caller's

  bool start_set = false, started = false;
  double start_t = 0.0, last_t = 0.0;
  Transform start_T_PO = Transform::Identity();
  StartSigmas start_sigmas;
  std::deque<Job> early;  // images captured after the newest sample, in capture order

  std::unique_ptr<tracker_detail::ImageFusion>
      fusion;  // used by one thread: the caller's, or the worker

  // Shared with the worker.
  std::mutex mutex;
  tracker_detail::History history;
  long sequence = 0;
  TrackerStats stats;
  std::deque<Job> queue;
  bool busy = false, stop = false;
  bool adopt_pending = false;
  FilterState adopt_state;
  VisualStep adopt_visual;
  VisualMemory adopt_memory;
  std::vector<EventDetector::Image> evidence;  // images published, not yet judged by the caller
  std::vector<TrackerEvent> events;            // not taken yet
  std::exception_ptr worker_error;
  std::condition_variable work_cv, idle_cv;
  std::thread worker;
};

Tracker::Tracker(const HandModel& hand, const ObjectModel& object, const Modalities& modalities,
                 const TrackerParams& params, const TrackerOptions& options)
    : impl_(std::make_unique<Impl>(hand, object, modalities, params, options)) {}

Tracker::~Tracker() = default;

void Tracker::Start(double t, const Transform& T_PO, const StartSigmas& sigmas) {
  sigmas.Validate("Tracker::Start");
  if (!std::isfinite(t) || !T_PO.matrix().allFinite())
    throw InputError("Tracker::Start: the time or the pose is not finite");
  WaitForImages();
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lock(m.mutex);
  m.start_set = true;
  m.started = false;
  m.start_t = t;
  m.start_T_PO = T_PO;
  m.start_sigmas = sigmas;
  m.history.Clear();
  m.early.clear();
  m.queue.clear();
  m.adopt_pending = false;
  m.last_visual = VisualStep();
  m.RecallLocked(VisualMemory(), 0);
  m.evidence.clear();
  m.health.Reset(t);
  m.next_press_t = t;
  m.detector.Reset();
  m.events.clear();
}

void Tracker::AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                             const Eigen::Ref<const Eigen::VectorXd>& tau) {
  impl_->AddJointSample(t, q, tau);
}

void Tracker::AddImage(double t_capture, const Image8& image, const Transform& T_PC,
                       const Intrinsics& K) {
  impl_->AddImage(t_capture, image, T_PC, K);
}

void Tracker::WaitForImages() { impl_->WaitForImages(); }

bool Tracker::started() const { return impl_->started; }
double Tracker::t() const { return impl_->last_t; }
Transform Tracker::T_PO() const { return impl_->filter.T_PO(); }
Eigen::MatrixXd Tracker::covariance() const { return impl_->filter.covariance(); }
const Eigen::VectorXd& Tracker::biases() const { return impl_->filter.biases(); }
const Eigen::VectorXd& Tracker::joints() const { return impl_->q_used; }
const FilterTrace& Tracker::trace() const { return impl_->filter.trace(); }
const Filter& Tracker::filter() const { return impl_->filter; }
const VisualStep& Tracker::last_visual() const { return impl_->last_visual; }
VisualMemory Tracker::visual_memory() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->memory;
}
const Modalities& Tracker::modalities() const { return impl_->modalities; }
const TrackerParams& Tracker::params() const { return impl_->params; }

const Health& Tracker::health() const { return impl_->health.health(); }
const PressEvidence& Tracker::press_evidence() const { return impl_->health.press(); }
Mat6 Tracker::claimed_pose_covariance() const {
  const Filter& f = impl_->filter;
  return ClaimedPoseCovariance(f.covariance().topLeftCorner<6, 6>(), health(), f.T_PO().linear(),
                               f.options().gyration_O);
}

void Tracker::TakeEvents(std::vector<TrackerEvent>& out) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  out.insert(out.end(), impl_->events.begin(), impl_->events.end());
  impl_->events.clear();
}

void Tracker::CloseEvents() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->detector.Close(impl_->events);
}

TrackerStats Tracker::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->stats;
}

std::ostream& operator<<(std::ostream& os, const VisualMemory& m) {
  return os << "{tag_disagreements " << m.tag_disagreements << ", features_matched_well "
            << m.features_matched_well << ", features_poor_frames " << m.features_poor_frames
            << ", implausible_images " << m.implausible_images << "}";
}

TrackerSnapshot Tracker::Save() const {
  Impl& m = *impl_;
  TrackerSnapshot s;
  std::lock_guard<std::mutex> lock(m.mutex);
  s.started = m.started;
  s.t = m.last_t;
  s.filter = m.filter.state();
  s.visual = m.last_visual;
  s.memory = m.memory;
  s.stats = m.stats;
  s.health = m.health;
  s.next_press_t = m.next_press_t;
  s.events = m.detector;
  if (m.history.last() >= m.history.first()) s.last = m.history.At(m.history.last());
  return s;
}

void Tracker::Restore(const TrackerSnapshot& s) {
  WaitForImages();
  Impl& m = *impl_;
  INHAND_CHECK(m.start_set, "Tracker::Restore before Start");
  std::lock_guard<std::mutex> lock(m.mutex);
  m.early.clear();
  m.queue.clear();
  m.adopt_pending = false;
  m.started = s.started;
  m.last_t = s.t;
  m.stats = s.stats;
  m.health = s.health;
  m.next_press_t = s.next_press_t;
  m.detector = s.events;
  m.events.clear();
  m.evidence.clear();
  m.last_visual = s.visual;
  m.RecallLocked(s.memory, s.visual.sequence);
  m.history.Clear();
  if (!s.started) return;
  m.filter.Restore(s.filter);
  m.history.Push() = s.last;
}

}  // namespace inhand
