#include "inhand/app/evaluation.hpp"

#include <Eigen/Cholesky>

namespace inhand::app {

void RecordContacts(const FilterTrace& trace, EstimateRecord& r) {
  r.contacts = static_cast<int>(trace.contacts.size());
  r.constraints = trace.num_constraints;
  r.penetration = trace.penetration;
  r.unexplained_torque = trace.unexplained_torque;
}

void RecordTrackerState(const Tracker& tracker, EstimateRecord& r) {
  const FilterTrace& trace = tracker.trace();
  r.T_PO = tracker.T_PO();
  const Mat6 P = tracker.claimed_pose_covariance();
  r.sigma_position = P.diagonal().head<3>().cwiseSqrt();
  r.sigma_orientation = P.diagonal().segment<3>(3).cwiseSqrt();
  r.biases = tracker.biases();
  r.gated = trace.num_gated;  // contacts and visual features of this sample
  r.slipping = trace.slipping;
  r.memory = tracker.visual_memory();
  r.health = tracker.health();
  r.press = tracker.press_evidence();
}

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
