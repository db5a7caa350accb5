#pragma once
// A joint sample as the filter must see it. Samples that no hand can produce are screened out
// before they reach it; an elastic joint's encoder reads the motor side, so the link stands at
// q − τ / k; encoders that overshoot their URDF limits may be clamped into them.
#include <Eigen/Core>

#include "inhand/core/hand_model.hpp"

namespace inhand {

// The first joint (configuration index) whose sample must not be fused, or -1: a position or a
// torque that is not a number, or a position beyond its URDF limits by more than
// `limit_margin` (rad or m; joints without limits: beyond ±1000). `torque` tells whether it is
// the torque rather than the position.
struct RejectedJoint {
  int joint = -1;
  bool torque = false;
};
RejectedJoint ScreenJointSample(const HandModel& hand, double limit_margin,
                                const Eigen::Ref<const Eigen::VectorXd>& q,
                                const Eigen::Ref<const Eigen::VectorXd>& tau);

// Clamps every joint with limits into them.
void ClampToLimits(const HandModel& hand, Eigen::Ref<Eigen::VectorXd> q);

// Throws InputError unless HandModel::joint_stiffness is empty or one finite value >= 0 per
// joint (0: rigid).
void ValidateJointStiffness(const HandModel& hand);
// Whether any joint is elastic (stiffness > 0).
bool HasElasticJoints(const HandModel& hand);
// The links' positions from the encoders' under the external torques τ: q − τ / k for every
// elastic joint (τ finite: ScreenJointSample refuses it otherwise).
void Undeflect(const HandModel& hand, const Eigen::Ref<const Eigen::VectorXd>& tau,
               Eigen::Ref<Eigen::VectorXd> q);

}  // namespace inhand
