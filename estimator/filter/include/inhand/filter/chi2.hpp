#pragma once
// Quantiles of the χ² distribution that the gates and consistency tests compare a squared
// Mahalanobis distance with, named by degrees of freedom and probability (two decimals, as
// tables give them).

namespace inhand::chi2 {

constexpr double k2Dof99 = 9.21;    // a pixel (2 rows) at 99 %
constexpr double k6Dof999 = 22.46;  // a pose (δp, δθ) at 99.9 %

}  // namespace inhand::chi2
