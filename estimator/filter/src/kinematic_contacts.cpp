// Kinematic contacts (docs/estimator.md, "Contacts"): every link that penetrates the
// object at the estimate is a zero-distance constraint. This file runs the contact step: query
// the pairs at the estimate, classify each (penetrating here, torque-confirmed in
// torque_contacts.cpp), apply the constraints (contact_constraint.cpp) and keep the contacts
// that move the object in the next Predict.
#include <algorithm>

#include "inhand/core/error.hpp"
#include "inhand/filter/filter.hpp"

namespace inhand {

void Filter::ContactStep(const Eigen::Ref<const Eigen::VectorXd>& tau, int iteration) {
  RefreshKinematics();
  const double reach = std::max(options_.use_torque ? params_.torque_candidate_distance : 0.0,
                                params_.prediction_contact_distance);
  contacts_.Query(kin_.link_poses(), T_PO(), reach, pairs_);
  const std::size_t k = pairs_.size();
  s_.trace.penetration = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    PointJacobian(hand_, kin_, pairs_[i].link, pairs_[i].c_f_P, Jc_[i]);
    s_.trace.penetration = std::max(s_.trace.penetration, -pairs_[i].distance);
  }
  EstimateContactForces(tau);
  // (J_wᵀJ_w + μI) y = τ, so what the candidates leave of τ is μ y.
  s_.trace.unexplained_torque = 0.0;
  if (options_.use_torque && tau.allFinite())
    s_.trace.unexplained_torque = torque_forces_ ? params_.torque_damping * y_.cwiseAbs().maxCoeff()
                                                 : tau.cwiseAbs().maxCoeff();
  if (iteration == 0) s_.active.clear();
  for (std::size_t i = 0; i < k; ++i) {
    const ContactPair& pair = pairs_[i];
    FilterTrace::Contact rec;
    rec.link = pair.link;
    rec.piece = pair.piece;
    rec.iteration = iteration;
    rec.distance = pair.distance;
    rec.c_o_P = pair.c_o_P;
    rec.c_f_P = pair.c_f_P;
    rec.normal_P = pair.normal_P;
    if (pair.distance < 0.0) {
      rec.kind = ContactKind::kKinematic;
      if (torque_forces_) rec.force_P = inv_weight_[i] * (Jc_[i] * y_);
    } else if (torque_forces_) {
      rec.kind = ClassifyTorqueContact(i, rec);
    }
    const bool constraint = rec.kind == ContactKind::kKinematic || rec.kind == ContactKind::kTorque;
    if (constraint) {
      rec.gated = !ApplyContactConstraint(pair, Jc_[i], rec);
      s_.trace.num_constraints += !rec.gated;
    }
    if (iteration == 0 && (constraint || pair.distance <= params_.prediction_contact_distance))
      s_.active.push_back({pair.link, kin_.T_PL(pair.link).inverse() * pair.c_f_P});
    s_.trace.contacts.push_back(rec);
  }
}

void Filter::UpdateContacts(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  INHAND_CHECK(tau.size() == m_, "torque vector size does not match the hand");
  for (int it = 0; it < params_.contact_iterations; ++it) {
    const int before = s_.trace.num_constraints;
    ContactStep(tau, it);
    Commit();
    if (s_.trace.num_constraints == before) break;  // nothing left to resolve
  }
  // The grip, from the torques alone (not from contacts at the estimate, which vanish when the
  // estimate drifts away and would then feed the drift).
  if (tau.allFinite()) {
    s_.grip = tau.cwiseAbs().sum();
    s_.max_grip = std::max(s_.max_grip, s_.grip);
  }
  RefreshKinematics();
}

}  // namespace inhand
