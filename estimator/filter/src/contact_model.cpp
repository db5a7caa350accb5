#include "inhand/filter/contact_model.hpp"

#include <Eigen/Cholesky>

namespace inhand {

Vec6 PoseError(const Transform& a, const Transform& b) {
  Vec6 e;
  e.head<3>() = a.translation() - b.translation();
  e.tail<3>() = LogSO3(a.linear() * b.linear().transpose());
  return e;
}

Mat36 GraspMapBlock(const Vec3& c_P, const Vec3& p_PO) {
  Mat36 A;
  A.leftCols<3>().setIdentity();
  A.rightCols<3>() = -Skew(c_P - p_PO);
  return A;
}

void TwistSolver::Reset() {
  AtA_.setZero();
  Atb_.setZero();
  count_ = 0;
}

void TwistSolver::Add(const Mat36& A_i, const Vec3& finger_velocity_i) {
  AtA_.noalias() += A_i.transpose() * A_i;
  Atb_.noalias() += A_i.transpose() * finger_velocity_i;
  ++count_;
}

Vec6 TwistSolver::Solve(double damping) const {
  if (count_ == 0) return Vec6::Zero();
  const double mu = damping * (AtA_.trace() / 6.0 + 1e-12);
  return (AtA_ + mu * Mat6::Identity()).ldlt().solve(Atb_);
}

Eigen::Matrix<double, 2, 6> VisualMeasurementJacobian(const Vec3& X_P, const Vec3& p_PO,
                                                      const Transform& T_PC, const Intrinsics& K) {
  const Mat3 Rc_T = T_PC.linear().transpose();
  const Eigen::Matrix<double, 2, 3> Jx =
      K.ProjectJacobian(Rc_T * (X_P - T_PC.translation())) * Rc_T;
  Eigen::Matrix<double, 2, 6> H;
  H.leftCols<3>() = Jx;
  H.rightCols<3>() = -Jx * Skew(X_P - p_PO);
  return H;
}

Eigen::Matrix<double, 2, 6> CameraPoseJacobian(const Vec3& X_P, const Transform& T_PC,
                                               const Intrinsics& K) {
  const Vec3 X_C = T_PC.linear().transpose() * (X_P - T_PC.translation());
  const Eigen::Matrix<double, 2, 3> Jp = K.ProjectJacobian(X_C);
  Eigen::Matrix<double, 2, 6> C;
  C.leftCols<3>() = -Jp;
  C.rightCols<3>() = Jp * Skew(X_C);
  return C;
}

}  // namespace inhand
