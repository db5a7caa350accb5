// Torque contacts (paper Sec. III-B): a link near the object whose share of the measured joint
// torques pushes into the object, inside the friction cone and above a minimum force, touches
// it. λ̄ = (J_cᵀ)⁺ τ over all candidates, weighted towards each finger's nearest links.
#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/filter/filter.hpp"

namespace inhand {

double Filter::CandidateWeight(double distance) const {
  if (params_.torque_distance_scale <= 0.0) return 1.0;  // the paper: plain (J_cᵀ)⁺
  const double d = std::max(distance, 0.0) / params_.torque_distance_scale;
  return 1.0 + d * d;
}

// Relative to the nearest candidate on the same finger (the candidates whose joint chains start
// at the same joint): scaling one finger's weights leaves its forces unchanged but for how the
// damping acts, so a finger's nearest candidate keeps the paper's pseudo-inverse (a lone
// candidate 2 mm away gets the paper's force), and only its farther links are discounted.
void Filter::ComputeCandidateWeights() {
  const std::size_t k = pairs_.size();
  inv_weight_.assign(k, 1.0);
  if (params_.torque_distance_scale <= 0.0) return;
  const auto finger = [&](std::size_t i) {
    const std::vector<int>& chain = hand_.support[static_cast<std::size_t>(pairs_[i].link)];
    return chain.empty() ? -1 : chain.front();
  };
  std::fill(finger_nearest_.begin(), finger_nearest_.end(),
            std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < k; ++i)
    if (const int f = finger(i); f >= 0)
      finger_nearest_[f] = std::min(finger_nearest_[f], std::max(pairs_[i].distance, 0.0));
  for (std::size_t i = 0; i < k; ++i)
    if (const int f = finger(i); f >= 0)
      inv_weight_[i] = CandidateWeight(finger_nearest_[f]) / CandidateWeight(pairs_[i].distance);
}

// λ̄_i = w_i⁻¹ J_i (Σ w_j⁻¹ J_jᵀ J_j + μ I)⁻¹ τ: the weighted, damped (J_cᵀ)⁺ τ.
void Filter::EstimateContactForces(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  torque_forces_ = options_.use_torque && !pairs_.empty();
  if (!torque_forces_) return;
  if (!tau.allFinite()) {  // no torque contacts from torques that are not numbers
    torque_forces_ = false;
    ++s_.trace.numeric_events;
    return;
  }
  ComputeCandidateWeights();
  JtJ_.setZero();
  for (std::size_t i = 0; i < pairs_.size(); ++i)
    JtJ_.noalias() += inv_weight_[i] * (Jc_[i].transpose() * Jc_[i]);
  JtJ_.diagonal().array() += params_.torque_damping;
  ldlt_.compute(JtJ_);
  y_ = ldlt_.solve(tau);
  if (!y_.allFinite()) {
    torque_forces_ = false;
    ++s_.trace.numeric_events;
  }
}

ContactKind Filter::ClassifyTorqueContact(std::size_t i, FilterTrace::Contact& rec) const {
  rec.force_P = inv_weight_[i] * (Jc_[i] * y_);
  const double f = rec.force_P.norm();
  const double cos_cone = std::cos(params_.friction_cone_deg * M_PI / 180.0);
  if (f < params_.force_min) return ContactKind::kRejectedForce;
  if (rec.force_P.dot(pairs_[i].normal_P) < f * cos_cone) return ContactKind::kRejectedCone;
  return ContactKind::kTorque;
}

}  // namespace inhand
