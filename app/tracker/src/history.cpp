#include "history.hpp"

#include <algorithm>

namespace inhand::tracker_detail {

void History::Resize(int samples) {
  ring_.resize(static_cast<std::size_t>(samples));
  Clear();
}

void History::Preallocate(int num_q, const FilterState& state) {
  for (TrackedSample& s : ring_) {
    s.q.setZero(num_q);
    s.tau.setZero(num_q);
    s.after_sample = state;
    s.after_sample.trace.contacts.reserve(state.trace.contacts.capacity());
    s.fused.reserve(4);
  }
}

TrackedSample& History::Push() {
  const long k = ++last_;
  if (k - first_ >= static_cast<long>(ring_.size()))
    first_ = k - static_cast<long>(ring_.size()) + 1;
  return At(k);
}

long History::LastAtOrBefore(double t_c) const {
  long a = last_;
  while (a >= first_ && At(a).t > t_c + kTimeTolerance) --a;
  return a;
}

void History::CopyOut(long a, long from, long to, std::vector<TrackedSample>& local) const {
  if (local.size() < static_cast<std::size_t>(to - a + 1))
    local.resize(static_cast<std::size_t>(to - a + 1));
  for (long k = from; k <= to; ++k) local[static_cast<std::size_t>(k - a)] = At(k);
}

void History::WriteBack(long a, long to, const std::vector<TrackedSample>& local) {
  for (long k = std::max(a, first_); k <= to; ++k) {
    TrackedSample& s = At(k);
    const TrackedSample& mine = local[static_cast<std::size_t>(k - a)];
    s.after_sample = mine.after_sample;
    s.fused = mine.fused;
  }
}

void History::Apply(Filter& f, const VisualUpdate& u) {
  if (u.relocate) f.Relocate(u.relocate_T_PO, u.relocate_covariance);
  if (u.widen_position > 0.0) f.WidenPose(u.widen_position, 0.0);
  f.UpdateVisual(u.features, u.T_PC, u.K);
}

void History::Replay(Filter& f, TrackedSample& s) {
  f.Step(s.q, s.tau, s.dt);
  s.after_sample = f.state();
  for (const VisualUpdate& u : s.fused) Apply(f, u);
}

}  // namespace inhand::tracker_detail
