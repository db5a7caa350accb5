#pragma once
// The tracker's history: after every joint sample a checkpoint of the filter (a slot of a ring),
// with the visual updates fused after that sample. Single-threaded: the tracker's shell guards
// it with its mutex; the rewind works on copies of the slots (CopyOut, WriteBack).
#include <vector>

#include "inhand/core/time.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::tracker_detail {

// inhand::kTimeTolerance (core/time.hpp): an image captured at t_c goes after the samples with
// t <= t_c + it; the same tolerance decides which images a new sample passes and which are beyond
// the horizon.
using ::inhand::kTimeTolerance;

class History {
 public:
  // Room for `samples` samples; empties the history.
  void Resize(int samples);
  void Clear() { first_ = 0, last_ = -1; }
  // Gives every slot its buffers now, shaped like `state`, so that a joint sample allocates
  // nothing.
  void Preallocate(int num_q, const FilterState& state);

  // Sample numbers held: [first(), last()]; last() < first() when empty.
  long first() const { return first_; }
  long last() const { return last_; }
  TrackedSample& At(long k) {
    return ring_[static_cast<std::size_t>(k % static_cast<long>(ring_.size()))];
  }
  const TrackedSample& At(long k) const {
    return ring_[static_cast<std::size_t>(k % static_cast<long>(ring_.size()))];
  }

  // A new newest sample (the oldest is forgotten when the ring is full); its slot, to fill.
  TrackedSample& Push();
  // The newest sample with t <= t_c (kTimeTolerance), or first() - 1 when every sample held is
  // later.
  long LastAtOrBefore(double t_c) const;
  // The samples [from, to] into `local` (index k - a), growing it when needed.
  void CopyOut(long a, long from, long to, std::vector<TrackedSample>& local) const;
  // The checkpoints and visual updates of the samples [max(a, first()), to] from `local`.
  void WriteBack(long a, long to, const std::vector<TrackedSample>& local);

  // Applies a fused visual update again (after an older image was fused before it).
  static void Apply(Filter& filter, const VisualUpdate& update);
  // Fuses a sample again after the filter has moved: its joint step, its new checkpoint, then
  // its visual updates.
  static void Replay(Filter& filter, TrackedSample& sample);

 private:
  std::vector<TrackedSample> ring_;
  long first_ = 0, last_ = -1;
};

}  // namespace inhand::tracker_detail
