#pragma once
// The filter's parameters, with units and defaults. Validate() names the field, its value and
// the constraint; JSON round-trips every field (replay --params, echoed into outputs).
#include <string>

#include "inhand/filter/chi2.hpp"

namespace inhand {

struct FilterParams {
  // --- contacts (estimator-math.md, kinematic update)
  double contact_sigma = 0.015;               // [m] σ of the zero-distance constraint, per axis.
                                              // Applied at every joint sample, so it is the
                                              // per-step σ of an error that is the same from one
                                              // step to the next (biases, geometry): with the
                                              // paper's "perfect" 1 mm the filter was
                                              // overconfident (mean NEES 100-2000) and torque
                                              // contacts cost accuracy. 10 mm was best of 1-10 mm
                                              // with starts 20 mm off; with the paper's starts
                                              // and the weighted torque pseudo-inverse, 12.5-20
                                              // mm are alike and 15 mm keeps j >= jt on every
                                              // scenario over 10 seeds (issue 7's notes)
  bool contact_normal_only = true;            // true: only along the contact normal (sliding
                                              // allowed); false: the paper's 3-D constraint,
                                              // which also pins the tangential directions a
                                              // closest-point pair cannot observe (a bottle's
                                              // axis) and makes the filter overconfident: mean
                                              // NEES in the thousands, tags gated away
  int contact_iterations = 1;                 // 1: one update per step (paper); >1: re-run GJK
                                              // and update again (iterated EKF)
  double contact_model_sigma = 0.002;         // [m] how well contact constraints can know the
                                              // object at all: the hand's and the object's
                                              // geometry errors, the same at every step. Applied
                                              // at joint rate, a constraint would otherwise count
                                              // 1000 independent measurements a second of that
                                              // one error. The variance along what a constraint
                                              // measures stays >= this² as far as contacts are
                                              // concerned: the information an update removes
                                              // below it is given back (never more than it
                                              // took, so what tags or the start knew is kept).
                                              // Fingers 3 mm too thick: the joint-only estimate
                                              // settled 6.6 mm off claiming σ 5 mm (NEES 30);
                                              // with 2 mm, NEES 10 (tests/filter/grasp_test.cpp).
                                              // Normal-only constraints; 0 disables
  double contact_gate_chi2 = 0.0;             // Mahalanobis gate per contact; 0 disables
  double prediction_contact_distance = 0.001; // [m] pairs this close (or penetrating) move the
                                              // object with the fingers in Predict
  // --- torque contacts (paper Sec. III-B)
  double torque_candidate_distance = 0.003;   // [m] closest pairs within this distance are
                                              // candidates; at 15 mm torques pulled far links
                                              // onto the object; 3 mm was best of 2-10 mm with
                                              // the damped twist and 10 mm contact σ, the only
                                              // value with j >= jt on every scenario. With the
                                              // weighted pseudo-inverse 2-10 mm are alike within
                                              // the seeds' scatter (issue 7's notes)
  double friction_cone_deg = 45.0;            // [deg] half-angle around the inward normal
  double force_min = 2.0;                     // [N] smaller estimated forces are ignored
  double torque_damping = 1e-6;               // [m²] damping of (J_cᵀ)⁺
  double torque_distance_scale = 0.0005;      // [m] weighted pseudo-inverse: a candidate at
                                              // distance d costs (1 + (d/scale)²) per unit force,
                                              // so torques are explained by touching links first
                                              // (beyond the paper). With the paper's (J_cᵀ)⁺ (0
                                              // here) a link 14 mm from the object took a share
                                              // of the distal link's torques, bent the touching
                                              // link's force out of its cone and was accepted
                                              // itself; at the true pose of a held object the
                                              // weighted forces are ~0 N on links that do not
                                              // touch. jt on a pinched brush: 18 mm -> 9 mm
  // --- prediction
  double twist_damping = 3e-3;                // damping of the grasp-map pseudo-inverse,
                                              // relative to the mean eigenvalue of its normal
                                              // matrix: with nearly collinear contacts the
                                              // undamped (1e-8) solve turned joint noise into
                                              // 1 deg per step and once a 65 deg jump in one step
                                              // (evaluation in issue 7's note)
  double process_position = 0.002;            // [m/√s] random walk of the object position
  double process_orientation = 0.02;          // [rad/√s] random walk of the object orientation
  double process_bias = 0.0;                  // [rad/√s] random walk of the joint biases
  double motion_position = 0.2;               // σ added per metre of predicted translation [1]
  double motion_orientation = 0.2;            // σ added per radian of predicted rotation [1]
  double travel_orientation = 2e-4;           // [m] the orientation's variance grows with the
                                              // fingers' travel at the contacts: by this · D ·
                                              // Γ⁻¹ per 50 ms window, D the largest displacement of
                                              // a contact point over the window (jitter cancels
                                              // within it, so the growth does not depend on the
                                              // joint rate), Γ the object's gyration tensor
                                              // (FilterOptions; without it, off). A pen (Γ about
                                              // its axis 15 mm²) is rolled by fingertips the
                                              // damped prediction does not follow; a bottle (600
                                              // mm²) is barely turned by fingers closing round it.
                                              // Chosen on paper noise, seeds 1-5, 1e-4 / 2e-4 /
                                              // 5e-4 against 0: pen j NEES 70 -> 9 / 7 / 5; brush
                                              // jtf 7.7 mm / 4.3 deg (NEES 16) -> 7.7 / 11.3 (10),
                                              // 5.5 / 0.8 (7), 5.0 / 1.2 (7); but pen jtf
                                              // orientation 52.6 -> 49 / 62 / 92 deg and ketchup jt
                                              // position 15.5 -> 19.7 / 21.4 / 20.6 mm. Over both
                                              // profiles and seeds 101-105 too, NEES within [2, 15]
                                              // on 66 of 76 sets, 56 before it and the
                                              // tracker's lost-object search (README); 0 disables
  double slip_torque = 2.0;                   // [N m] with torques: once the hand has gripped
                                              // this hard (Σ|τ| over the joints), a grip below it
                                              // may let the object slip, which the no-slip
                                              // prediction cannot follow: the random walk grows
                                              // by slip_scale (beyond the paper; the ketchup
                                              // bottle turns 17 deg in a loosened grip). From the
                                              // torques alone, not from contacts at the estimate,
                                              // which vanish as it drifts. 0.5-4 evaluated;
                                              // 0 disables
  double slip_scale = 30.0;                   // [1] factor on the random walk's σ while slipping
  // --- visual features (paper Sec. III-C)
  double pixel_sigma = 4.0;                   // [px] σ of a feature's pixel: detection noise
                                              // and the camera pose's error (0.5 deg of hand-eye
                                              // error is 5 px at 640x480, 45 deg fov); 4 px beat
                                              // 2, 5, 8 and 10 for tags and extracted features
  double visual_gate_chi2 = chi2::k2Dof99;   // χ²₂ at 99 %
  double visual_model_sigma = 4.0;            // [px] how well vision can know a feature's pixel
                                              // at all (camera calibration, hand-eye pose, object
                                              // model: the same error in every frame): the
                                              // variance of a predicted pixel stays >= this² as
                                              // far as visual updates are concerned (the
                                              // information removed below it is given back);
                                              // 0 disables
  double camera_position_sigma = 0.0;         // [m] σ per axis of the camera pose's error (hand-
  double camera_orientation_sigma = 0.0;      // [rad] eye calibration): a state of its own, the
                                              // same for every feature and every frame, so that a
                                              // common error is not counted once per feature
                                              // (beyond the paper; both 0: independent features,
                                              // as in the paper). 2 mm / 0.5 deg with 4 px, 4
                                              // scenarios x 5 seeds: mean NEES of jta/jtf 37 ->
                                              // 19 (ketchup 2, shampoo and water jta 5-6), jtf
                                              // terminal position 4.4 -> 2.8 mm, but water jta
                                              // 6.9 -> 9.2 mm and the pen's jtf 5.8 -> 13 mm (one
                                              // run in five 37 mm: early mismatches on the thin
                                              // pen are taken for a camera error): off by default

  // Throws InputError("SOURCE: parameter 'NAME' is V, expected ...").
  void Validate(const std::string& source = "filter parameters") const;
};

std::string FilterParamsToJson(const FilterParams& params);
// Unknown fields are errors (a typo must not silently keep a default). Validates.
FilterParams FilterParamsFromJson(const std::string& json_text, const std::string& source);

}  // namespace inhand
