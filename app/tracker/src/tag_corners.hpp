#pragma once
// Tag corners as visual measurements: AprilTags detected in the camera image, each corner the
// pixel of its known point on the object (TagPlacement::CornersO). Used on one thread only.
#include <memory>
#include <vector>

#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/tracker/tracker_params.hpp"

namespace inhand::tracker_detail {

class TagCorners {
 public:
  TagCorners(const ObjectModel& object, const TrackerParams& params);
  // Tags of the whole frame at the detector's decimation; then each of the object's tags that
  // the estimate puts in view, facing the camera, and that was not found, searched at full
  // resolution in its expected box. Their corners (undistorted) into `out`.
  void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
               const Transform& T_PO, std::vector<TagDetection>& tags,
               std::vector<VisualFeature>& out);

 private:
  const ObjectModel& object_;
  bool fine_search_;
  std::unique_ptr<TagDetector> coarse_, fine_;
};

}  // namespace inhand::tracker_detail
