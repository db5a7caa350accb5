#pragma once
// A source of visual measurements (tag corners, extracted features): it measures an image
// against the filter at the image's capture time, says what it wants fused (features, or the
// object put elsewhere) and owns what it remembers from one image to the next. The tracker
// applies the update, counts it and keeps it for re-application (History).
#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::tracker_detail {

class VisualSource {
 public:
  virtual ~VisualSource() = default;
  // Measures `image` against `filter` and fills `update` (its time and camera are set): the
  // features to fuse after widening the position by update.widen_position, or a relocation.
  // `tau`: the joint torques of the sample the image is fused after (sets without torques
  // ignore them).
  // Writes what it saw into `step`.
  virtual void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
                       const Eigen::VectorXd& tau, const Filter& filter, VisualStep& step,
                       VisualUpdate& update) = 0;
  // `update` was applied to `filter`, which fused `used` of its features.
  virtual void Fused(const Filter& filter, const VisualUpdate& update, int used,
                     VisualStep& step) = 0;
  // What Measure carries from one image to the next, to save and to set back.
  virtual void Remember(VisualMemory& memory) const = 0;
  virtual void Recall(const VisualMemory& memory) = 0;
};

}  // namespace inhand::tracker_detail
