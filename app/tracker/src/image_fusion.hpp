#pragma once
// Fuses one image at its capture time, on copies of the history's slots: restore the checkpoint
// of the last sample at or before the capture time, re-apply the visual updates already fused
// there that were captured earlier, measure the image with every visual source and fuse what
// each wants, re-apply the later updates of that sample and then every later sample. Runs on
// one thread: the caller's (deterministic, on the caller's filter) or the worker's (on a filter
// of its own).
#include <memory>
#include <vector>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/tracker/tracker.hpp"
#include "visual_source.hpp"

namespace inhand::tracker_detail {

// The filter options of a tracker's set.
FilterOptions FilterOptionsFor(const ObjectModel& object, const Modalities& modalities);

class ImageFusion {
 public:
  // `shared`: the filter to work on (the caller's), or nullptr for one of its own (the worker's).
  // Throws InputError for a configuration the sources refuse (tags on an object without tags).
  ImageFusion(const HandModel& hand, const ObjectModel& object, const Modalities& modalities,
              const TrackerParams& params, Filter* shared);
  ~ImageFusion();

  Filter& filter() { return *filter_; }
  // The slots to work on: [0] the sample the image is fused after, then the later ones.
  std::vector<TrackedSample>& slots() { return slots_; }
  // What the last image showed and did.
  VisualStep& step() { return step_; }

  // Fuses the image captured at t_c after slots()[0] and replays slots()[1..last].
  void Fuse(double t_c, const Image8& image, const Transform& T_PC, const Intrinsics& K, long last);
  // Replays slots()[from..to] (the samples that arrived meanwhile).
  void Replay(long from, long to);

  VisualMemory Memory() const;
  void Recall(const VisualMemory& memory);

 private:
  // Applies an update just measured, counting what it offered and fused into step_.
  int Apply(const VisualUpdate& update, double& mahalanobis_sum);

  std::unique_ptr<BulletContactQuery> query_;  // the own filter's
  std::unique_ptr<Filter> own_;
  Filter* filter_ = nullptr;
  std::vector<std::unique_ptr<VisualSource>> sources_;  // extracted features, then tags
  std::vector<TrackedSample> slots_;
  std::vector<VisualUpdate> fresh_;
  std::vector<double> displacements_;  // one update's, for their median
  VisualStep step_;
};

}  // namespace inhand::tracker_detail
