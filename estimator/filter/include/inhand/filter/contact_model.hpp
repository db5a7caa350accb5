#pragma once
// The kinematic pieces of the paper's models (docs/estimator.md), as small testable functions.
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/so3.hpp"

namespace inhand {

using Mat36 = Eigen::Matrix<double, 3, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Pose a minus pose b in the filter's error state (δp, δθ), a = (p_b + δp, Exp(δθ) R_b).
Vec6 PoseError(const Transform& a, const Transform& b);

// A_i = G_iᵀ = [ I₃ , -[c - p]x ]: object twist (v, ω) → velocity of the object point c.
Mat36 GraspMapBlock(const Vec3& c_P, const Vec3& p_PO);

// Object twist from the finger motion at hard, non-slipping contacts: ν = A⁺ (J u), with
// A and J u stacked over contacts. Accumulates AᵀA and Aᵀ(J u) so no stacking is needed; the
// damped normal equations give the minimum-norm solution when contacts leave the twist
// under-determined (one contact, or collinear ones).
class TwistSolver {
 public:
  void Reset();
  void Add(const Mat36& A_i, const Vec3& finger_velocity_i);
  int count() const { return count_; }
  // ν = (AᵀA + μ I)⁻¹ Aᵀ b with μ = damping · (trace(AᵀA)/6 + 1e-12).
  Vec6 Solve(double damping) const;

 private:
  Mat6 AtA_ = Mat6::Zero();
  Vec6 Atb_ = Vec6::Zero();
  int count_ = 0;
};

// The contact measurement h = c_f - c_o and its Jacobian w.r.t. the error state
// δ = (δp, δθ, δb): H = [ -A_i(c_o) , J_f ] (J_f: 3×m point Jacobian of c_f on its link).
// H may have more columns (an augmented state); those are left as they are.
template <typename JacobianIn, typename JacobianOut>
void ContactMeasurementJacobian(const Vec3& c_o_P, const Vec3& p_PO, const JacobianIn& J_f,
                                JacobianOut& H) {
  H.template leftCols<6>() = -GraspMapBlock(c_o_P, p_PO);
  H.middleCols(6, J_f.cols()) = J_f;  // columns past the biases (camera error) untouched
}

// The pixel p̄ of an object point X (palm frame) seen by a camera at T_PC, differentiated w.r.t.
// the object pose error (δp, δθ): ∂p̄/∂δp = ∂p̄/∂X_C R_cᵀ, ∂p̄/∂δθ = -∂p̄/∂X_C R_cᵀ [X - p]x.
// (∂p̄/∂δb = 0.) X must lie in front of the camera.
Eigen::Matrix<double, 2, 6> VisualMeasurementJacobian(const Vec3& X_P, const Vec3& p_PO,
                                                      const Transform& T_PC, const Intrinsics& K);

// The same pixel differentiated w.r.t. an error (v, ω) of the camera pose, T_PC_true =
// T_PC Exp(v, ω) (the hand-eye calibration's error): X_C changes by -v + [X_C]x ω.
Eigen::Matrix<double, 2, 6> CameraPoseJacobian(const Vec3& X_P, const Transform& T_PC,
                                               const Intrinsics& K);

}  // namespace inhand
