#include "tag_corners.hpp"

#include <algorithm>
#include <cmath>

#include "inhand/core/error.hpp"

namespace inhand::tracker_detail {

TagCorners::TagCorners(const ObjectModel& object, const TrackerParams& params)
    : object_(object), fine_search_(params.tag_fine_search) {
  if (object.tags.empty())
    throw InputError(object.source + ": modality a needs AprilTags on the object, it has none");
  TagDetectorParams p = params.tags;
  if (params.tag_family_from_object) p.family = object.tags.front().family;
  coarse_ = std::make_unique<TagDetector>(p);
  p.decimate = 1.0;
  fine_ = std::make_unique<TagDetector>(p);
}

void TagCorners::Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
                         const Transform& T_PO, std::vector<TagDetection>& tags,
                         std::vector<VisualFeature>& out) {
  // Decimation loses tags under ~30 px wide, as a tag on an object in the hand often is.
  tags = coarse_->Detect(image);
  const Transform T_CO = T_PC.inverse() * T_PO;
  for (const TagPlacement& tag : object_.tags) {
    if (!fine_search_) break;
    const bool found = std::any_of(tags.begin(), tags.end(), [&](const TagDetection& d) {
      return d.id == tag.id && d.family == tag.family;
    });
    if (found || tag.family != fine_->params().family) continue;
    const Transform T_CT = T_CO * tag.T_OT;
    if (T_CT.translation().z() <= 0.0 || T_CT.linear().col(2).dot(T_CT.translation()) >= 0.0)
      continue;  // behind, or seen from the back
    Eigen::AlignedBox2d box;
    bool in_front = true;
    for (const Vec3& c : tag.CornersO()) {
      const Vec3 X = T_CO * c;
      in_front = in_front && X.z() > 1e-3;
      if (in_front) box.extend(K.Project(X));
    }
    if (!in_front) continue;
    // Widened by the tag's size (at least 40 px) for the estimate's error.
    const double margin = std::max(40.0, box.sizes().maxCoeff());
    const PixelRect region{static_cast<int>(std::floor(box.min().x() - margin)),
                           static_cast<int>(std::floor(box.min().y() - margin)),
                           static_cast<int>(std::ceil(box.max().x() + margin)),
                           static_cast<int>(std::ceil(box.max().y() + margin))};
    for (const TagDetection& d : fine_->Detect(image, region))
      if (d.id == tag.id) tags.push_back(d);
  }
  out.clear();
  for (const TagDetection& d : tags)
    for (const TagPlacement& tag : object_.tags) {
      if (tag.id != d.id || tag.family != d.family) continue;
      const auto corners = tag.CornersO();
      for (std::size_t c = 0; c < 4; ++c)
        out.push_back({d.id * 4 + static_cast<int>(c), corners[c], K.Undistort(d.corners[c])});
    }
}

}  // namespace inhand::tracker_detail
