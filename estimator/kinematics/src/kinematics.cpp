#include "inhand/kinematics/kinematics.hpp"

#include "inhand/core/error.hpp"

namespace inhand {

KinematicsData::KinematicsData(const HandModel& model)
    : T_PL_(model.links.size(), Transform::Identity()),
      axis_P_(model.joints.size(), Vec3::UnitZ()),
      origin_P_(model.joints.size(), Vec3::Zero()),
      value_(model.joints.size(), 0.0) {}

void KinematicsData::Update(const HandModel& model, const Eigen::Ref<const Eigen::VectorXd>& q) {
  INHAND_CHECK(q.size() == model.num_q(), "configuration size does not match the hand model");
  T_PL_[model.root_link].setIdentity();
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const Transform T_PJ = T_PL_[joint.parent_link] * joint.T_LJ;
    axis_P_[j] = T_PJ.linear() * joint.axis;
    origin_P_[j] = T_PJ.translation();
    double value = 0.0;
    if (joint.q_index >= 0) value = joint.multiplier * q[joint.q_index] + joint.offset;
    value_[j] = value;
    Transform& T_PC = T_PL_[joint.child_link];
    switch (joint.type) {
      case JointType::kRevolute:
      case JointType::kContinuous:
        T_PC.linear() = T_PJ.linear() * Eigen::AngleAxisd(value, joint.axis).toRotationMatrix();
        T_PC.translation() = T_PJ.translation();
        break;
      case JointType::kPrismatic:
        T_PC.linear() = T_PJ.linear();
        T_PC.translation() = T_PJ.translation() + value * axis_P_[j];
        break;
      case JointType::kFixed:
        T_PC = T_PJ;
        break;
    }
  }
}

void PointJacobian(const HandModel& model, const KinematicsData& data, int link, const Vec3& p_P,
                   Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J) {
  J.setZero();
  for (int j : model.support[link]) {
    const Joint& joint = model.joints[j];
    Vec3 column;
    if (joint.type == JointType::kPrismatic) {
      column = data.axis_P(j);
    } else {
      column = data.axis_P(j).cross(p_P - data.origin_P(j));
    }
    J.col(joint.q_index) += joint.multiplier * column;
  }
}

}  // namespace inhand
