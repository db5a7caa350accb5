#pragma once
// Does a pose of the object explain the hand? (docs/estimator.md, "Plausibility".) Whatever the
// image says, a pose is physically impossible when a link lies deep inside the object, and does
// not explain the joint torques when a finger that they say presses is far from it. The visual
// step scores every pose it can jump to with this, and the tracker's recovery settles its
// hypotheses with it. Nothing here runs per joint sample: per image and per hypothesis.
#include <utility>
#include <vector>

#include "inhand/core/contact.hpp"
#include "inhand/core/hand_model.hpp"

namespace inhand {

struct HealthParams;

// Which links and joints make up each finger of a hand: the links whose joint chains start at
// the same joint. The palm's links belong to no finger.
struct HandFingers {
  explicit HandFingers(const HandModel& hand);
  std::vector<int> link_finger;            // per link: its finger, -1 for none (the palm)
  std::vector<std::vector<int>> finger_q;  // per finger: its configuration entries
  std::vector<int> tip;                    // per finger: its link farthest down the chain
  // The palm: of the links that belong to no finger and collide, the widest (-1: none). Its
  // collision geometry's centre and its grasp side's normal, in its link frame: the direction in
  // which that geometry is thinnest, signed toward the fingertips' mean with every joint in the
  // middle of its range (a half-closed hand; joints without limits at 0). Zero when the
  // fingertips lie in the palm's plane there, or when the hand has fewer than two fingers (a
  // wrist joint above every link makes the whole hand one finger).
  int palm = -1;
  Vec3 palm_centre_L = Vec3::Zero();
  Vec3 palm_normal_L = Vec3::Zero();
  int size() const { return static_cast<int>(finger_q.size()); }
  // The palm's centre and grasp side's normal at the links' poses T_PL, in P (zero normal
  // without a palm).
  std::pair<Vec3, Vec3> GraspSide(const std::vector<Transform>& T_PL) const;
  // [N m] the largest |τ| over finger f's joints (tau in configuration order).
  double Torque(int f, const Eigen::Ref<const Eigen::VectorXd>& tau) const;
};

// How far a pose is from explaining the hand.
struct Plausibility {
  double penetration = 0.0;  // [m] the deepest link inside the object (0: none inside)
  int penetration_link = -1;
  int pressing = 0;           // fingers whose joint torques say they press
  double pressing_gap = 0.0;  // [m] the largest distance from a pressing finger's nearest link to
                              // the object (the reach when none is within it; 0 when none
                              // presses)
  int pressing_link = -1;
  // [m] what does not explain the hand: the penetration beyond HealthParams::penetration plus
  // the pressing gap beyond HealthParams::press_gap. 0: plausible.
  double Excess(const HealthParams& params) const;
};

class HandPlausibility {
 public:
  // `query`: a contact query of this hand and object, for this object's use only (not the
  // filter's: Score and Settle run between the filter's steps but share no state with it).
  HandPlausibility(const HandModel& hand, ContactQuery& query);

  // Scores T_PO against the links at T_PL (every link's pose) and the joint torques tau
  // (configuration order; not finite or empty: no finger presses), looking `reach` far.
  Plausibility Score(const Eigen::Ref<const Eigen::VectorXd>& tau,
                     const std::vector<Transform>& T_PL, const Transform& T_PO,
                     const HealthParams& params, double reach);

  // The pose nearest T_PO, by a translation, that explains the hand: every pressing finger's
  // nearest link on the surface and no link inside. Gauss-Newton on the signed distances of
  // those pairs (each is linear in the translation along its normal), damped, at most
  // `max_step` per iteration, until the translation moves less than 0.1 mm.
  Transform Settle(const Eigen::Ref<const Eigen::VectorXd>& tau, const std::vector<Transform>& T_PL,
                   const Transform& T_PO, const HealthParams& params, double reach,
                   int iterations = 12, double max_step = 0.02);

  // A start pose that puts a link deeper than HealthParams::penetration inside the object: the
  // filter would push the object out the way the field's gradient points inside it, which along
  // a bottle's axis slides it tens of millimetres away. Hypotheses: T_PO and T_PO moved by
  // ±2 sigma_position along each palm axis, each settled (Settle); the one chosen has the
  // object's centre (centre_O) on the grasp side of the palm (GraspSide), then no excess, then
  // the smallest Mahalanobis distance from T_PO. The start is kept (hypothesis -1) when it is
  // within the bound, when no hypothesis is on the grasp side, and when the start's own way out
  // (hypothesis 0) is the one chosen: the filter's contact updates take that way themselves.
  struct StartChoice {
    Transform T_PO = Transform::Identity();
    double penetration = 0.0;  // [m] at the given start
    int link = -1;             // its deepest link
    int hypothesis = -1;       // the one chosen (1-6: from ±2σ along x, y, z), -1: the start kept
  };
  StartChoice SettleStart(const Eigen::Ref<const Eigen::VectorXd>& tau,
                          const std::vector<Transform>& T_PL, const Transform& T_PO,
                          const Vec3& centre_O, double sigma_position, const HealthParams& params,
                          double reach);

  const HandFingers& fingers() const { return fingers_; }

 private:
  // Queries and keeps, per finger, its nearest pair within reach (pairs_ index, -1 for none).
  void Measure(const std::vector<Transform>& T_PL, const Transform& T_PO, double reach);

  HandFingers fingers_;
  ContactQuery& query_;
  std::vector<ContactPair> pairs_;
  std::vector<int> nearest_;  // per finger
  std::vector<double> torque_;
};

}  // namespace inhand
