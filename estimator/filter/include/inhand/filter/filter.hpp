#pragma once
// The error-state EKF of estimator-math.md: mean (p, R, b), error δ = (δp, δθ, δb) ∈ R^(6+m),
// R = Exp(δθ) R̂. Predict maps finger motion to object motion through the grasp map of the
// active contacts; UpdateContacts removes penetrations and adds torque-confirmed contacts;
// UpdateVisual (visual features) aligns the object with pixels. Every update goes through one
// generic, sequential, Joseph-form block update with gating and one retraction per step.
// Sized once from the model: a step allocates nothing after warm-up.
#include <Eigen/Cholesky>
#include <vector>

#include "inhand/core/contact.hpp"
#include "inhand/core/hand_model.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/filter/params.hpp"
#include "inhand/kinematics/kinematics.hpp"

namespace inhand {

enum class ContactKind {
  kKinematic,       // penetrating (d < 0): a zero-distance constraint
  kTorque,          // separated, confirmed by joint torques: pulled into touch
  kRejectedCone,    // torque candidate whose force lies outside the friction cone
  kRejectedForce,   // torque candidate whose force is below force_min
  kCandidate,       // near but neither penetrating nor torque-confirmed
};
const char* ContactKindName(ContactKind kind);

// Everything one step decided, for overlays, logs and tests. The core never prints or draws.
struct FilterTrace {
  struct Contact {
    ContactKind kind = ContactKind::kCandidate;
    int link = -1;
    int piece = -1;
    int iteration = 0;
    double distance = 0.0;          // [m] signed, before the update
    Vec3 c_o_P = Vec3::Zero();
    Vec3 c_f_P = Vec3::Zero();
    Vec3 normal_P = Vec3::Zero();   // link → object
    Vec3 force_P = Vec3::Zero();    // λ̄: estimated force applied to the object [N]
    double mahalanobis = 0.0;       // r S⁻¹ r of its update (constraints only)
    bool gated = false;             // rejected by the gate
  };
  struct Visual {
    int id = -1;                    // caller's feature id (tag id*4+corner, match index, ...)
    Vec2 measured = Vec2::Zero();   // [px] undistorted
    Vec2 predicted = Vec2::Zero();  // [px] at the prior
    double mahalanobis = 0.0;
    bool gated = false;
  };
  double t = 0.0;
  std::vector<Contact> contacts;
  std::vector<Visual> visual;
  int prediction_contacts = 0;      // contacts that moved the object in Predict
  Vec6 predicted_twist = Vec6::Zero();  // (Δp, Δθ) of the last Predict
  int num_constraints = 0;          // contact blocks applied
  int num_gated = 0;                // blocks rejected by a gate
  int numeric_events = 0;           // ill-conditioned S, non-finite residuals (skipped)
  bool slipping = false;            // Predict grew the random walk: the grip was too weak
  void Clear();
};

struct VisualFeature {
  int id = -1;
  Vec3 x_O = Vec3::Zero();          // the feature's point on the object, object frame [m]
  Vec2 pixel = Vec2::Zero();        // measured pixel, undistorted [px]
};

class Filter {
 public:
  // `contacts` must outlive the filter. `use_torque` enables torque contacts (modality jt).
  Filter(const HandModel& hand, ContactQuery& contacts, const FilterParams& params, bool use_torque);

  // Starts from T_PO with the given standard deviations; biases start at zero.
  void Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
             double sigma_position, double sigma_orientation, double sigma_bias);
  void Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
             double sigma_position, double sigma_orientation,
             const Eigen::Ref<const Eigen::VectorXd>& sigma_bias);

  // Moves the object with the fingers from the previous q_meas to this one over dt seconds.
  void Predict(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt);
  // Kinematic and (if enabled) torque contacts at the current estimate.
  void UpdateContacts(const Eigen::Ref<const Eigen::VectorXd>& tau);
  // Pixels of object points seen by a camera at T_PC. Returns the number of features used.
  int UpdateVisual(const std::vector<VisualFeature>& features, const Transform& T_PC,
                   const Intrinsics& K);

  Transform T_PO() const;
  const Vec3& position() const { return p_; }
  const Mat3& rotation() const { return R_; }
  const Eigen::VectorXd& biases() const { return b_; }
  // The camera pose's estimated error (v, ω), T_PC_true = T_PC Exp(ξ); zero unless camera σ > 0.
  const Vec6& camera_error() const { return xi_; }
  const Eigen::MatrixXd& covariance() const { return P_; }
  const FilterTrace& trace() const { return trace_; }
  FilterTrace& mutable_trace() { return trace_; }
  const FilterParams& params() const { return params_; }
  const KinematicsData& kinematics() const { return kin_; }  // at q_meas + b of the last update
  int dim() const { return n_; }

  // The generic block update: residual r (D), Jacobian H (D × n) at the current linearisation
  // point, noise R (D × D). Sequential: r is corrected by the not yet applied correction.
  // Returns false when gated (chi2 > gate, gate > 0) or numerically unusable.
  template <int D>
  bool UpdateBlock(const Eigen::Matrix<double, D, 1>& r, const Eigen::Matrix<double, D, Eigen::Dynamic>& H,
                   const Eigen::Matrix<double, D, D>& R, double gate_chi2, double* mahalanobis);
  // Applies the accumulated correction (retraction on SO(3)) and clears it.
  void Commit();

 private:
  struct Active {
    int link;
    Vec3 c_f_L;  // contact point in the link frame
  };
  void ContactStep(const Eigen::Ref<const Eigen::VectorXd>& tau, int iteration);
  double CandidateWeight(double distance) const;
  // inv_weight_[i] = 1 / weight of candidate i relative to its finger's nearest candidate.
  void ComputeCandidateWeights();

  const HandModel& hand_;
  ContactQuery& contacts_;
  FilterParams params_;
  bool use_torque_;
  int m_, n_;

  Vec3 p_ = Vec3::Zero();
  Mat3 R_ = Mat3::Identity();
  Eigen::VectorXd b_;
  Eigen::MatrixXd P_;
  Eigen::VectorXd delta_;  // accumulated, not yet applied correction
  // The camera pose's error ξ = (v, ω), T_PC_true = T_PC Exp(ξ), when camera σ > 0: a state
  // kept beside the others (its covariance Pcc_, its cross-covariance with them Pxc_), seen by
  // the visual update only, constant over time.
  bool camera_state_ = false;
  Vec6 xi_ = Vec6::Zero(), dxi_ = Vec6::Zero();
  Eigen::Matrix<double, Eigen::Dynamic, 6> Pxc_;
  Eigen::Matrix<double, 6, 6> Pcc_ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::VectorXd q_prev_, q_eff_;
  bool have_prev_ = false;
  double grip_ = 0.0;      // [N m] Σ|τ| of the last contact update
  double max_grip_ = 0.0;  // [N m] its largest value since Reset

  KinematicsData kin_;
  std::vector<ContactPair> pairs_;
  std::vector<Active> active_;
  FilterTrace trace_;

  // Work buffers, sized once.
  Eigen::Matrix<double, 3, Eigen::Dynamic> J_, H3_, HP3_, SKt3_;
  Eigen::Matrix<double, Eigen::Dynamic, 3> K3_;
  Eigen::Matrix<double, 2, Eigen::Dynamic> H2_, HP2_, SKt2_;
  Eigen::Matrix<double, Eigen::Dynamic, 2> K2_;
  Eigen::Matrix<double, 1, Eigen::Dynamic> H1_, HP1_, SKt1_;
  Eigen::Matrix<double, Eigen::Dynamic, 1> K1_;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> Jc_;  // per candidate
  std::vector<double> inv_weight_;                            // per candidate
  std::vector<double> finger_nearest_;                        // per joint: nearest candidate
  Eigen::MatrixXd JtJ_;
  Eigen::VectorXd y_, dq_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  TwistSolver twist_;
};

}  // namespace inhand
