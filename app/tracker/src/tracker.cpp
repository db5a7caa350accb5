// The tracker's history: after every joint sample a checkpoint of the filter (a slot of a
// ring), with the visual updates fused after that sample. An image captured at t_c is fused
// after the last sample with t <= t_c: restore that sample's checkpoint, re-apply the visual
// updates already fused there that were captured before t_c, measure and fuse the image, then
// re-apply the rest and every later sample (with its visual updates), rewriting their
// checkpoints. The same procedure runs on the caller's thread (deterministic) or on the worker
// (threaded), which works on its own filter and copies of the slots, catches up with the samples
// that arrived meanwhile, writes the slots back and leaves its filter state for the caller to
// adopt at its next call.
#include "inhand/tracker/tracker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <ostream>
#include <sstream>
#include <thread>
#include <utility>

#include "extracted_features.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/chi2.hpp"
#include "tag_corners.hpp"

namespace inhand {

std::string Modalities::Name() const {
  return std::string("j") + (torque ? "t" : "") + (tags ? "a" : "") + (features ? "f" : "");
}

namespace {

constexpr double kTimeTolerance = 1e-9;  // [s] an image at t_c goes after samples with t <= t_c + this

using Slot = TrackedSample;

struct Job {
  double t_capture = 0.0;
  Image8 image;
  Transform T_PC = Transform::Identity();
  Intrinsics K;
};

FilterOptions FilterOptionsFor(const ObjectModel& object, const Modalities& m) {
  FilterOptions options;
  options.use_torque = m.torque;
  options.gyration_O = object.inertia_com / object.mass;  // for FilterParams::travel_orientation
  return options;
}

}  // namespace

struct Tracker::Impl {
  // Where visual measurements are made and fused: the caller's filter (deterministic) or the
  // worker's own. Used by one thread only.
  struct Processor {
    std::unique_ptr<BulletContactQuery> query;  // the worker's (the caller's filter has its own)
    std::unique_ptr<Filter> own_filter;
    Filter* filter = nullptr;
    std::unique_ptr<tracker_detail::TagCorners> tags;
    std::unique_ptr<tracker_detail::ExtractedFeatures> features;
    std::vector<Slot> local;
    std::vector<VisualFeature> measured;
    VisualStep step;
    int tag_disagreements = 0;  // images in a row whose tags put the object where the estimate cannot be
    std::vector<tracker_detail::TagCorners::PoseFit> fits;

    VisualMemory Memory() const {
      VisualMemory m;
      m.tag_disagreements = tag_disagreements;
      if (features) m.features_matched_well = features->matched_well(), m.features_poor_frames = features->poor_frames();
      return m;
    }
    void Recall(const VisualMemory& m) {
      tag_disagreements = m.tag_disagreements;
      if (features) features->Recall(m.features_matched_well, m.features_poor_frames);
    }
  };

  Impl(const HandModel& h, const ObjectModel& o, const Modalities& m, const TrackerParams& p, const TrackerOptions& opt)
      : hand(h), object(o), modalities(m), params(p), options(opt), query(h, o), filter(h, query, p.filter, FilterOptionsFor(o, m)) {
    params.Validate();
    const std::vector<double>& ks = h.joint_stiffness;
    if (!ks.empty() && ks.size() != static_cast<std::size_t>(h.num_q()))
      throw InputError("hand joint_stiffness: " + std::to_string(ks.size()) + " values for " + std::to_string(h.num_q()) +
                       " joints, expected one per joint or none");
    for (std::size_t j = 0; j < ks.size(); ++j) {
      if (std::isfinite(ks[j]) && ks[j] >= 0.0) continue;
      std::ostringstream os;
      os << "hand joint_stiffness of joint '" << h.QNames()[j] << "' is " << ks[j] << ", expected >= 0 N m/rad (0: rigid)";
      throw InputError(os.str());
    }
    deflect = m.torque && std::any_of(ks.begin(), ks.end(), [](double k) { return k > 0.0; });
    if (!(options.horizon >= 0.0) || options.history_samples < 1 || options.max_queued_images < 1)
      throw InputError("tracker options: horizon must be >= 0 s, history_samples and max_queued_images >= 1");
    ring.resize(static_cast<std::size_t>(options.history_samples));
    if (options.threaded) {
      proc.query = std::make_unique<BulletContactQuery>(h, o);
      proc.own_filter = std::make_unique<Filter>(h, *proc.query, p.filter, FilterOptionsFor(o, m));
      proc.filter = proc.own_filter.get();
    } else {
      proc.filter = &filter;
    }
    // Configuration errors surface here, not on the worker.
    if (m.tags) proc.tags = std::make_unique<tracker_detail::TagCorners>(o, params);
    if (m.features) proc.features = std::make_unique<tracker_detail::ExtractedFeatures>(h, o, params.features);
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

  // The encoder reads the motor side; the link lags it by the external torque over the
  // stiffness (HandModel::joint_stiffness): q_link = q_recorded − τ / k. τ is finite here:
  // ScreenJointSample refused the sample otherwise.
  void Undeflect(const Eigen::Ref<const Eigen::VectorXd>& tau) {
    for (int j = 0; j < q_used.size(); ++j) {
      const double k = hand.joint_stiffness[static_cast<std::size_t>(j)];
      if (k > 0.0) q_used[j] -= tau[j] / k;
    }
  }

  Slot& At(long k) { return ring[static_cast<std::size_t>(k % static_cast<long>(ring.size()))]; }

  // --- the caller's side
  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& tau) {
    INHAND_CHECK(start_set, "Tracker::AddJointSample before Start");
    INHAND_CHECK(q.size() == hand.num_q() && tau.size() == hand.num_q(), "joint sample size does not match the hand");
    Adopt();
    if (!std::isfinite(t) || (started && !(t > last_t)) || (!started && !(t >= start_t - kTimeTolerance))) {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.samples_dropped;
      return;
    }
    if (ScreenJointSample(hand, params, q, tau).joint >= 0) {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.samples_rejected;
      return;
    }
    // Images captured before this sample belong after the previous one.
    while (!early.empty() && early.front().t_capture + kTimeTolerance < t) {
      Job job = std::move(early.front());
      early.pop_front();
      if (started) Submit(std::move(job));
      else DropLate();
    }
    if (q_used.size() != q.size()) q_used.resize(q.size());  // once
    q_used = q;
    if (deflect) Undeflect(tau);
    if (params.joint_clamp_to_limits) ClampToLimits(hand, q_used);
    const double dt = started ? t - last_t : 0.0;
    if (!started) {
      filter.Reset(start_T_PO, q_used, start_sigmas);
      started = true;
      PreallocateRing();
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
      const long k = ++last;
      if (k - first >= static_cast<long>(ring.size())) first = k - static_cast<long>(ring.size()) + 1;
      Slot& s = At(k);
      s.t = t;
      s.dt = dt;
      s.q = q_used;
      s.tau = tau;
      s.after_sample = filter.state();
      s.fused.clear();
      ++stats.samples;
    }
    last_t = t;
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
      return;
    }
    if (!started || t_c > last_t + kTimeTolerance) {
      if (t_c + kTimeTolerance < start_t) return DropLate();
      // Waits for the samples up to its capture time, in capture order.
      Job job{t_c, image, T_PC, K};
      auto it = std::upper_bound(early.begin(), early.end(), t_c, [](double v, const Job& j) { return v < j.t_capture; });
      early.insert(it, std::move(job));
      return;
    }
    if (BeyondHorizon(t_c)) return DropLate();
    if (!options.threaded) return Process(t_c, image, T_PC, K);  // no copy of the image
    Submit(Job{t_c, image, T_PC, K});
  }

  bool BeyondHorizon(double t_c) const { return t_c < last_t - options.horizon - kTimeTolerance; }

  void Submit(Job job) {
    if (BeyondHorizon(job.t_capture)) return DropLate();
    if (!options.threaded) {
      Process(job.t_capture, job.image, job.T_PC, job.K);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (static_cast<int>(queue.size()) >= options.max_queued_images) {
        queue.pop_front();
        ++stats.images_dropped_busy;
      }
      queue.push_back(std::move(job));
    }
    work_cv.notify_one();
  }

  void DropLate() {
    std::lock_guard<std::mutex> lock(mutex);
    ++stats.images_dropped_late;
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
    proc.Recall(m);
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

  // Every slot gets its buffers now, so that a joint sample allocates nothing.
  void PreallocateRing() {
    std::lock_guard<std::mutex> lock(mutex);
    for (Slot& s : ring) {
      s.q.setZero(hand.num_q());
      s.tau.setZero(hand.num_q());
      s.after_sample = filter.state();
      s.after_sample.trace.contacts.reserve(filter.state().trace.contacts.capacity());
      s.fused.reserve(4);
    }
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

  static void Apply(Filter& f, const VisualUpdate& u) {
    if (u.relocate) f.Relocate(u.relocate_T_PO, u.relocate_covariance);
    if (u.widen_position > 0.0) f.WidenPose(u.widen_position, 0.0);
    f.UpdateVisual(u.features, u.T_PC, u.K);
  }

  // Whether a pose the tags fit is beyond what the estimate and the fit can both be off by: the
  // pose difference's χ²₆ under the sum of their covariances above 99.9 %.
  static bool Disagrees(const Filter& f, const tracker_detail::TagCorners::PoseFit& fit) {
    const Vec6 d = PoseError(fit.T_PO, f.T_PO());
    const Mat6 S = f.covariance().topLeftCorner<6, 6>() + fit.covariance;
    return d.dot(S.ldlt().solve(d)) > chi2::k6Dof999;
  }

  // Whether the tags of this image put the object where the estimate cannot be; if so, `where`
  // is the best fit. Every fit that explains the corners nearly as well as the best (χ²₂ 99 %
  // in units of the pixel σ) counts, and one that agrees with the estimate ends it. A small tag
  // seen at an angle fits two poses nearly alike: when neither is where the estimate is, the
  // object is put at the better one, its covariance widened by the other's difference (d dᵀ).
  bool TagsElsewhere(const Filter& f, const Transform& T_PC, const Intrinsics& K, tracker_detail::TagCorners::PoseFit& where) {
    std::vector<tracker_detail::TagCorners::PoseFit>& fits = proc.fits;
    const double sigma = params.filter.pixel_sigma;
    proc.tags->FitPoses(proc.measured, T_PC, K, f.T_PO(), sigma, fits);
    if (fits.empty() || fits.front().cost > sigma * sigma * static_cast<double>(proc.measured.size())) return false;
    where = fits.front();
    for (const auto& fit : fits) {
      if (fit.cost > fits.front().cost + chi2::k2Dof99 * sigma * sigma) break;
      if (!Disagrees(f, fit)) return false;
      const Vec6 d = PoseError(fit.T_PO, where.T_PO);
      where.covariance += d * d.transpose();
    }
    return true;
  }

  void Replay(Filter& f, Slot& s) {
    f.Step(s.q, s.tau, s.dt);
    s.after_sample = f.state();
    for (const VisualUpdate& u : s.fused) Apply(f, u);
  }

  // Under the lock: the ring's samples [from, to] into the processor's copies (index k - a).
  void CopyOut(long a, long from, long to) {
    std::vector<Slot>& local = proc.local;
    if (local.size() < static_cast<std::size_t>(to - a + 1)) local.resize(static_cast<std::size_t>(to - a + 1));
    for (long k = from; k <= to; ++k) local[static_cast<std::size_t>(k - a)] = At(k);
  }

  // Fuses one image at its capture time (see the top of this file).
  void Process(double t_c, const Image8& image, const Transform& T_PC, const Intrinsics& K) {
    Filter& f = *proc.filter;
    std::vector<Slot>& local = proc.local;
    long a, upto;
    {
      std::lock_guard<std::mutex> lock(mutex);
      a = last;
      while (a >= first && At(a).t > t_c + kTimeTolerance) --a;
      if (a < first) {
        ++stats.images_dropped_late;
        return;
      }
      upto = last;
      CopyOut(a, a, upto);
    }
    const auto start = std::chrono::steady_clock::now();
    f.Restore(local[0].after_sample);
    std::vector<VisualUpdate>& here = local[0].fused;
    std::size_t split = 0;
    while (split < here.size() && here[split].t_capture <= t_c) Apply(f, here[split++]);

    VisualStep& step = proc.step;
    step.tags.clear();
    step.has_features = false;
    step.offered = step.used = 0;
    step.relocalized = 0.0;
    double m2 = 0.0;
    std::vector<VisualUpdate> fresh;
    const auto fuse = [&](std::vector<VisualFeature>& measured, double widen_position) {
      if (widen_position > 0.0) f.WidenPose(widen_position, 0.0);
      step.used += f.UpdateVisual(measured, T_PC, K);
      step.offered += static_cast<int>(measured.size());
      const auto& visual = f.trace().visual;
      for (std::size_t i = visual.size() - measured.size(); i < visual.size(); ++i) m2 += visual[i].mahalanobis;
      fresh.push_back({t_c, widen_position, false, Transform::Identity(), Mat6::Identity(), measured, T_PC, K});
    };
    if (proc.features) {
      proc.features->Measure(image, T_PC, K, f, step, proc.measured);
      const Transform T_CP = T_PC.inverse();
      const auto residuals = [&](std::vector<double>& out) {
        const Transform T_PO = f.T_PO();
        out.clear();
        for (const VisualFeature& v : proc.measured) out.push_back((K.Project(T_CP * (T_PO * v.x_O)) - v.pixel).norm());
      };
      residuals(step.residual_before);
      fuse(proc.measured, step.relocalized);
      proc.features->Fused(step.used);
      residuals(step.residual_after);
    }
    if (proc.tags) {
      proc.tags->Measure(image, T_PC, K, f.T_PO(), step.tags, proc.measured);
      tracker_detail::TagCorners::PoseFit fit;
      const bool elsewhere = params.tag_relocate_images > 0 && TagsElsewhere(f, T_PC, K, fit);
      proc.tag_disagreements = elsewhere ? proc.tag_disagreements + 1 : 0;
      if (elsewhere && proc.tag_disagreements >= params.tag_relocate_images) {
        // The tags put the object where the estimate cannot be: it is put there, and the fit is
        // this image's measurement.
        proc.tag_disagreements = 0;
        step.relocalized = (fit.T_PO.translation() - f.position()).norm();
        f.Relocate(fit.T_PO, fit.covariance);
        fresh.push_back({t_c, 0.0, true, fit.T_PO, fit.covariance, {}, T_PC, K});
      } else {
        fuse(proc.measured, 0.0);
      }
    }
    step.mean_mahalanobis = step.offered > 0 ? m2 / step.offered : 0.0;
    step.t_capture = t_c;
    step.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    here.insert(here.begin() + static_cast<long>(split), fresh.begin(), fresh.end());
    for (std::size_t i = split + fresh.size(); i < here.size(); ++i) Apply(f, here[i]);
    for (long k = a + 1; k <= upto; ++k) Replay(f, local[static_cast<std::size_t>(k - a)]);

    // Catch up with the samples that arrived meanwhile, then write back and publish.
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex);
      if (last > upto) {
        const long from = upto + 1;
        upto = last;
        CopyOut(a, from, upto);
        lock.unlock();
        for (long k = from; k <= upto; ++k) Replay(f, local[static_cast<std::size_t>(k - a)]);
        continue;
      }
      for (long k = std::max(a, first); k <= upto; ++k) {
        Slot& s = At(k);
        const Slot& mine = local[static_cast<std::size_t>(k - a)];
        s.after_sample = mine.after_sample;
        s.fused = mine.fused;
      }
      ++stats.images_fused;
      const VisualMemory after = proc.Memory();
      stats.images_features_lost += after.features_lost();
      stats.images_tags_elsewhere += after.tag_disagreements > 0;
      if (step.relocalized > 0.0) {
        ++stats.relocalizations;
        stats.last_relocalization_t = t_c;
        stats.last_relocalized = step.relocalized;
      }
      if (upto > a) ++stats.rewinds, stats.samples_replayed += upto - a;
      step.sequence = ++sequence;
      if (options.threaded) {
        adopt_state = f.state();
        std::swap(adopt_visual, step);
        adopt_memory = after;
        adopt_pending = true;
      } else {
        std::swap(last_visual, step);
        memory = after;
      }
      return;
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
  VisualMemory memory;  // after last_visual

  bool start_set = false, started = false;
  double start_t = 0.0, last_t = 0.0;
  Transform start_T_PO = Transform::Identity();
  StartSigmas start_sigmas;
  std::deque<Job> early;  // images captured after the newest sample, in capture order

  Processor proc;

  // Shared with the worker.
  std::mutex mutex;
  std::vector<Slot> ring;
  long first = 0, last = -1;  // sample numbers held by the ring
  long sequence = 0;
  TrackerStats stats;
  std::deque<Job> queue;
  bool busy = false, stop = false;
  bool adopt_pending = false;
  FilterState adopt_state;
  VisualStep adopt_visual;
  VisualMemory adopt_memory;
  std::exception_ptr worker_error;
  std::condition_variable work_cv, idle_cv;
  std::thread worker;
};

Tracker::Tracker(const HandModel& hand, const ObjectModel& object, const Modalities& modalities, const TrackerParams& params,
                 const TrackerOptions& options)
    : impl_(std::make_unique<Impl>(hand, object, modalities, params, options)) {}

Tracker::~Tracker() = default;

void Tracker::Start(double t, const Transform& T_PO, const StartSigmas& sigmas) {
  sigmas.Validate("Tracker::Start");
  if (!std::isfinite(t) || !T_PO.matrix().allFinite()) throw InputError("Tracker::Start: the time or the pose is not finite");
  WaitForImages();
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lock(m.mutex);
  m.start_set = true;
  m.started = false;
  m.start_t = t;
  m.start_T_PO = T_PO;
  m.start_sigmas = sigmas;
  m.first = 0;
  m.last = -1;
  m.early.clear();
  m.queue.clear();
  m.adopt_pending = false;
  m.last_visual = VisualStep();
  m.RecallLocked(VisualMemory(), 0);
}

void Tracker::AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& tau) {
  impl_->AddJointSample(t, q, tau);
}

void Tracker::AddImage(double t_capture, const Image8& image, const Transform& T_PC, const Intrinsics& K) {
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

TrackerStats Tracker::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->stats;
}

std::ostream& operator<<(std::ostream& os, const VisualMemory& m) {
  return os << "{tag_disagreements " << m.tag_disagreements << ", features_matched_well " << m.features_matched_well
            << ", features_poor_frames " << m.features_poor_frames << "}";
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
  if (m.last >= m.first) s.last = m.At(m.last);
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
  m.last_visual = s.visual;
  m.RecallLocked(s.memory, s.visual.sequence);
  m.first = 0;
  m.last = -1;
  if (!s.started) return;
  m.filter.Restore(s.filter);
  m.last = 0;
  m.At(0) = s.last;
}

}  // namespace inhand
