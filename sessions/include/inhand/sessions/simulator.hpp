#pragma once
// Synthetic sessions with known truth: the paper's five experiments simulated with Bullet
// dynamics (double precision) and rendered with the project's renderer.
//
// The hand is torque-controlled by emulation: every link is a kinematic body driven by a joint
// admittance loop, q̇ = (τ_motor − τ_contact) / B with τ_motor = clamp(K (q_target − q), ±τ_max),
// where τ_contact = Σ J_cᵀ λ is computed from the solver's contact impulses. A finger thus moves
// freely towards its target, stops where the contact torque balances its bounded motor torque,
// and yields when pushed harder: a torque-limited, compliant finger. The recorded torques are
// that contact part (sessions/FORMAT.md: "external"). The palm follows a scripted trajectory in
// the world (the arm); the object is a dynamic rigid body (convex pieces, mass, inertia,
// friction) on a table under gravity; the camera is fixed in the world (the robot's head).
#include <optional>
#include <string>
#include <vector>

#include "inhand/core/so3.hpp"
#include "inhand/sessions/realism.hpp"

namespace inhand {

// `realistic`: the paper's noise plus every effect of realism.hpp (the world is not the model).
enum class NoiseProfile { kNone, kPaper, kHard, kRealistic };
NoiseProfile ParseNoiseProfile(const std::string& name);  // throws InputError
const char* NoiseProfileName(NoiseProfile profile);

struct ScenarioInfo {
  std::string name;
  std::string description;
  double duration = 0.0;    // [s]
  std::string object_file;  // the object description it simulates (assets/objects/NAME/object.json)
};
std::vector<ScenarioInfo> ListScenarios();

struct SimulateOptions {
  std::string scenario;
  std::string out_dir;
  unsigned seed = 1;
  NoiseProfile noise = NoiseProfile::kPaper;
  bool overwrite = false;
  double physics_rate = 1000.0;  // [Hz]
  double joint_rate = 500.0;     // [Hz] recorded joint samples
  double camera_rate = 10.0;     // [Hz]
  int image_width = 640;
  int image_height = 480;
  bool images = true;           // false: joints only (fast tests)
  double duration_scale = 1.0;  // < 1 runs a shortened script (tests)
  // The realism effects (realism.hpp); unset: every effect for `realistic`, none otherwise.
  std::optional<Effects> effects;
  RealismParams realism;
};
// The effects a simulation runs with: `options.effects`, else the profile's own.
Effects EffectsOf(const SimulateOptions& options);

struct SimulationSummary {
  std::string session_dir;
  double duration = 0.0;   // simulated [s]
  double wall_time = 0.0;  // [s]
  int joint_samples = 0;
  int camera_frames = 0;
  double max_penetration = 0.0;   // [m] deepest finger/object penetration while recorded
  double held_fraction = 0.0;     // share of samples after the grasp with >= 2 links touching
  double tilt_in_hand_deg = 0.0;  // object rotation in the palm frame, closing start → end
  double max_in_hand_rotation_deg = 0.0;
  double table_travel_before_grasp = 0.0;  // [m] object motion on the table before closing
  double lift_height = 0.0;                // [m] object height gain, start → end
};

// Simulates `options.scenario` and writes a v1 session (atomically). Throws InputError for an
// unknown scenario or an existing output without overwrite.
SimulationSummary Simulate(const SimulateOptions& options);

}  // namespace inhand
