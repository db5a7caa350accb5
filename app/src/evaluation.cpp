#include "inhand/app/evaluation.hpp"

#include <Eigen/Cholesky>

namespace inhand::app {

void CompareWithTruth(const Transform& gt, const Mat6& P, EstimateRecord& r) {
  r.position_error = (r.T_PO.translation() - gt.translation()).norm();
  r.orientation_error = RotationDistance(r.T_PO.linear(), gt.linear());
  r.position_error_O = gt.linear().transpose() * (r.T_PO.translation() - gt.translation());
  r.orientation_error_O = LogSO3(gt.linear().transpose() * r.T_PO.linear());
  const Vec6 e = PoseError(gt, r.T_PO);
  r.nees = e.dot(P.ldlt().solve(e));
}

EstimateRecord WithoutTruth(EstimateRecord r) {
  const EstimateRecord blank;
  r.position_error = blank.position_error;
  r.orientation_error = blank.orientation_error;
  r.position_error_O = blank.position_error_O;
  r.orientation_error_O = blank.orientation_error_O;
  r.nees = blank.nees;
  return r;
}

}  // namespace inhand::app
