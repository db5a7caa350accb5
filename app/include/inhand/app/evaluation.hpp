#pragma once
// One modality set's estimate at one joint sample, and how it compares with the ground truth.
#include <limits>

#include "inhand/core/so3.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::app {

struct EstimateRecord {
  double t = 0.0;
  Transform T_PO;
  Vec3 sigma_position = Vec3::Zero();     // [m]
  Vec3 sigma_orientation = Vec3::Zero();  // [rad]
  Eigen::VectorXd biases;
  double position_error = std::numeric_limits<double>::quiet_NaN();     // [m] when truth exists
  double orientation_error = std::numeric_limits<double>::quiet_NaN();  // [rad]
  // The same errors per axis of the true object frame (estimate − truth), so the degrees of
  // freedom the fingers leave unobservable (along and about a bottle's axis) can be read apart.
  Vec3 position_error_O = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // [m]
  Vec3 orientation_error_O =
      Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // [rad], R_gtᵀ R̂ = Exp(·)
  double step_time_us = 0.0;
  double penetration = 0.0;  // [m] FilterTrace::penetration: the deepest link inside the estimate
  double unexplained_torque = 0.0;  // [N m] FilterTrace::unexplained_torque (sets with torques)
  int constraints = 0;
  int contacts = 0;
  int gated = 0;                    // measurement blocks rejected by a gate in this sample
  double visual_mahalanobis = 0.0;  // mean over the features of the last visual update
  double nees =
      std::numeric_limits<double>::quiet_NaN();  // 6-D pose error against P, when truth exists
  double visual_ms = -1.0;  // last visual step (detection + update) when one ran at this sample
  int visual_used = 0;      // features used by it
  // What the HUD says beside the numbers (FrameComposer): the grip loosened (FilterTrace::
  // slipping); the extracted features are lost, the tags see the object elsewhere (VisualMemory).
  bool slipping = false;
  VisualMemory memory;
  Health health;        // Tracker::health() after this sample and its images
  PressEvidence press;  // Tracker::press_evidence(): the pressing finger most in the air
  // What the tracker reported at this sample (Tracker::TakeEvents), and, against the truth, the
  // NEES leaving its χ²₆ 99 % bound: an excursion begins when it rises beyond the bound and ends
  // once it has stayed within it for kNeesSettle.
  std::vector<TrackerEvent> events;
  bool nees_beyond = false;
  double nees_within_since = -1.0;  // [s] within the bound since (during an excursion)
};

constexpr double kNeesBound99 = 16.812;  // χ²₆ 99 %
constexpr double kNeesSettle = 0.1;      // [s]

// Fills the errors against the true pose and the NEES of the pose against its covariance P
// (6×6, the filter's error convention p = p̂ + δp, R = Exp(δθ) R̂).
void CompareWithTruth(const Transform& truth, const Mat6& P, EstimateRecord& r);
// The contact figures of a joint sample's trace (contacts, constraints, penetration, unexplained
// torque), as the step found them before any image fused at that sample.
void RecordContacts(const FilterTrace& trace, EstimateRecord& r);
// What `tracker` says after its last sample and its images, into r: pose, σ, biases, gated
// measurements, slipping, its visual memory, health and pressing evidence. Events and the visual
// step are the caller's.
void RecordTrackerState(const Tracker& tracker, EstimateRecord& r);
// The record with its comparison fields reset (no truth at its time).
EstimateRecord WithoutTruth(EstimateRecord r);

}  // namespace inhand::app
