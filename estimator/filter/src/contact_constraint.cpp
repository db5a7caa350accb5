// The constraint both kinds of contact apply (docs/estimator.md, "Contacts"):
// h = c_f - c_o, z = 0, so r = c_o - c_f and H = [-A(c_o), J(c_f)] (zero for the camera
// error). Normal-only by default: a closest-point pair observes the distance along its normal,
// not where along the surface the contact sits.
#include <cmath>

#include "inhand/filter/filter.hpp"

namespace inhand {

bool Filter::ApplyContactConstraint(const ContactPair& pair,
                                    const Eigen::Matrix<double, 3, Eigen::Dynamic>& J_f,
                                    FilterTrace::Contact& rec) {
  const Vec3 r = pair.c_o_P - pair.c_f_P;
  ContactMeasurementJacobian(pair.c_o_P, s_.p, J_f, H3_);
  const double var = params_.contact_sigma * params_.contact_sigma;
  if (params_.contact_normal_only) {
    H1_.noalias() = pair.normal_P.transpose() * H3_;
    const Eigen::Matrix<double, 1, 1> r1(pair.normal_P.dot(r));
    const Eigen::Matrix<double, 1, 1> R1(var);
    if (Update<1>(r1, H1_, R1, params_.contact_gate_chi2, &rec.mahalanobis) != Outcome::kApplied)
      return false;
    CapContactInformation(var);
    return true;
  }
  const Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity() * var;
  return Update<3>(r, H3_, R3, params_.contact_gate_chi2, &rec.mahalanobis) == Outcome::kApplied;
}

// contact_model_sigma: the variance along what the constraint measures (the normal distance) may
// not fall below σ_m² through contact constraints. The update just removed (HP)ᵀ(HP)/S from P
// (HP: H times the prior P, which Update left in HP1_); as much of it as needed is given back, in
// the directions it was taken from (pose and joint biases alike), never more than it took: a pose
// known better from elsewhere (tags, the start) keeps what it knew.
void Filter::CapContactInformation(double var) {
  const double floor = params_.contact_model_sigma * params_.contact_model_sigma;
  if (!(floor > 0.0)) return;
  const double v_before = HP1_.dot(H1_);
  const double S = v_before + var;
  const double v_after = v_before - v_before * v_before / S;
  if (!(v_after < floor) || !(v_before > v_after)) return;
  const double alpha = std::min(1.0, (floor - v_after) / (v_before - v_after));
  HP1_ *= std::sqrt(alpha / S);  // scratch: scaled in place so that the sum stays exactly symmetric
  s_.P.noalias() += HP1_.transpose() * HP1_;
}

}  // namespace inhand
