#pragma once
// The filter's parameters, with units and defaults. Validate() names the field, its value and
// the constraint; JSON round-trips every field (replay --params, echoed into outputs).
#include <string>

#include "inhand/filter/chi2.hpp"

namespace inhand {

struct FilterParams {
  // Units in brackets; why each default is what it is, with the figures, in docs/evaluation.md
  // ("Parameters").
  // --- contacts (docs/estimator.md, "Contacts")
  double contact_sigma = 0.015;                // [m] σ of the zero-distance constraint, per axis,
                                               // applied at every joint sample: the per-step σ of
                                               // an error that persists (biases, geometry)
  bool contact_normal_only = true;             // true: along the contact normal only (sliding
                                               // allowed); false: the paper's 3-D constraint,
                                               // which pins tangential directions a closest-point
                                               // pair cannot observe (overconfident)
  int contact_iterations = 1;                  // 1: one update per step (paper); >1: re-run GJK
                                               // and update again (iterated EKF)
  double contact_model_sigma = 0.002;          // [m] floor on what contact constraints may claim:
                                               // the variance along a constraint's normal stays
                                               // >= this² as far as contacts are concerned (the
                                               // same geometry error recurs at every step);
                                               // normal-only constraints; 0 disables
  double contact_gate_chi2 = 0.0;              // Mahalanobis gate per contact; 0 disables
  double prediction_contact_distance = 0.001;  // [m] pairs this close (or penetrating) move the
                                               // object with the fingers in Predict
  // --- torque contacts (paper Sec. III-B)
  double torque_candidate_distance = 0.003;  // [m] closest pairs within this distance are
                                             // candidates (farther ones let torques pull links
                                             // that do not touch onto the object)
  double friction_cone_deg = 45.0;           // [deg] half-angle around the inward normal
  double force_min = 2.0;                    // [N] smaller estimated forces are ignored
  double torque_damping = 1e-6;              // [m²] damping of (J_cᵀ)⁺
  double torque_distance_scale = 0.0005;     // [m] weighted pseudo-inverse: a candidate at
                                             // distance d costs (1 + (d/scale)²) per unit force,
                                             // so each finger's touching link explains its
                                             // torques first (beyond the paper); 0: the paper's
                                             // plain (J_cᵀ)⁺
  // --- prediction
  double twist_damping = 3e-3;        // damping of the grasp-map pseudo-inverse, relative
                                      // to the mean eigenvalue of its normal matrix:
                                      // nearly collinear contacts must not turn joint
                                      // noise into rotations
  double process_position = 0.002;    // [m/√s] random walk of the object position
  double process_orientation = 0.02;  // [rad/√s] random walk of the object orientation
  double process_bias = 0.0;          // [rad/√s] random walk of the joint biases
  double motion_position = 0.2;       // σ added per metre of predicted translation [1]
  double motion_orientation = 0.2;    // σ added per radian of predicted rotation [1]
  double travel_orientation = 2e-4;   // [m] the orientation's variance grows by this · D ·
                                      // Γ⁻¹ per 50 ms window, D the largest displacement of
                                      // a contact point over the window, Γ the object's
                                      // gyration tensor (FilterOptions; without it, off):
                                      // fingertips roll a thin object about its axis,
                                      // which the damped prediction does not follow;
                                      // 0 disables
  double slip_torque = 2.0;           // [N m] with torques: once the hand has gripped
                                      // this hard (Σ|τ| over the joints), a grip below it
                                      // may let the object slip, which the no-slip
                                      // prediction cannot follow: the random walk grows
                                      // by slip_scale (beyond the paper). From the torques
                                      // alone, not from contacts at the estimate, which
                                      // vanish as it drifts; 0 disables
  double slip_scale = 30.0;           // [1] factor on the random walk's σ while slipping
  // --- visual features (paper Sec. III-C)
  double pixel_sigma = 4.0;                 // [px] σ of a feature's pixel: detection noise and
                                            // the camera pose's error (0.5 deg of hand-eye
                                            // error is 5 px at 640x480, 45 deg fov)
  double visual_gate_chi2 = chi2::k2Dof99;  // χ²₂ at 99 %
  double visual_model_sigma = 4.0;          // [px] floor on what vision may claim: the variance
                                            // of a predicted pixel stays >= this² as far as
                                            // visual updates are concerned (calibration,
                                            // hand-eye and model errors recur in every frame);
                                            // 0 disables
  double camera_position_sigma = 0.0;       // [m] σ per axis of the camera pose's error (hand-
  double camera_orientation_sigma = 0.0;    // [rad] eye calibration): a state of its own, the
                                            // same for every feature and every frame (beyond
                                            // the paper; both 0: independent features, as in
                                            // the paper; off by default, docs/evaluation.md)

  // Throws InputError("SOURCE: parameter 'NAME' is V, expected ...").
  void Validate(const std::string& source = "filter parameters") const;
};

std::string FilterParamsToJson(const FilterParams& params);
// Unknown fields are errors (a typo must not silently keep a default). Validates.
FilterParams FilterParamsFromJson(const std::string& json_text, const std::string& source);

}  // namespace inhand
