#include "inhand/app/evaluation.hpp"

#include <Eigen/Cholesky>

namespace inhand::app {

void CompareWithTruth(const Transform& gt, const Mat6& P, EstimateRecord& r) {
  r.position_error = (r.T_PO.translation() - gt.translation()).norm();
  r.orientation_error = RotationDistance(r.T_PO.linear(), gt.linear());
  r.position_error_O = gt.linear().transpose() * (r.T_PO.translation() - gt.translation());
  r.orientation_error_O = LogSO3(gt.linear().transpose() * r.T_PO.linear());
  Vec6 e;
  e.head<3>() = gt.translation() - r.T_PO.translation();
  e.tail<3>() = LogSO3(gt.linear() * r.T_PO.linear().transpose());
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
