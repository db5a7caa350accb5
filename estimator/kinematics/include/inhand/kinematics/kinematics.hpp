#pragma once
// Forward kinematics and translational point Jacobians of a HandModel, all in the palm frame P
// (the root link's frame). KinematicsData is sized once from the model; Update() and
// PointJacobian() allocate nothing.
#include <vector>

#include "inhand/core/hand_model.hpp"

namespace inhand {

class KinematicsData {
 public:
  explicit KinematicsData(const HandModel& model);

  // Computes every link pose T_PL for the configuration q (size model.num_q()).
  void Update(const HandModel& model, const Eigen::Ref<const Eigen::VectorXd>& q);

  const Transform& T_PL(int link) const { return T_PL_[link]; }
  const std::vector<Transform>& link_poses() const { return T_PL_; }
  // Joint axis (unit) and a point on it, in P, of the last Update().
  const Vec3& axis_P(int joint) const { return axis_P_[joint]; }
  const Vec3& origin_P(int joint) const { return origin_P_[joint]; }
  // Position of joint `joint` (mimic and fixed joints resolved) for the last Update().
  double joint_value(int joint) const { return value_[joint]; }

 private:
  std::vector<Transform> T_PL_;
  std::vector<Vec3> axis_P_;
  std::vector<Vec3> origin_P_;
  std::vector<double> value_;
};

// J (3 × num_q): velocity in P of the point p_P attached to link `link`, per unit q̇.
// Columns of joints outside the link's chain are zero; the root link's Jacobian is zero.
void PointJacobian(const HandModel& model, const KinematicsData& data, int link, const Vec3& p_P,
                   Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J);

}  // namespace inhand
