#pragma once
// Internal: what a simulation draws from its seed before it runs (the world as it is, the
// camera, the session's constant errors) and what the session records of it (provenance, truth).
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/sessions/camera_sim.hpp"
#include "inhand/sessions/realism.hpp"
#include "inhand/sessions/simulator.hpp"
#include "scenarios.hpp"

namespace inhand::sim {

namespace fs = std::filesystem;

// The numbers of each noise profile (documented in sessions/FORMAT.md).
struct Noise {
  // Magnitudes of the initial estimate's error: a start from the tracking system (its error and
  // the markers' registration), and a start set by hand or purposely off (Scenario::Start).
  double tracked_position = 0.0;      // [m]
  double tracked_orientation = 0.0;   // [rad]
  double initial_position = 0.0;      // [m]
  double initial_orientation = 0.0;   // [rad]
  double bias_sigma = 0.0;            // [rad] constant joint biases ~ N(0, σ)
  double joint_sigma = 0.0;           // [rad] white noise per sample
  double torque_sigma = 0.0;          // [N m]
  double hand_eye_position = 0.0;     // [m] constant error of the recorded T_PC
  double hand_eye_orientation = 0.0;  // [rad]
  double pixel_sigma = 0.0;           // [grey levels]
  double blur_sigma = 0.0;            // [px]
  int occluders = 0;                  // extra objects between camera and hand
};

Noise NoiseFor(NoiseProfile p);

// Position [m] and orientation [rad] error of the initial estimate. Set too high (Exp. I), the
// position is off by the hand-set amount straight up and the orientation still by the tracker's.
std::pair<double, double> StartError(const Noise& n, Scenario::Start start);

// The project's assets: $INHAND_ASSETS when set, else an installation's PREFIX/share/inhand/
// assets (found from the executable or Python module holding this code), else the source
// tree's. Throws InputError naming the places tried.
std::string AssetDir();

// A file's bytes (empty when it cannot be read).
std::string ReadBinary(const fs::path& p);

// The session's random draws. Each realism effect draws from its own stream, so that switching
// one leaves the others' draws alone; the session's constant errors and the noise of the
// recording draw from the main one. One normal distribution serves every stream: it keeps a spare
// value between calls, so the order of the draws (DrawWorld, DrawCamera, the start error, then
// the recording) is part of what a seed means.
struct Draws {
  explicit Draws(unsigned s) : seed(s), main(s * 7919u + 17u) {}
  std::mt19937 ForEffect(Effect e) const {
    std::seed_seq seq{seed, 0x5eedu, static_cast<unsigned>(e)};
    return std::mt19937(seq);
  }
  unsigned seed;
  std::mt19937 main;
  std::normal_distribution<double> gauss{0.0, 1.0};
};

// The models the session states (copied into it), and where they come from.
struct Models {
  fs::path hand_dir, object_dir;
  HandModel hand;
  ObjectModel object;
};

Models LoadModels(const Scenario& scenario);

// The world as it is where it differs from the models (realism.hpp: not the same under the
// `realistic` profile), and the session's constant errors.
struct TrueWorld {
  ObjectModel object;
  Vec3 object_scale = Vec3::Ones(), colour_gains = Vec3::Ones();
  std::optional<SimplifiedModel> simplified;  // the model the session states, when simplified
  HandModel hand;
  std::vector<Vec3> joint_origin_offsets;
  Eigen::VectorXd stiffness;                         // [N m/rad] each joint's true stiffness
  Eigen::VectorXd bias;                              // [rad] q_true = q_meas + bias
  Transform hand_eye_error = Transform::Identity();  // T_PC_recorded = T_PC_true * error
};

TrueWorld DrawWorld(const Models& models, const Noise& noise, const Effects& effects,
                    const RealismParams& rp, Draws& d);

// The camera, fixed in the world and looking at the workspace: the true intrinsics (K renders,
// K_lens adds the lens' distortion) and what the session says about them (K_session).
struct CameraSetup {
  Intrinsics K, K_session, K_lens;
  Transform T_WC = Transform::Identity();
};

CameraSetup DrawCamera(const SimulateOptions& opt, const Scenario& scenario, const Effects& effects,
                       Draws& d);

// What the session's provenance records: the generator, its rates and the noise and realism
// parameters it drew from.
jsonf::Json Provenance(const SimulateOptions& opt, const Scenario& scenario, double duration,
                       const Noise& noise, const std::pair<double, double>& start_error,
                       const Effects& effects, bool camera_sim);

// The truth of a session beside what it records (truth/truth.json): the errors drawn, the world's
// realism and the summary's checks.
jsonf::Json TruthJson(const TrueWorld& w, const ObjectModel& model_object,
                      const CameraSetup& camera, const LightRig* light, bool images,
                      const Effects& effects, const RealismParams& rp, const Transform& T_PO0,
                      const SimulationSummary& summary);

}  // namespace inhand::sim
