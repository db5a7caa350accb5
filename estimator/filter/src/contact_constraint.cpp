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
  if (params_.contact_normal_only) {
    H1_.noalias() = pair.normal_P.transpose() * H3_;
    const Eigen::Matrix<double, 1, 1> r1(pair.normal_P.dot(r));
    const Eigen::Matrix<double, 1, 1> R1(var);
    return Update<1>(r1, H1_, R1, params_.contact_gate_chi2, &rec.mahalanobis) == Outcome::kApplied;
  }
  const Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity() * var;
  return Update<3>(r, H3_, R3, params_.contact_gate_chi2, &rec.mahalanobis) == Outcome::kApplied;
}

}  // namespace inhand
