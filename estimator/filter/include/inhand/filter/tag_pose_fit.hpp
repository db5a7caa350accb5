#pragma once
// The object's poses that its tags' corners fit on their own, without the filter: what the
// tracker compares the estimate with before it fuses the corners, and where it relocates the
// estimate when the two disagree (docs/estimator.md, "Relocation").
#include <vector>

#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/core/so3.hpp"
#include "inhand/filter/filter.hpp"

namespace inhand {

struct TagPoseFit {
  Transform T_PO = Transform::Identity();
  Mat6 covariance = Mat6::Identity();  // of (δp, δθ) in the palm frame, the filter's error state
  double cost = 0.0;                   // [px²] sum of the corners' squared pixel errors at the fit
};

// `corners` come four per tag, in TagPlacement::CornersO's order, each with id = 4 * tag id +
// corner and its undistorted pixel. Each tag's homography, its mirror image and `T_PO_guess`
// start a Gauss-Newton fit of all corners; each distinct minimum (5 mm or 5° apart), best first,
// goes into `fits` with its covariance (HᵀH)⁻¹ σ², σ = `pixel_sigma`. A small tag seen at an
// angle has two poses that fit nearly alike: which one is the object's, its corners cannot tell.
// No corners, or not four per tag: no fit.
void FitTagPoses(const ObjectModel& object, const std::vector<VisualFeature>& corners,
                 const Transform& T_PC, const Intrinsics& K, const Transform& T_PO_guess,
                 double pixel_sigma, std::vector<TagPoseFit>& fits);

}  // namespace inhand
