#include "inhand/filter/filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/core/error.hpp"

namespace inhand {

const char* ContactKindName(ContactKind kind) {
  switch (kind) {
    case ContactKind::kKinematic: return "kinematic";
    case ContactKind::kTorque: return "torque";
    case ContactKind::kRejectedCone: return "rejected_cone";
    case ContactKind::kRejectedForce: return "rejected_force";
    case ContactKind::kCandidate: return "candidate";
  }
  return "?";
}

void FilterTrace::Clear() {
  contacts.clear();
  visual.clear();
  prediction_contacts = 0;
  predicted_twist.setZero();
  num_constraints = 0;
  num_gated = 0;
  numeric_events = 0;
  slipping = false;
}

Filter::Filter(const HandModel& hand, ContactQuery& contacts, const FilterParams& params, bool use_torque)
    : hand_(hand),
      contacts_(contacts),
      params_(params),
      use_torque_(use_torque),
      m_(hand.num_q()),
      n_(6 + hand.num_q()),
      b_(Eigen::VectorXd::Zero(m_)),
      P_(Eigen::MatrixXd::Identity(n_, n_)),
      delta_(Eigen::VectorXd::Zero(n_)),
      q_prev_(Eigen::VectorXd::Zero(m_)),
      q_eff_(Eigen::VectorXd::Zero(m_)),
      kin_(hand),
      J_(3, m_), H3_(3, n_), HP3_(3, n_), SKt3_(3, n_), K3_(n_, 3),
      H2_(2, n_), HP2_(2, n_), SKt2_(2, n_), K2_(n_, 2),
      H1_(1, n_), HP1_(1, n_), SKt1_(1, n_), K1_(n_, 1),
      JtJ_(m_, m_), y_(m_), dq_(m_), ldlt_(m_) {
  params_.Validate();
  camera_state_ = params_.camera_position_sigma > 0.0 || params_.camera_orientation_sigma > 0.0;
  Pxc_.setZero(n_, 6);
  const std::size_t links = hand.links.size();
  pairs_.reserve(links);
  active_.reserve(links);
  Jc_.assign(links, Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, m_));
  inv_weight_.reserve(links);
  finger_nearest_.assign(hand.joints.size(), 0.0);
  trace_.contacts.reserve(links * static_cast<std::size_t>(params_.contact_iterations));
  trace_.visual.reserve(512);
}

void Filter::Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
                   double sigma_position, double sigma_orientation, double sigma_bias) {
  Reset(T_PO, q_meas, sigma_position, sigma_orientation, Eigen::VectorXd::Constant(m_, sigma_bias));
}

void Filter::Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
                   double sigma_position, double sigma_orientation,
                   const Eigen::Ref<const Eigen::VectorXd>& sigma_bias) {
  INHAND_CHECK(q_meas.size() == m_ && sigma_bias.size() == m_, "joint vector size does not match the hand");
  p_ = T_PO.translation();
  R_ = Orthonormalize(T_PO.linear());
  b_.setZero();
  delta_.setZero();
  P_.setZero();
  P_.diagonal().head<3>().setConstant(sigma_position * sigma_position);
  P_.diagonal().segment<3>(3).setConstant(sigma_orientation * sigma_orientation);
  P_.diagonal().tail(m_) = sigma_bias.array().square().matrix();
  q_prev_ = q_meas;
  have_prev_ = true;
  q_eff_ = q_meas;
  kin_.Update(hand_, q_eff_);
  active_.clear();
  trace_.Clear();
  grip_ = max_grip_ = 0.0;
  xi_.setZero();
  dxi_.setZero();
  Pxc_.setZero();
  Pcc_.setZero();
  Pcc_.diagonal().head<3>().setConstant(params_.camera_position_sigma * params_.camera_position_sigma);
  Pcc_.diagonal().tail<3>().setConstant(params_.camera_orientation_sigma * params_.camera_orientation_sigma);
}

Transform Filter::T_PO() const { return MakeTransform(p_, R_); }

void Filter::Predict(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt) {
  INHAND_CHECK(q_meas.size() == m_, "joint vector size does not match the hand");
  trace_.Clear();
  if (!have_prev_) {
    q_prev_ = q_meas;
    have_prev_ = true;
  }
  dq_ = q_meas - q_prev_;
  // Hard-finger, non-slipping contacts: A ν = J Δq (kin_ holds the previous configuration).
  twist_.Reset();
  for (const Active& a : active_) {
    const Vec3 c_P = kin_.T_PL(a.link) * a.c_f_L;
    PointJacobian(hand_, kin_, a.link, c_P, J_);
    const Vec3 finger_motion = J_ * dq_;
    twist_.Add(GraspMapBlock(c_P, p_), finger_motion);
  }
  const Vec6 nu = twist_.Solve(params_.twist_damping);
  p_ += nu.head<3>();
  R_ = ExpSO3(nu.tail<3>()) * R_;
  trace_.predicted_twist = nu;
  trace_.prediction_contacts = twist_.count();

  // Process noise: a random walk plus a share of the predicted motion (rolling and slipping
  // are not modelled). F = I to first order, as in the paper.
  const double dtp = std::max(dt, 0.0);
  // Only once the object has been held: before the grasp nothing holds it, but nothing moves it.
  const bool slipping = use_torque_ && params_.slip_torque > 0.0 && max_grip_ >= params_.slip_torque &&
                        grip_ < params_.slip_torque;
  const double walk = slipping ? params_.slip_scale * params_.slip_scale : 1.0;
  trace_.slipping = slipping;
  const double sp = walk * params_.process_position * params_.process_position * dtp +
                    std::pow(params_.motion_position * nu.head<3>().norm(), 2);
  const double so = walk * params_.process_orientation * params_.process_orientation * dtp +
                    std::pow(params_.motion_orientation * nu.tail<3>().norm(), 2);
  P_.diagonal().head<3>().array() += sp;
  P_.diagonal().segment<3>(3).array() += so;
  P_.diagonal().tail(m_).array() += params_.process_bias * params_.process_bias * dtp;
  q_prev_ = q_meas;
}

template <int D>
bool Filter::UpdateBlock(const Eigen::Matrix<double, D, 1>& r_in, const Eigen::Matrix<double, D, Eigen::Dynamic>& H,
                         const Eigen::Matrix<double, D, D>& R, double gate_chi2, double* mahalanobis) {
  Eigen::Matrix<double, D, Eigen::Dynamic>* HP;
  Eigen::Matrix<double, D, Eigen::Dynamic>* SKt;
  Eigen::Matrix<double, Eigen::Dynamic, D>* K;
  if constexpr (D == 3) {
    HP = &HP3_, SKt = &SKt3_, K = &K3_;
  } else if constexpr (D == 2) {
    HP = &HP2_, SKt = &SKt2_, K = &K2_;
  } else {
    static_assert(D == 1, "blocks of 1, 2 or 3 rows");
    HP = &HP1_, SKt = &SKt1_, K = &K1_;
  }
  // Sequential processing: account for the correction not yet applied.
  Eigen::Matrix<double, D, 1> r = r_in;
  r.noalias() -= H * delta_;
  HP->noalias() = H * P_;
  Eigen::Matrix<double, D, D> S = R;
  S.noalias() += *HP * H.transpose();
  const Eigen::LDLT<Eigen::Matrix<double, D, D>> ldlt(S);
  if (!r.allFinite() || !S.allFinite() || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-300) {
    ++trace_.numeric_events;
    return false;
  }
  const Eigen::Matrix<double, D, 1> Sinv_r = ldlt.solve(r);
  const double m2 = r.dot(Sinv_r);
  if (mahalanobis) *mahalanobis = m2;
  if (gate_chi2 > 0.0 && m2 > gate_chi2) {
    ++trace_.num_gated;
    return false;
  }
  const Eigen::Matrix<double, D, D> Sinv = ldlt.solve(Eigen::Matrix<double, D, D>::Identity());
  K->noalias() = HP->transpose() * Sinv;
  delta_.noalias() += *K * r;
  if (camera_state_) {
    // The camera error is not measured here (H has no columns for it) but moves with what it is
    // correlated with: its gain Kc = (H Pxc)ᵀ S⁻¹.
    Eigen::Matrix<double, D, 6> HC;
    HC.noalias() = H * Pxc_;
    const Eigen::Matrix<double, 6, D> Kc = HC.transpose() * Sinv;
    dxi_.noalias() += Kc * r;
    Pcc_.noalias() -= Kc * HC;
    Pcc_ = (0.5 * (Pcc_ + Pcc_.transpose())).eval();
    Pxc_.noalias() -= *K * HC;
  }
  // Joseph form, expanded: (I-KH)P(I-KH)ᵀ + KRKᵀ = P - K(HP) - (HP)ᵀKᵀ + K S Kᵀ.
  P_.noalias() -= *K * *HP;
  P_.noalias() -= HP->transpose() * K->transpose();
  SKt->noalias() = S * K->transpose();
  P_.noalias() += *K * *SKt;
  for (int i = 0; i < n_; ++i)
    for (int j = i + 1; j < n_; ++j) P_(i, j) = P_(j, i) = 0.5 * (P_(i, j) + P_(j, i));
  return true;
}

template bool Filter::UpdateBlock<1>(const Eigen::Matrix<double, 1, 1>&, const Eigen::Matrix<double, 1, Eigen::Dynamic>&,
                                     const Eigen::Matrix<double, 1, 1>&, double, double*);
template bool Filter::UpdateBlock<2>(const Eigen::Matrix<double, 2, 1>&, const Eigen::Matrix<double, 2, Eigen::Dynamic>&,
                                     const Eigen::Matrix<double, 2, 2>&, double, double*);
template bool Filter::UpdateBlock<3>(const Eigen::Matrix<double, 3, 1>&, const Eigen::Matrix<double, 3, Eigen::Dynamic>&,
                                     const Eigen::Matrix<double, 3, 3>&, double, double*);

void Filter::Commit() {
  p_ += delta_.head<3>();
  R_ = ExpSO3(delta_.segment<3>(3)) * R_;
  R_ = Quat(R_).normalized().toRotationMatrix();  // keep R on SO(3) against rounding drift
  b_ += delta_.tail(m_);
  delta_.setZero();
  xi_ += dxi_;
  dxi_.setZero();
}

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
  std::fill(finger_nearest_.begin(), finger_nearest_.end(), std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < k; ++i)
    if (const int f = finger(i); f >= 0) finger_nearest_[f] = std::min(finger_nearest_[f], std::max(pairs_[i].distance, 0.0));
  for (std::size_t i = 0; i < k; ++i)
    if (const int f = finger(i); f >= 0) inv_weight_[i] = CandidateWeight(finger_nearest_[f]) / CandidateWeight(pairs_[i].distance);
}

void Filter::ContactStep(const Eigen::Ref<const Eigen::VectorXd>& tau, int iteration) {
  q_eff_ = q_prev_ + b_;
  kin_.Update(hand_, q_eff_);
  const double reach = std::max(use_torque_ ? params_.torque_candidate_distance : 0.0,
                                params_.prediction_contact_distance);
  contacts_.Query(kin_.link_poses(), T_PO(), reach, pairs_);

  // Torque contacts: λ̄ = (J_cᵀ)⁺ τ over all candidates = J_c (J_cᵀ J_c + μ I)⁻¹ τ.
  const std::size_t k = pairs_.size();
  for (std::size_t i = 0; i < k; ++i) PointJacobian(hand_, kin_, pairs_[i].link, pairs_[i].c_f_P, Jc_[i]);
  const bool torque = use_torque_ && k > 0;
  if (torque) {
    ComputeCandidateWeights();
    JtJ_.setZero();
    for (std::size_t i = 0; i < k; ++i) JtJ_.noalias() += inv_weight_[i] * (Jc_[i].transpose() * Jc_[i]);
    JtJ_.diagonal().array() += params_.torque_damping;
    ldlt_.compute(JtJ_);
    y_ = ldlt_.solve(tau);
  }
  const double cos_cone = std::cos(params_.friction_cone_deg * M_PI / 180.0);
  const Eigen::Matrix3d Rc = Eigen::Matrix3d::Identity() * (params_.contact_sigma * params_.contact_sigma);
  if (iteration == 0) active_.clear();
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
    if (torque) rec.force_P = inv_weight_[i] * (Jc_[i] * y_);
    if (pair.distance < 0.0) {
      rec.kind = ContactKind::kKinematic;
    } else if (torque) {
      const double f = rec.force_P.norm();
      if (f < params_.force_min) rec.kind = ContactKind::kRejectedForce;
      else if (rec.force_P.dot(pair.normal_P) < f * cos_cone) rec.kind = ContactKind::kRejectedCone;
      else rec.kind = ContactKind::kTorque;
    }
    const bool constraint = rec.kind == ContactKind::kKinematic || rec.kind == ContactKind::kTorque;
    if (constraint) {
      // h = c_f - c_o, z = 0: r = c_o - c_f; H = [-A(c_o), J(c_f)].
      const Vec3 r = pair.c_o_P - pair.c_f_P;
      ContactMeasurementJacobian(pair.c_o_P, p_, Jc_[i], H3_);
      bool applied;
      if (params_.contact_normal_only) {
        H1_.noalias() = pair.normal_P.transpose() * H3_;
        const Eigen::Matrix<double, 1, 1> r1(pair.normal_P.dot(r));
        const Eigen::Matrix<double, 1, 1> R1(params_.contact_sigma * params_.contact_sigma);
        applied = UpdateBlock<1>(r1, H1_, R1, params_.contact_gate_chi2, &rec.mahalanobis);
      } else {
        applied = UpdateBlock<3>(r, H3_, Rc, params_.contact_gate_chi2, &rec.mahalanobis);
      }
      rec.gated = !applied;
      trace_.num_constraints += applied;
    }
    if (iteration == 0 && (constraint || pair.distance <= params_.prediction_contact_distance))
      active_.push_back({pair.link, kin_.T_PL(pair.link).inverse() * pair.c_f_P});
    trace_.contacts.push_back(rec);
  }
}

void Filter::UpdateContacts(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  INHAND_CHECK(tau.size() == m_, "torque vector size does not match the hand");
  for (int it = 0; it < params_.contact_iterations; ++it) {
    const int before = trace_.num_constraints;
    ContactStep(tau, it);
    Commit();
    if (trace_.num_constraints == before) break;  // nothing left to resolve
  }
  // The grip, from the torques alone (not from contacts at the estimate, which vanish when the
  // estimate drifts away and would then feed the drift).
  grip_ = tau.cwiseAbs().sum();
  max_grip_ = std::max(max_grip_, grip_);
  q_eff_ = q_prev_ + b_;
  kin_.Update(hand_, q_eff_);
}

int Filter::UpdateVisual(const std::vector<VisualFeature>& features, const Transform& T_PC_recorded, const Intrinsics& K) {
  // With a camera σ the camera pose's error ξ is a state: every feature is fused one by one as
  // in the paper, gated against what the features before it showed, and ξ, shared by all of
  // them and by every frame, keeps a common error from being counted once per feature.
  const int na = camera_state_ ? n_ + 6 : n_;
  const Transform T_PC = camera_state_ ? Transform(T_PC_recorded * MakeTransform(xi_.head<3>(), ExpSO3(xi_.tail<3>())))
                                       : T_PC_recorded;
  const Mat3 Rc_T = T_PC.linear().transpose();
  const Eigen::Matrix2d Rv = Eigen::Matrix2d::Identity() * (params_.pixel_sigma * params_.pixel_sigma);
  Eigen::MatrixXd Pa(na, na);
  Pa.topLeftCorner(n_, n_) = P_;
  Eigen::VectorXd da(na);
  da.head(n_) = delta_;
  if (camera_state_) {
    Pa.topRightCorner(n_, 6) = Pxc_;
    Pa.bottomLeftCorner(6, n_) = Pxc_.transpose();
    Pa.bottomRightCorner<6, 6>() = Pcc_;
    da.tail<6>() = dxi_;
  }
  Eigen::Matrix<double, 2, Eigen::Dynamic> Ha(2, na), HP(2, na);
  int used = 0;
  for (const VisualFeature& f : features) {
    FilterTrace::Visual rec;
    rec.id = f.id;
    rec.measured = f.pixel;
    const Vec3 X = p_ + R_ * f.x_O;
    const Vec3 X_C = Rc_T * (X - T_PC.translation());
    if (!(X_C.z() > 1e-6)) {
      ++trace_.numeric_events;
      rec.gated = true;
      trace_.visual.push_back(rec);
      continue;
    }
    rec.predicted = K.Project(X_C);
    Ha.setZero();
    Ha.leftCols<6>() = VisualMeasurementJacobian(X, p_, T_PC, K);
    if (camera_state_) Ha.rightCols<6>() = CameraPoseJacobian(X, T_PC, K);
    const Eigen::Vector2d r = f.pixel - rec.predicted - Ha * da;
    HP.noalias() = Ha * Pa;
    const Eigen::Matrix2d S = HP * Ha.transpose() + Rv;
    const Eigen::LDLT<Eigen::Matrix2d> ldlt(S);
    rec.mahalanobis = r.dot(ldlt.solve(r));
    rec.gated = !(std::isfinite(rec.mahalanobis) && ldlt.isPositive()) ||
                (params_.visual_gate_chi2 > 0.0 && rec.mahalanobis > params_.visual_gate_chi2);
    if (rec.gated) {
      ++trace_.num_gated;
    } else {
      const Eigen::Matrix<double, Eigen::Dynamic, 2> Kg = ldlt.solve(HP).transpose();
      da.noalias() += Kg * r;
      // Joseph form, expanded as in UpdateBlock.
      Pa.noalias() -= Kg * HP;
      Pa.noalias() -= HP.transpose() * Kg.transpose();
      Pa.noalias() += Kg * (S * Kg.transpose());
      Pa = 0.5 * (Pa + Pa.transpose()).eval();
      ++used;
    }
    trace_.visual.push_back(rec);
  }
  P_ = Pa.topLeftCorner(n_, n_);
  delta_ = da.head(n_);
  if (camera_state_) {
    Pxc_ = Pa.topRightCorner(n_, 6);
    Pcc_ = Pa.bottomRightCorner<6, 6>();
    dxi_ = da.tail<6>();
  }
  Commit();
  q_eff_ = q_prev_ + b_;
  kin_.Update(hand_, q_eff_);
  return used;
}

}  // namespace inhand
