#pragma once
// The error-state EKF of docs/estimator.md: mean (p, R, b), error δ = (δp, δθ, δb) ∈ R^(6+m),
// R = Exp(δθ) R̂ (plus the camera pose's error ξ when it is estimated). Predict maps finger
// motion to object motion through the grasp map of the active contacts; UpdateContacts removes
// penetrations and adds torque-confirmed contacts; UpdateVisual aligns the object with pixels.
// Each measurement source fills residual, Jacobian, noise and gate for one generic, sequential,
// Joseph-form block update with one retraction per step. Sized once from the model: a step
// allocates nothing after warm-up.
#include <Eigen/Cholesky>
#include <string>
#include <vector>

#include "inhand/core/contact.hpp"
#include "inhand/core/hand_model.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/filter/params.hpp"
#include "inhand/kinematics/kinematics.hpp"

namespace inhand {

enum class ContactKind {
  kKinematic,      // penetrating (d < 0): a zero-distance constraint
  kTorque,         // separated, confirmed by joint torques: pulled into touch
  kRejectedCone,   // torque candidate whose force lies outside the friction cone
  kRejectedForce,  // torque candidate whose force is below force_min
  kCandidate,      // near but neither penetrating nor torque-confirmed
};
const char* ContactKindName(ContactKind kind);

// Everything one step decided, for overlays, logs and tests. The core never prints or draws.
struct FilterTrace {
  struct Contact {
    ContactKind kind = ContactKind::kCandidate;
    int link = -1;
    int piece = -1;  // the ContactPair's: -1 for the object as a whole
    int iteration = 0;
    double distance = 0.0;  // [m] signed, before the update
    Vec3 c_o_P = Vec3::Zero();
    Vec3 c_f_P = Vec3::Zero();
    Vec3 normal_P = Vec3::Zero();  // link → object
    Vec3 force_P = Vec3::Zero();   // λ̄: estimated force applied to the object [N]
    double mahalanobis = 0.0;      // r S⁻¹ r of its update (constraints only)
    bool gated = false;            // rejected by the gate
  };
  struct Visual {
    int id = -1;                    // caller's feature id (tag id*4+corner, match index, ...)
    Vec2 measured = Vec2::Zero();   // [px] undistorted
    Vec2 predicted = Vec2::Zero();  // [px] at the prior
    double depth = 0.0;             // [m] of the point in the camera at the prior; 0 if behind it
    double mahalanobis = 0.0;
    bool gated = false;
  };
  double t = 0.0;
  std::vector<Contact> contacts;
  std::vector<Visual> visual;
  int prediction_contacts = 0;          // contacts that moved the object in Predict
  Vec6 predicted_twist = Vec6::Zero();  // (Δp, Δθ) of the last Predict
  int num_constraints = 0;              // contact blocks applied
  int num_gated = 0;                    // blocks rejected by a gate
  int numeric_events = 0;               // ill-conditioned S, non-finite inputs or results (skipped:
                                        // nothing non-finite enters the state)
  bool slipping = false;                // Predict grew the random walk: the grip was too weak
  // [m] how deep the deepest link lies inside the object at the estimate the step's last contact
  // query saw (before that query's update; 0: no link inside). A hand cannot be inside what it
  // holds: the estimate's own measure of impossibility, free (the step runs that query anyway).
  double penetration = 0.0;
  // [N m] sets with torques: the largest joint torque that the contacts at the estimate (every
  // candidate within reach, before the cone and force tests) cannot explain, |τ − Σ J_iᵀ λ̄_i|∞ at
  // the step's last contact query; all of τ when no link is within reach. Fingers that press on an
  // object the estimate has put elsewhere show here. 0 without torques.
  double unexplained_torque = 0.0;
  void Clear();
};

struct VisualFeature {
  int id = -1;
  Vec3 x_O = Vec3::Zero();    // the feature's point on the object, object frame [m]
  Vec2 pixel = Vec2::Zero();  // measured pixel, undistorted [px]
  // x_O is where the line of sight grazes the surface (an extracted corner on the object's
  // outline): a turn about a symmetry axis moves it along the line of sight.
  bool on_outline = false;
};

// The standard deviations the filter starts with (docs/estimator.md, "State").
struct StartSigmas {
  double position = 0.020;                // [m] per axis
  double orientation = 5.0 * M_PI / 180;  // [rad] per axis
  double bias = 5.0 * M_PI / 180;         // [rad] every joint bias, unless bias_per_joint is set
  Eigen::VectorXd bias_per_joint;         // [rad] one per joint (empty: `bias` for every joint)
  // Throws InputError("SOURCE: 'sigma_position' is V, expected ...") outside the ranges that
  // keep the filter's arithmetic finite: position [1e-6, 10] m, orientation [1e-6, 2π] rad,
  // biases [0, 2π] rad.
  void Validate(const std::string& source = "start sigmas") const;
};

struct FilterOptions {
  bool use_torque = false;  // torque contacts (modality t)
  // The object's gyration tensor (inertia about its centre of mass / mass, object axes [m²]):
  // the metric of FilterParams::travel_orientation. Zero (not known): that noise is off.
  Mat3 gyration_O = Mat3::Zero();
  // The object's continuous symmetry (ObjectModel::symmetry_axis_O): an image feature then
  // measures nothing along the pixel direction a turn about it moves the feature in. Zero: none.
  Vec3 symmetry_axis_O = Vec3::Zero();
  Vec3 symmetry_point_O = Vec3::Zero();
};

// A contact that moves the object with its finger in Predict: its point fixed on the link.
struct ActiveContact {
  int link = -1;
  Vec3 c_f_L = Vec3::Zero();
};

// Everything the filter carries from one step to the next, as plain data: saving it and
// restoring it later continues bit-identically (the tracker's checkpoints, the GUI's seeking).
// The error state is δ = (δp, δθ, δb[, ξ]): ξ, the camera pose's error, only when a camera σ
// is set; P covers all of it.
struct FilterState {
  Vec3 p = Vec3::Zero();      // object position in the palm frame [m]
  Mat3 R = Mat3::Identity();  // object orientation
  Eigen::VectorXd b;          // joint biases [rad]
  Vec6 xi = Vec6::Zero();     // camera pose error (v, ω), T_PC_true = T_PC Exp(ξ)
  Eigen::MatrixXd P;          // covariance of δ
  Eigen::VectorXd q_prev;     // the last measured joints
  Eigen::VectorXd q_eff;      // q_prev + b: where the kinematics were last evaluated
  bool have_prev = false;
  double grip = 0.0;         // [N m] Σ|τ| of the last contact update
  double max_grip = 0.0;     // [N m] its largest value since Reset
  Eigen::VectorXd q_window;  // the joints where the current travel window began
  double window_time = 0.0;  // [s] since then
  std::vector<ActiveContact> active;
  // Per link: the direction (object frame, from the link into the object) in which its last
  // penetration was pushed out, zero when it did not penetrate at the last contact step.
  std::vector<Vec3> push_O;
  FilterTrace trace;  // what the last step decided
};

class Filter {
 public:
  // `contacts` must outlive the filter.
  Filter(const HandModel& hand, ContactQuery& contacts, const FilterParams& params,
         const FilterOptions& options = {});

  // Starts from T_PO with the given standard deviations; biases start at zero.
  void Reset(const Transform& T_PO, const Eigen::Ref<const Eigen::VectorXd>& q_meas,
             const StartSigmas& sigmas = {});

  // One joint sample: Predict to q_meas over dt, then UpdateContacts with tau at the joints
  // just predicted to. The contact update reads the joints that Predict stored (FilterState::
  // q_prev), so the two belong together; a joint-rate loop calls this.
  void Step(const Eigen::Ref<const Eigen::VectorXd>& q_meas,
            const Eigen::Ref<const Eigen::VectorXd>& tau, double dt);
  // The two halves of Step, for tests that look between them.
  // Moves the object with the fingers from the previous q_meas to this one over dt seconds.
  void Predict(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt);
  // Kinematic and (if enabled) torque contacts at the current estimate, at the joints of the
  // last Predict (or Reset).
  void UpdateContacts(const Eigen::Ref<const Eigen::VectorXd>& tau);
  // Pixels of object points seen by a camera at T_PC (tag corners, extracted features). Returns
  // the number of features used. Allocates nothing once the trace has room for the features.
  int UpdateVisual(const std::vector<VisualFeature>& features, const Transform& T_PC,
                   const Intrinsics& K);

  // Adds σ² to the variance of every axis of the position and of the orientation: what the
  // caller learnt the estimate can be off by, beyond what the filter's models admit (the
  // tracker: the object found again far from where the estimate had lost it). Throws
  // InputError unless both are finite and >= 0.
  void WidenPose(double sigma_position, double sigma_orientation);
  // Puts the object at T_PO with covariance `pose_covariance` of (δp, δθ): what the caller
  // measured on its own, far from where the estimate was (the tracker: tags that a fit puts
  // where the estimate cannot be). The pose forgets its correlations with the biases and the
  // camera error, which keep their own; the contacts that moved the object with the fingers are
  // dropped (they held the object where it was not). Throws InputError unless the pose is
  // finite and the covariance symmetric positive definite.
  void Relocate(const Transform& T_PO, const Mat6& pose_covariance);

  Transform T_PO() const;
  const Vec3& position() const { return s_.p; }
  const Mat3& rotation() const { return s_.R; }
  const Eigen::VectorXd& biases() const { return s_.b; }
  // The camera pose's estimated error (v, ω), T_PC_true = T_PC Exp(ξ); zero unless camera σ > 0.
  const Vec6& camera_error() const { return s_.xi; }
  // Covariance of (δp, δθ, δb) (dim() × dim()).
  Eigen::Block<const Eigen::MatrixXd> covariance() const { return s_.P.topLeftCorner(n_, n_); }
  const FilterTrace& trace() const { return s_.trace; }
  const FilterParams& params() const { return params_; }
  const FilterOptions& options() const { return options_; }
  const KinematicsData& kinematics() const { return kin_; }  // at q_meas + b of the last update
  int dim() const { return n_; }

  const FilterState& state() const { return s_; }
  // Continues from a state saved from a filter of the same hand and parameters. Allocates
  // nothing when this filter's state already has the sizes (every state of one filter has).
  void Restore(const FilterState& state);

 private:
  // The generic block update (every measurement source ends here): residual r = z - h(x̂)
  // (D rows), Jacobian H (D × the whole error state, zeros where the source sees nothing),
  // noise R, gate (χ², 0: none). Sequential: r is corrected by the not yet applied correction;
  // Joseph form; nothing is applied to the mean until Commit.
  enum class Outcome { kApplied, kGated, kNumeric };
  template <int D>
  Outcome Update(const Eigen::Matrix<double, D, 1>& r,
                 const Eigen::Matrix<double, D, Eigen::Dynamic>& H,
                 const Eigen::Matrix<double, D, D>& R, double gate_chi2, double* mahalanobis);
  // Applies the accumulated correction (retraction on SO(3)) and clears it.
  void Commit();
  void RefreshKinematics();
  // travel_orientation: at the end of each 50 ms window, the orientation's variance grows with
  // the largest displacement of an active contact point over it.
  void GrowWithTravel(const Eigen::Ref<const Eigen::VectorXd>& q_meas, double dt);

  // Measurement sources, one file each (src/): kinematic_contacts.cpp, torque_contacts.cpp,
  // contact_constraint.cpp (the constraint both kinds of contact apply), visual_features.cpp.
  void ContactStep(const Eigen::Ref<const Eigen::VectorXd>& tau, int iteration);
  void EstimateContactForces(const Eigen::Ref<const Eigen::VectorXd>& tau);
  ContactKind ClassifyTorqueContact(std::size_t candidate, FilterTrace::Contact& rec) const;
  bool ApplyContactConstraint(const ContactPair& pair,
                              const Eigen::Matrix<double, 3, Eigen::Dynamic>& J_f,
                              FilterTrace::Contact& rec);
  // Penetrating pairs keep the direction of their link's last push when a new one opposes it
  // (FilterState::push_O); links not penetrating forget theirs.
  void KeepPushDirections();
  void CapContactInformation(double var);  // contact_model_sigma, after a normal-only constraint
  void CapVisualInformation(const Eigen::Matrix2d& R);  // visual_model_sigma, after a feature
  void ProjectOutSymmetry(const Vec6& turn, Eigen::Vector2d& r);  // r, H2_ across H2_ turn
  double CandidateWeight(double distance) const;
  // inv_weight_[i] = 1 / weight of candidate i relative to its finger's nearest candidate.
  void ComputeCandidateWeights();

  const HandModel& hand_;
  ContactQuery& contacts_;
  FilterParams params_;
  FilterOptions options_;
  bool camera_state_ = false;  // ξ is part of the state (camera σ > 0)
  bool travel_ = false;        // travel_orientation > 0 with a gyration tensor
  Mat3 gyration_inv_O_ = Mat3::Zero();
  int m_, n_, na_;  // joints; pose + biases; + camera error

  FilterState s_;
  Eigen::VectorXd delta_;        // accumulated, not yet applied correction (na_)
  Eigen::VectorXd delta_saved_;  // delta_ before the block being applied
  Eigen::MatrixXd Pn_;           // the covariance after the block being applied
  KinematicsData kin_;
  std::vector<ContactPair> pairs_;

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
  std::vector<char> penetrating_;                             // per link: inside at this step
  bool torque_forces_ = false;                                // y_ holds this step's solve
  Eigen::MatrixXd JtJ_;
  Eigen::VectorXd y_, dq_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  TwistSolver twist_;
};

}  // namespace inhand
