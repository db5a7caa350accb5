// The filter's core: start, prediction, the generic block update and the retraction. The
// measurement sources that feed the update live in their own files (filter.hpp lists them).
#include "inhand/filter/filter.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "inhand/core/error.hpp"

namespace inhand {

const char* ContactKindName(ContactKind kind) {
  switch (kind) {
    case ContactKind::kKinematic:
      return "kinematic";
    case ContactKind::kTorque:
      return "torque";
    case ContactKind::kRejectedCone:
      return "rejected_cone";
    case ContactKind::kRejectedForce:
      return "rejected_force";
    case ContactKind::kCandidate:
      return "candidate";
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
  penetration = 0.0;
  unexplained_torque = 0.0;
}

Filter::Filter(const HandModel& hand, ContactQuery& contacts, const FilterParams& params,
               const FilterOptions& options)
    : hand_(hand),
      contacts_(contacts),
      params_(params),
      options_(options),
      m_(hand.num_q()),
      n_(6 + hand.num_q()),
      kin_(hand) {
  params_.Validate();
  const Mat3& G = options_.gyration_O;
  if (!G.isZero(0.0)) {
    if (!G.allFinite() || !G.isApprox(G.transpose(), 1e-9) ||
        Eigen::SelfAdjointEigenSolver<Mat3>(G).eigenvalues().minCoeff() <= 0.0)
      throw InputError(
          "filter options: the object's gyration tensor must be symmetric positive definite");
    gyration_inv_O_ = G.inverse();
    travel_ = params_.travel_orientation > 0.0;
  }
  camera_state_ = params_.camera_position_sigma > 0.0 || params_.camera_orientation_sigma > 0.0;
  na_ = camera_state_ ? n_ + 6 : n_;
  s_.b = Eigen::VectorXd::Zero(m_);
  s_.P = Eigen::MatrixXd::Identity(na_, na_);
  Pn_ = s_.P;
  delta_saved_ = Eigen::VectorXd::Zero(na_);
  s_.q_prev = Eigen::VectorXd::Zero(m_);
  s_.q_window = Eigen::VectorXd::Zero(m_);
  s_.q_eff = Eigen::VectorXd::Zero(m_);
  s_.push_O.assign(hand.links.size(), Vec3::Zero());
  penetrating_.assign(hand.links.size(), 0);
  delta_ = Eigen::VectorXd::Zero(na_);
  J_.setZero(3, m_);
  // Columns a source does not see stay zero (the contacts never touch the camera's).
  H3_.setZero(3, na_), HP3_.setZero(3, na_), SKt3_.setZero(3, na_), K3_.setZero(na_, 3);
  H2_.setZero(2, na_), HP2_.setZero(2, na_), SKt2_.setZero(2, na_), K2_.setZero(na_, 2);
  H1_.setZero(1, na_), HP1_.setZero(1, na_), SKt1_.setZero(1, na_), K1_.setZero(na_, 1);
  JtJ_.setIdentity(m_, m_);
  y_.setZero(m_);
  dq_.setZero(m_);
  ldlt_.compute(JtJ_);  // computed once, so that copying a filter never copies an unset LDLT
  const std::size_t links = hand.links.size();
  pairs_.reserve(links);
  s_.active.reserve(links);
  Jc_.assign(links, Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, m_));
  inv_weight_.reserve(links);
  finger_nearest_.assign(hand.joints.size(), 0.0);
  s_.trace.contacts.reserve(links * static_cast<std::size_t>(params_.contact_iterations));
  s_.trace.visual.reserve(512);
}

void StartSigmas::Validate(const std::string& source) const {
  const auto check = [&](const char* name, double v, double lo, double hi, const char* expected) {
    if (!(v >= lo && v <= hi))
      throw InputError(source + ": '" + name + "' is " + std::to_string(v) + ", expected " +
                       expected);
  };
  check("sigma_position", position, 1e-6, 10.0, "in [1e-6, 10] m");
  check("sigma_orientation", orientation, 1e-6, 2 * M_PI, "in [1e-6, 2 pi] rad");
  check("sigma_joint_bias", bias, 0.0, 2 * M_PI, "in [0, 2 pi] rad");
  for (long i = 0; i < bias_per_joint.size(); ++i)
    check("sigma_joint_bias", bias_per_joint[i], 0.0, 2 * M_PI, "in [0, 2 pi] rad");
}

void Filter::Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
                   const StartSigmas& sigmas) {
  INHAND_CHECK(q_meas.size() == m_, "joint vector size does not match the hand");
  sigmas.Validate("filter start");
  if (!T_PO.matrix().allFinite() || !q_meas.allFinite())
    throw InputError("filter start: the pose or the joints are not finite");
  INHAND_CHECK(sigmas.bias_per_joint.size() == 0 || sigmas.bias_per_joint.size() == m_,
               "per-joint bias sigmas do not match the hand");
  s_.p = T_PO.translation();
  s_.R = Orthonormalize(T_PO.linear());
  s_.b.setZero();
  s_.xi.setZero();
  delta_.setZero();
  s_.P.setZero();
  s_.P.diagonal().head<3>().setConstant(sigmas.position * sigmas.position);
  s_.P.diagonal().segment<3>(3).setConstant(sigmas.orientation * sigmas.orientation);
  if (sigmas.bias_per_joint.size() == m_)
    s_.P.diagonal().segment(6, m_) = sigmas.bias_per_joint.array().square().matrix();
  else
    s_.P.diagonal().segment(6, m_).setConstant(sigmas.bias * sigmas.bias);
  if (camera_state_) {
    s_.P.diagonal().segment<3>(n_).setConstant(params_.camera_position_sigma *
                                               params_.camera_position_sigma);
    s_.P.diagonal().tail<3>().setConstant(params_.camera_orientation_sigma *
                                          params_.camera_orientation_sigma);
  }
  s_.q_prev = q_meas;
  s_.have_prev = true;
  s_.active.clear();
  std::fill(s_.push_O.begin(), s_.push_O.end(), Vec3::Zero());
  s_.trace.Clear();
  s_.grip = s_.max_grip = 0.0;
  s_.q_window = q_meas;
  s_.window_time = 0.0;
  RefreshKinematics();
}

void Filter::Restore(const FilterState& state) {
  INHAND_CHECK(state.b.size() == m_ && state.q_window.size() == m_ && state.P.rows() == na_ &&
                   state.P.cols() == na_ && state.push_O.size() == s_.push_O.size(),
               "filter state of another hand or parameters");
  s_ = state;  // same sizes: Eigen and std::vector reuse their storage
  delta_.setZero();
  kin_.Update(hand_, s_.q_eff);
}

void Filter::WidenPose(double sigma_position, double sigma_orientation) {
  if (!(sigma_position >= 0.0 && sigma_orientation >= 0.0) || !std::isfinite(sigma_position) ||
      !std::isfinite(sigma_orientation))
    throw InputError("filter: widening the pose by sigma " + std::to_string(sigma_position) +
                     " m, " + std::to_string(sigma_orientation) + " rad; expected finite and >= 0");
  s_.P.diagonal().head<3>().array() += sigma_position * sigma_position;
  s_.P.diagonal().segment<3>(3).array() += sigma_orientation * sigma_orientation;
}

void Filter::Relocate(const Transform& T_PO, const Mat6& pose_covariance) {
  const Eigen::LLT<Mat6> llt(pose_covariance);
  if (!T_PO.matrix().allFinite() || !pose_covariance.allFinite() ||
      !pose_covariance.isApprox(pose_covariance.transpose()) || llt.info() != Eigen::Success)
    throw InputError(
        "filter: relocating the object needs a finite pose and a symmetric positive definite "
        "covariance");
  s_.p = T_PO.translation();
  s_.R = Orthonormalize(T_PO.linear());
  delta_.setZero();
  s_.P.topRows<6>().setZero();
  s_.P.leftCols<6>().setZero();
  s_.P.topLeftCorner<6, 6>() = 0.5 * (pose_covariance + pose_covariance.transpose());
  s_.active.clear();
  std::fill(s_.push_O.begin(), s_.push_O.end(), Vec3::Zero());
}

Transform Filter::T_PO() const { return MakeTransform(s_.p, s_.R); }

void Filter::RefreshKinematics() {
  s_.q_eff = s_.q_prev + s_.b;
  kin_.Update(hand_, s_.q_eff);
}

void Filter::Predict(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt) {
  INHAND_CHECK(q_meas.size() == m_, "joint vector size does not match the hand");
  s_.trace.Clear();
  if (!q_meas.allFinite() || !std::isfinite(dt)) {  // nothing non-finite enters the state
    ++s_.trace.numeric_events;
    return;
  }
  if (!s_.have_prev) {
    s_.q_prev = q_meas;
    s_.have_prev = true;
  }
  dq_ = q_meas - s_.q_prev;
  // Hard-finger, non-slipping contacts: A ν = J Δq (kin_ holds the previous configuration).
  twist_.Reset();
  for (const ActiveContact& a : s_.active) {
    const Vec3 c_P = kin_.T_PL(a.link) * a.c_f_L;
    PointJacobian(hand_, kin_, a.link, c_P, J_);
    const Vec3 finger_motion = J_ * dq_;
    twist_.Add(GraspMapBlock(c_P, s_.p), finger_motion);
  }
  Vec6 nu = twist_.Solve(params_.twist_damping);
  if (!nu.allFinite()) {
    ++s_.trace.numeric_events;
    nu.setZero();
  }
  s_.p += nu.head<3>();
  s_.R = ExpSO3(nu.tail<3>()) * s_.R;
  s_.trace.predicted_twist = nu;
  s_.trace.prediction_contacts = twist_.count();

  // Process noise: a random walk plus a share of the predicted motion (rolling and slipping
  // are not modelled). F = I to first order, as in the paper. The camera error is constant.
  const double dtp = std::max(dt, 0.0);
  // Only once the object has been held: before the grasp nothing holds it, but nothing moves it.
  const bool slipping = options_.use_torque && params_.slip_torque > 0.0 &&
                        s_.max_grip >= params_.slip_torque && s_.grip < params_.slip_torque;
  const double walk = slipping ? params_.slip_scale * params_.slip_scale : 1.0;
  s_.trace.slipping = slipping;
  const double sp = walk * params_.process_position * params_.process_position * dtp +
                    std::pow(params_.motion_position * nu.head<3>().norm(), 2);
  const double so = walk * params_.process_orientation * params_.process_orientation * dtp +
                    std::pow(params_.motion_orientation * nu.tail<3>().norm(), 2);
  s_.P.diagonal().head<3>().array() += sp;
  s_.P.diagonal().segment<3>(3).array() += so;
  s_.P.diagonal().segment(6, m_).array() += params_.process_bias * params_.process_bias * dtp;
  if (travel_) GrowWithTravel(q_meas, dtp);
  s_.q_prev = q_meas;
}

void Filter::Step(const Eigen::Ref<const Eigen::VectorXd>& q_meas,
                  const Eigen::Ref<const Eigen::VectorXd>& tau, double dt) {
  Predict(q_meas, dt);
  UpdateContacts(tau);
}

void Filter::GrowWithTravel(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt) {
  constexpr double kWindow = 0.05;  // [s]
  s_.window_time += dt;
  if (s_.window_time < kWindow) return;
  dq_ = q_meas - s_.q_window;  // over the window: the joints' noise telescopes
  double travel = 0.0;
  for (const ActiveContact& a : s_.active) {
    PointJacobian(hand_, kin_, a.link, kin_.T_PL(a.link) * a.c_f_L, J_);
    travel = std::max(travel, (J_ * dq_).norm());
  }
  if (travel > 0.0 && std::isfinite(travel)) {
    const Mat3 G_inv = s_.R * gyration_inv_O_ * s_.R.transpose();
    s_.P.block<3, 3>(3, 3) += (0.5 * params_.travel_orientation * travel) *
                              (G_inv + G_inv.transpose());  // exactly symmetric
  }
  s_.q_window = q_meas;
  s_.window_time = 0.0;
}

template <int D>
Filter::Outcome Filter::Update(const Eigen::Matrix<double, D, 1>& r_in,
                               const Eigen::Matrix<double, D, Eigen::Dynamic>& H,
                               const Eigen::Matrix<double, D, D>& R, double gate_chi2,
                               double* mahalanobis) {
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
  HP->noalias() = H * s_.P;
  Eigen::Matrix<double, D, D> S = R;
  S.noalias() += *HP * H.transpose();
  const Eigen::LDLT<Eigen::Matrix<double, D, D>> ldlt(S);
  if (!r.allFinite() || !S.allFinite() || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-300) {
    ++s_.trace.numeric_events;
    return Outcome::kNumeric;
  }
  const Eigen::Matrix<double, D, 1> Sinv_r = ldlt.solve(r);
  const double m2 = r.dot(Sinv_r);
  if (mahalanobis) *mahalanobis = m2;
  if (gate_chi2 > 0.0 && m2 > gate_chi2) {
    ++s_.trace.num_gated;
    return Outcome::kGated;
  }
  const Eigen::Matrix<double, D, D> Sinv = ldlt.solve(Eigen::Matrix<double, D, D>::Identity());
  K->noalias() = HP->transpose() * Sinv;
  // Joseph form, expanded: (I-KH)P(I-KH)ᵀ + KRKᵀ = P - K(HP) - (HP)ᵀKᵀ + K S Kᵀ, into the spare
  // buffer: the state takes it only when it is finite and its variances are not negative.
  Pn_ = s_.P;
  Pn_.noalias() -= *K * *HP;
  Pn_.noalias() -= HP->transpose() * K->transpose();
  SKt->noalias() = S * K->transpose();
  Pn_.noalias() += *K * *SKt;
  for (int i = 0; i < na_; ++i)
    for (int j = i + 1; j < na_; ++j) Pn_(i, j) = Pn_(j, i) = 0.5 * (Pn_(i, j) + Pn_(j, i));
  delta_saved_ = delta_;
  delta_.noalias() += *K * r;
  // (A variance may be 0, a known state; below 0 beyond rounding the covariance is lost.)
  if (!delta_.allFinite() || !Pn_.allFinite() ||
      !(Pn_.diagonal().minCoeff() >= -1e-9 * Pn_.diagonal().maxCoeff())) {
    delta_ = delta_saved_;
    ++s_.trace.numeric_events;
    return Outcome::kNumeric;
  }
  s_.P.swap(Pn_);
  return Outcome::kApplied;
}

template Filter::Outcome Filter::Update<1>(const Eigen::Matrix<double, 1, 1>&,
                                           const Eigen::Matrix<double, 1, Eigen::Dynamic>&,
                                           const Eigen::Matrix<double, 1, 1>&, double, double*);
template Filter::Outcome Filter::Update<2>(const Eigen::Matrix<double, 2, 1>&,
                                           const Eigen::Matrix<double, 2, Eigen::Dynamic>&,
                                           const Eigen::Matrix<double, 2, 2>&, double, double*);
template Filter::Outcome Filter::Update<3>(const Eigen::Matrix<double, 3, 1>&,
                                           const Eigen::Matrix<double, 3, Eigen::Dynamic>&,
                                           const Eigen::Matrix<double, 3, 3>&, double, double*);

void Filter::Commit() {
  s_.p += delta_.head<3>();
  s_.R = ExpSO3(delta_.segment<3>(3)) * s_.R;
  s_.R = Quat(s_.R).normalized().toRotationMatrix();  // keep R on SO(3) against rounding drift
  s_.b += delta_.segment(6, m_);
  if (camera_state_) s_.xi += delta_.tail<6>();
  delta_.setZero();
}

}  // namespace inhand
