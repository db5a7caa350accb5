#pragma once
// The `realistic` noise profile: a simulated world that is not the estimator's model. Every
// effect can be switched on or off on its own (`inhand simulate --effects` / `--without`); the
// numbers are RealismParams' defaults, documented in sessions/FORMAT.md.
//
//  - The object is not its model: per-axis scale, tags glued off their declared placement,
//    slightly different colours and label texture; the estimator gets a simplified mesh with a
//    convex decomposition of its own.
//  - The hand is not its URDF: joint origins off, joints that deflect under load (the encoder
//    reads the motor side), soft fingertip pads.
//  - The torques are not the contact part: drifting offsets, friction and gravity residue, lag.
//  - The camera is not our renderer (CameraSimulator, camera_sim.hpp): its own light rig with
//    cast shadows and specular highlights relighting the scene's albedo, exposure and
//    white-balance drift, vignetting, lens distortion, motion blur, shot and read noise, JPEG;
//    the session's intrinsics and distortion coefficients off from the true ones.
#include <array>
#include <bitset>
#include <random>
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand {

enum class Effect {
  kObjectScale,
  kObjectTags,
  kObjectColour,
  kHandGeometry,
  kHandDeflection,
  kHandPads,
  kTorqueDrift,
  kTorqueResidue,
  kTorqueLag,
  kCameraLight,
  kCameraExposure,
  kCameraVignetting,
  kCameraDistortion,
  kCameraMotionBlur,
  kCameraSensorNoise,
  kCameraJpeg,
  kCameraIntrinsics,
  kObjectMesh,  // after the others: each effect's random stream is seeded by its value
  kCount
};
const char* EffectName(Effect effect);  // "object.scale", "camera.jpeg", ...

class Effects {
 public:
  static Effects All();
  static Effects None() { return {}; }
  // A comma-separated list of effect names; "camera" (a group name) stands for every camera.*
  // effect, "all" for every effect. Throws InputError naming `option` and the unknown name.
  static Effects Parse(const std::string& list, const std::string& option);
  bool Has(Effect e) const { return bits_[static_cast<std::size_t>(e)]; }
  void Set(Effect e, bool on) { bits_[static_cast<std::size_t>(e)] = on; }
  Effects Without(const Effects& other) const;
  bool Any() const { return bits_.any(); }
  bool AnyCamera() const;  // an effect that needs the camera simulation
  std::vector<std::string> Names() const;

 private:
  std::bitset<static_cast<std::size_t>(Effect::kCount)> bits_;
};

struct RealismParams {
  // The object.
  double scale_sigma = 0.005;                 // per-axis relative scale error
  double tag_position = 0.0005;               // [m] in a random direction in the tag's plane
  double tag_orientation = 1.0 * M_PI / 180;  // [rad] about a random axis
  double colour_sigma = 0.04;      // relative gain per colour channel (material and texture)
  double simplify_fraction = 0.4;  // the estimator's mesh: this share of the triangles,
  double simplify_error = 0.001;   // [m] unless a collapse would move the surface further
  double slab = 0.02;              // [m] its own convex decomposition: slabs this thick
  int max_slabs = 8;               //     across each solid's longest axis, at most this many
  // The hand.
  double joint_origin_sigma = 0.0003;  // [m] per axis of every joint origin (link lengths)
  double joint_stiffness = 20.0;       // [N m/rad] q_motor = q_link + tau / k, nominal (the
                                       // session's hand.joint_stiffness)
  double joint_stiffness_sigma = 0.2;  // each joint's true k: nominal · exp(σ g), g ~ N(0, 1)
  double pad_stiffness = 20000.0;      // [N/m] fingertip pads (distal links)
  double pad_damping = 400.0;          // [N s/m]
  // The torques.
  double drift_sigma = 0.05;        // [N m] stationary std of the offset per joint
  double drift_time = 10.0;         // [s] its correlation time (Ornstein-Uhlenbeck)
  double friction_residue = 0.02;   // [N m] Coulomb friction left in the estimate
  double friction_velocity = 0.05;  // [rad/s] its smoothing (tanh(q̇ / v))
  double gravity_residue = 0.3;     // share of the fingers' gravity torque left in it
  double torque_lag = 0.02;         // [s] extra first-order lag of the estimate
  // The camera.
  double intrinsics_scale_sigma = 0.005;  // relative error of the session's fx, fy
  double intrinsics_centre_sigma = 2.0;   // [px] of its cx, cy
  std::array<double, 5> distortion{-0.12, 0.05, 0.0004, -0.0003, 0.0};  // true k1 k2 p1 p2 k3
  double distortion_error = 0.05;     // relative error of the session's coefficients
  double exposure_sigma = 0.08;       // relative, per frame (AR(1), correlation 0.8)
  double white_balance_sigma = 0.03;  // relative per channel, per frame (AR(1), 0.8)
  double vignetting = 0.35;           // brightness loss at the image corners
  double exposure_time = 0.008;       // [s] motion blur: sub-frames over this window
  int blur_subframes = 3;
  double full_well = 6000.0;  // [e-] at white: shot noise sqrt(signal)
  double read_noise = 8.0;    // [e-]
  int jpeg_quality = 85;
};

// The world's object: scaled per axis in the object frame (pieces become hulls; mass with the
// volume, inertia with the squares of the sizes; contact field dropped).
ObjectModel ScaledObject(const ObjectModel& object, const Vec3& scale);
// Colour gains (r, g, b) on every visual material and texture.
void TintObject(ObjectModel& object, const Vec3& gains);
// Every tag moved by `position` in its plane and turned by `orientation` about a random axis.
void MisplaceTags(ObjectModel& object, double position, double orientation, std::mt19937& rng);
// A direction drawn uniformly on the unit sphere (a normal 3-vector, normalised; a fresh
// distribution, so that no value is kept from one call to the next).
Vec3 RandomUnitVector(std::mt19937& rng);
// The estimator's object when it is not the world's (Effect::kObjectMesh): the model's visual
// meshes simplified (SimplifyMesh) and a convex decomposition of its own (SlabHulls of the
// simplified meshes), as files for the session's model folder that replace the model's own:
// "simplified.obj", "simplified.mtl", "simplified_pieces.obj", and object.json (the model's,
// read from `object_json`, with "visual" and "collision" pointing at them; textures are named
// relative to `object_dir`, the folder the model was loaded from and copied with).
struct SimplifiedModel {
  std::vector<std::pair<std::string, std::string>> files;  // name in the folder, contents
  std::size_t triangles_before = 0, triangles_after = 0;
  std::size_t pieces_before = 0, pieces_after = 0;
};
SimplifiedModel SimplifyModel(const ObjectModel& model, const std::string& object_json,
                              const std::string& object_dir, const RealismParams& params);
// Joint origins moved by N(0, sigma) per axis; the offsets (per joint, in its parent link's
// frame) go to `offsets` when given.
HandModel PerturbedHand(const HandModel& hand, double sigma, std::mt19937& rng,
                        std::vector<Vec3>* offsets = nullptr);

// What the "external" torque estimate adds to the true contact torque.
class TorqueErrors {
 public:
  TorqueErrors(int joints, const RealismParams& params, const Effects& effects, std::mt19937& rng);
  // One step of dt: the estimate of `tau_contact` given the joint velocities and the fingers'
  // gravity torque.
  Eigen::VectorXd Step(double dt, const Eigen::VectorXd& tau_contact, const Eigen::VectorXd& q_dot,
                       const Eigen::VectorXd& tau_gravity);
  const Eigen::VectorXd& offsets() const { return drift_; }

 private:
  RealismParams params_;
  Effects effects_;
  std::mt19937 rng_;
  Eigen::VectorXd drift_, lagged_;
  bool started_ = false;
};

}  // namespace inhand
