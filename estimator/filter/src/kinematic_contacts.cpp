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
  KeepPushDirections();
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

// A link inside the object is pushed out the way it was pushed at the last step while it stays
// inside: it cannot have crossed the object's middle in one step. Where the link straddles that
// middle (a palm 12 mm deep across a bottle), the field's normal flips from one step to
// the next as the estimate moves by a fraction of a millimetre, the pushes cancel, and the link
// stayed inside for the rest of the run (hard shampoo seed 311). The kept direction replaces a
// new one that opposes it; the depth is the field's.
void Filter::KeepPushDirections() {
  std::fill(penetrating_.begin(), penetrating_.end(), 0);
  for (ContactPair& pair : pairs_) {
    if (!(pair.distance < 0.0)) continue;
    const auto l = static_cast<std::size_t>(pair.link);
    Vec3& kept = s_.push_O[l];
    const Vec3 n_O = s_.R.transpose() * pair.normal_P;
    if (kept.dot(n_O) < 0.0) {
      pair.normal_P = s_.R * kept;
      pair.c_o_P = pair.c_f_P + pair.distance * pair.normal_P;
    } else {
      kept = n_O;
    }
    penetrating_[l] = 1;
  }
  for (std::size_t l = 0; l < penetrating_.size(); ++l)
    if (!penetrating_[l]) s_.push_O[l].setZero();
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
