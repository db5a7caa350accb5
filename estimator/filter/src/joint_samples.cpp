#include "inhand/filter/joint_samples.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand {

RejectedJoint ScreenJointSample(const HandModel& hand, double limit_margin,
                                const Eigen::Ref<const Eigen::VectorXd>& q,
                                const Eigen::Ref<const Eigen::VectorXd>& tau) {
  for (int i = 0; i < hand.num_q(); ++i) {
    if (!std::isfinite(tau[i])) return {i, true};
    const double v = q[i];
    if (!std::isfinite(v)) return {i, false};
    const Joint& joint = hand.QJoint(i);
    const double lo = joint.has_limits ? joint.lower - limit_margin : -1000.0;
    const double hi = joint.has_limits ? joint.upper + limit_margin : 1000.0;
    if (v < lo || v > hi) return {i, false};
  }
  return {};
}

void ClampToLimits(const HandModel& hand, Eigen::Ref<Eigen::VectorXd> q) {
  for (int i = 0; i < hand.num_q(); ++i) {
    const Joint& joint = hand.QJoint(i);
    if (joint.has_limits) q[i] = std::clamp(q[i], joint.lower, joint.upper);
  }
}

void ValidateJointStiffness(const HandModel& hand) {
  const std::vector<double>& ks = hand.joint_stiffness;
  if (!ks.empty() && ks.size() != static_cast<std::size_t>(hand.num_q()))
    throw InputError("hand joint_stiffness: " + std::to_string(ks.size()) + " values for " +
                     std::to_string(hand.num_q()) + " joints, expected one per joint or none");
  for (std::size_t j = 0; j < ks.size(); ++j) {
    if (std::isfinite(ks[j]) && ks[j] >= 0.0) continue;
    std::ostringstream os;
    os << "hand joint_stiffness of joint '" << hand.QNames()[j] << "' is " << ks[j]
       << ", expected >= 0 N m/rad (0: rigid)";
    throw InputError(os.str());
  }
}

bool HasElasticJoints(const HandModel& hand) {
  return std::any_of(hand.joint_stiffness.begin(), hand.joint_stiffness.end(),
                     [](double k) { return k > 0.0; });
}

void Undeflect(const HandModel& hand, const Eigen::Ref<const Eigen::VectorXd>& tau,
               Eigen::Ref<Eigen::VectorXd> q) {
  for (int j = 0; j < q.size(); ++j) {
    const double k = hand.joint_stiffness[static_cast<std::size_t>(j)];
    if (k > 0.0) q[j] -= tau[j] / k;
  }
}

}  // namespace inhand
