#pragma once
// Tags as a visual source: each image's tag corners are fused as features, unless the tags have
// put the object where the estimate cannot be in TrackerParams::tag_relocate_images images in a
// row; then the object is put where their own fit says (a relocation), instead of the corners
// being gated one by one while the estimate stays where the object is not (a bottle fallen out
// of a loosened grip, a start far off).
#include <vector>

#include "inhand/filter/tag_pose_fit.hpp"
#include "tag_corners.hpp"
#include "visual_source.hpp"

namespace inhand::tracker_detail {

class TagSource final : public VisualSource {
 public:
  TagSource(const ObjectModel& object, const TrackerParams& params);
  // Fills step.tags (and step.relocalized, the distance, when it relocates).
  void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
               const Eigen::VectorXd& tau, const Filter& filter, VisualStep& step,
               VisualUpdate& update) override;
  void Fused(const Filter&, const VisualUpdate&, int, VisualStep&) override {}
  void Remember(VisualMemory& memory) const override { memory.tag_disagreements = disagreements_; }
  void Recall(const VisualMemory& memory) override { disagreements_ = memory.tag_disagreements; }

 private:
  // Whether the corners of this image put the object where the estimate cannot be; if so,
  // `where` is the best fit.
  bool Elsewhere(const Filter& f, const std::vector<VisualFeature>& corners, const Transform& T_PC,
                 const Intrinsics& K, TagPoseFit& where);
  // Whether a pose the tags fit is beyond what the estimate and the fit can both be off by.
  static bool Disagrees(const Filter& f, const TagPoseFit& fit);

  const ObjectModel& object_;
  TagCorners corners_;
  double pixel_sigma_;
  int relocate_images_;
  int disagreements_ = 0;  // images in a row whose tags put the object where the estimate cannot be
  std::vector<TagPoseFit> fits_;
};

}  // namespace inhand::tracker_detail
