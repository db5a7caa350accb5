#include "tag_source.hpp"

#include "inhand/filter/chi2.hpp"
#include "inhand/filter/contact_model.hpp"

namespace inhand::tracker_detail {

TagSource::TagSource(const ObjectModel& object, const TrackerParams& params)
    : object_(object),
      corners_(object, params),
      pixel_sigma_(params.filter.pixel_sigma),
      relocate_images_(params.tag_relocate_images) {}

void TagSource::Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
                        const Eigen::VectorXd& /*tau*/, const Filter& f, VisualStep& step,
                        VisualUpdate& update) {
  corners_.Measure(image, T_PC, K, f.T_PO(), step.tags, update.features);
  TagPoseFit fit;
  const bool elsewhere = relocate_images_ > 0 && Elsewhere(f, update.features, T_PC, K, fit);
  disagreements_ = elsewhere ? disagreements_ + 1 : 0;
  if (!elsewhere || disagreements_ < relocate_images_) return;
  // The object is put where the tags' fit says, and that fit is this image's measurement (the
  // same corners are not fused as well).
  disagreements_ = 0;
  step.relocalized = (fit.T_PO.translation() - f.position()).norm();
  update = VisualUpdate::Relocation(update.t_capture, fit.T_PO, fit.covariance, T_PC, K);
}

// The pose difference's χ²₆ under the sum of both covariances above 99.9 %.
bool TagSource::Disagrees(const Filter& f, const TagPoseFit& fit) {
  const Vec6 d = PoseError(fit.T_PO, f.T_PO());
  const Mat6 S = f.covariance().topLeftCorner<6, 6>() + fit.covariance;
  return d.dot(S.ldlt().solve(d)) > chi2::k6Dof999;
}

// Every fit that explains the corners nearly as well as the best (χ²₂ 99 % in units of the
// pixel σ) counts, and one that agrees with the estimate ends it. A small tag seen at an angle
// fits two poses nearly alike: when neither is where the estimate is, the object is put at the
// better one, its covariance widened by the other's difference (d dᵀ).
bool TagSource::Elsewhere(const Filter& f, const std::vector<VisualFeature>& corners,
                          const Transform& T_PC, const Intrinsics& K, TagPoseFit& where) {
  const double sigma = pixel_sigma_;
  FitTagPoses(object_, corners, T_PC, K, f.T_PO(), sigma, fits_);
  if (fits_.empty() || fits_.front().cost > sigma * sigma * static_cast<double>(corners.size()))
    return false;
  where = fits_.front();
  for (const auto& fit : fits_) {
    if (fit.cost > fits_.front().cost + chi2::k2Dof99 * sigma * sigma) break;
    if (!Disagrees(f, fit)) return false;
    const Vec6 d = PoseError(fit.T_PO, where.T_PO);
    where.covariance += d * d.transpose();
  }
  return true;
}

}  // namespace inhand::tracker_detail
