// The constraint both kinds of contact apply (estimator-math.md, "Kinematic update"):
// h = c_f - c_o, z = 0, so r = c_o - c_f and H = [-A(c_o), J(c_f)] (zero for the camera
// error). Normal-only by default: a closest-point pair observes the distance along its normal,
// not where along the surface the contact sits.
#include "inhand/filter/filter.hpp"

namespace inhand {

bool Filter::ApplyContactConstraint(const ContactPair& pair, const Eigen::Matrix<double, 3, Eigen::Dynamic>& J_f,
                                    FilterTrace::Contact& rec) {
  const Vec3 r = pair.c_o_P - pair.c_f_P;
  ContactMeasurementJacobian(pair.c_o_P, s_.p, J_f, H3_);
  const double var = params_.contact_sigma * params_.contact_sigma;
  bool applied;
  if (params_.contact_normal_only) {
    H1_.noalias() = pair.normal_P.transpose() * H3_;
    const Eigen::Matrix<double, 1, 1> r1(pair.normal_P.dot(r));
    const Eigen::Matrix<double, 1, 1> R1(var);
    applied = Update<1>(r1, H1_, R1, params_.contact_gate_chi2, &rec.mahalanobis) == Outcome::kApplied;
  } else {
    const Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity() * var;
    applied = Update<3>(r, H3_, R3, params_.contact_gate_chi2, &rec.mahalanobis) == Outcome::kApplied;
    H1_.noalias() = pair.normal_P.transpose() * H3_;
  }
  if (applied) HoldModelVariance();
  return applied;
}

// The floor of contact_model_sigma along the normal distance the constraint measures, added in
// the pose directions only (h = the pose part of H1_): P += β h hᵀ with β chosen so that
// H1 P H1ᵀ = σ_m². Joint biases are left as the update made them.
void Filter::HoldModelVariance() {
  const double floor = params_.contact_model_sigma * params_.contact_model_sigma;
  if (!(floor > 0.0)) return;
  const Vec6 h = H1_.leftCols<6>().transpose();
  const double hh = h.squaredNorm();
  if (!(hh > 1e-12)) return;
  const double v = (H1_ * s_.P * H1_.transpose())(0, 0);
  if (!(v < floor)) return;
  const double beta = (floor - v) / (hh * hh);
  s_.P.topLeftCorner<6, 6>().noalias() += beta * h * h.transpose();
}

}  // namespace inhand
