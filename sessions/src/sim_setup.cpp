#include "sim_setup.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/install_dirs.hpp"

namespace inhand::sim {
namespace {

const char* StartName(Scenario::Start start) {
  switch (start) {
    case Scenario::Start::kTracked:
      return "tracked";
    case Scenario::Start::kTooHigh:
      return "too_high";
    case Scenario::Start::kByHand:
      return "by_hand";
  }
  return "?";
}

}  // namespace

Noise NoiseFor(NoiseProfile p) {
  Noise n;
  if (p == NoiseProfile::kNone) return n;
  n.tracked_position = 0.002;
  n.tracked_orientation = 1.0 * M_PI / 180;
  n.initial_position = 0.020;
  n.initial_orientation = 5.0 * M_PI / 180;
  n.bias_sigma = 3.0 * M_PI / 180;
  n.joint_sigma = 0.1 * M_PI / 180;
  n.torque_sigma = 0.02;
  n.hand_eye_position = 0.002;
  n.hand_eye_orientation = 0.5 * M_PI / 180;
  n.pixel_sigma = 3.0;
  n.blur_sigma = 0.7;
  if (p == NoiseProfile::kHard) {
    n.initial_position *= 2;
    n.initial_orientation *= 2;
    n.tracked_position = n.initial_position;  // no tracker: every start as if set by hand
    n.tracked_orientation = n.initial_orientation;
    n.bias_sigma *= 2;
    n.joint_sigma *= 2;
    n.torque_sigma *= 2;
    n.hand_eye_position *= 2;
    n.hand_eye_orientation *= 2;
    n.pixel_sigma *= 2;
    n.blur_sigma *= 2;
    n.occluders = 2;
  }
  return n;
}

std::pair<double, double> StartError(const Noise& n, Scenario::Start start) {
  switch (start) {
    case Scenario::Start::kTracked:
      return {n.tracked_position, n.tracked_orientation};
    case Scenario::Start::kTooHigh:
      return {n.initial_position, n.tracked_orientation};
    case Scenario::Start::kByHand:
      return {n.initial_position, n.initial_orientation};
  }
  return {0.0, 0.0};
}

std::string AssetDir() {
  if (const char* env = std::getenv("INHAND_ASSETS"); env && *env) return env;
  // Installed: the code is PREFIX/bin/inhand or the Python module in PREFIX/lib/python3.X/
  // dist-packages; the assets are in PREFIX/share/inhand/assets.
  const std::vector<fs::path> tried = BesideRunningCode("share/inhand/assets");
  for (const fs::path& dir : tried)
    if (fs::is_directory(dir / "hands")) return dir.string();
  // The build tree: the source tree's assets.
  if (fs::is_directory(fs::path(INHAND_ASSET_DIR) / "hands")) return INHAND_ASSET_DIR;
  std::string message = "the project's assets (hands/, objects/) are not in";
  for (const fs::path& p : tried) message += " " + p.string() + ",";
  throw InputError(message + " nor in " + INHAND_ASSET_DIR +
                   "; set INHAND_ASSETS to the folder that holds them");
}

std::string ReadBinary(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Models LoadModels(const Scenario& scenario) {
  Models m;
  const std::string assets = AssetDir();
  m.hand_dir = fs::path(assets) / "hands" / "inhand_hand";
  m.object_dir = fs::path(assets) / "objects" / scenario.object;
  m.hand = LoadHandModel((m.hand_dir / "inhand_hand.urdf").string());
  m.object = LoadObjectModel((m.object_dir / "object.json").string());
  return m;
}

TrueWorld DrawWorld(const Models& models, const Noise& noise, const Effects& effects,
                    const RealismParams& rp, Draws& d) {
  TrueWorld w;
  const int m = models.hand.num_q();
  w.object = models.object;
  if (effects.Has(Effect::kObjectScale)) {
    std::mt19937 r = d.ForEffect(Effect::kObjectScale);
    for (int a = 0; a < 3; ++a) w.object_scale[a] = 1.0 + rp.scale_sigma * d.gauss(r);
    w.object = ScaledObject(models.object, w.object_scale);
  }
  if (effects.Has(Effect::kObjectTags)) {
    std::mt19937 r = d.ForEffect(Effect::kObjectTags);
    MisplaceTags(w.object, rp.tag_position, rp.tag_orientation, r);
  }
  if (effects.Has(Effect::kObjectColour)) {
    std::mt19937 r = d.ForEffect(Effect::kObjectColour);
    for (int c = 0; c < 3; ++c) w.colour_gains[c] = 1.0 + rp.colour_sigma * d.gauss(r);
    TintObject(w.object, w.colour_gains);
  }
  // The estimator's model is simplified, the world keeps the detailed one.
  if (effects.Has(Effect::kObjectMesh))
    w.simplified = SimplifyModel(models.object, ReadBinary(models.object_dir / "object.json"),
                                 models.object_dir.string(), rp);
  w.hand = models.hand;
  if (effects.Has(Effect::kHandGeometry)) {
    std::mt19937 r = d.ForEffect(Effect::kHandGeometry);
    w.hand = PerturbedHand(models.hand, rp.joint_origin_sigma, r, &w.joint_origin_offsets);
  }
  // Each joint's true stiffness, around the nominal one the session states (a maker's figure,
  // or a calibration): log-normal, so that it stays positive.
  w.stiffness = Eigen::VectorXd::Constant(m, rp.joint_stiffness);
  if (effects.Has(Effect::kHandDeflection)) {
    std::mt19937 r = d.ForEffect(Effect::kHandDeflection);
    std::normal_distribution<double> g(0.0, 1.0);  // its own: no value cached from another stream
    for (int j = 0; j < m; ++j)
      w.stiffness[j] = rp.joint_stiffness * std::exp(rp.joint_stiffness_sigma * g(r));
  }
  w.bias.resize(m);
  for (int j = 0; j < m; ++j) w.bias[j] = noise.bias_sigma * d.gauss(d.main);
  w.hand_eye_error = MakeTransform(noise.hand_eye_position * RandomUnitVector(d.main),
                                   ExpSO3(noise.hand_eye_orientation * RandomUnitVector(d.main)));
  return w;
}

CameraSetup DrawCamera(const SimulateOptions& opt, const Scenario& scenario, const Effects& effects,
                       Draws& d) {
  const RealismParams& rp = opt.realism;
  CameraSetup c;
  c.K.width = opt.image_width;
  c.K.height = opt.image_height;
  c.K.fx = c.K.fy = 580.0 * opt.image_width / 640.0;
  c.K.cx = 0.5 * opt.image_width - 0.5;
  c.K.cy = 0.5 * opt.image_height - 0.5;
  c.T_WC = LookAt(scenario.camera_eye, scenario.camera_target, Vec3::UnitZ());
  c.K_session = c.K_lens = c.K;
  if (effects.Has(Effect::kCameraDistortion)) {
    std::mt19937 r = d.ForEffect(Effect::kCameraDistortion);
    for (std::size_t i = 0; i < 5; ++i) {
      c.K_lens.distortion[i] = rp.distortion[i];
      c.K_session.distortion[i] = rp.distortion[i] * (1.0 + rp.distortion_error * d.gauss(r));
    }
  }
  if (effects.Has(Effect::kCameraIntrinsics)) {
    std::mt19937 r = d.ForEffect(Effect::kCameraIntrinsics);
    c.K_session.fx *= 1.0 + rp.intrinsics_scale_sigma * d.gauss(r);
    c.K_session.fy *= 1.0 + rp.intrinsics_scale_sigma * d.gauss(r);
    c.K_session.cx += rp.intrinsics_centre_sigma * d.gauss(r);
    c.K_session.cy += rp.intrinsics_centre_sigma * d.gauss(r);
  }
  return c;
}

jsonf::Json Provenance(const SimulateOptions& opt, const Scenario& scenario, double duration,
                       const Noise& noise, const std::pair<double, double>& start_error,
                       const Effects& effects, bool camera_sim) {
  const RealismParams& rp = opt.realism;
  jsonf::Json provenance = {{"generator", "inhand simulate"},
                            {"scenario", scenario.name},
                            {"seed", opt.seed},
                            {"noise", NoiseProfileName(opt.noise)},
                            {"physics_rate", opt.physics_rate},
                            {"joint_rate", opt.joint_rate},
                            {"camera_rate", opt.camera_rate},
                            {"duration", duration},
                            {"noise_parameters",
                             {{"start", StartName(scenario.start)},
                              {"initial_position_m", start_error.first},
                              {"initial_orientation_rad", start_error.second},
                              {"bias_sigma_rad", noise.bias_sigma},
                              {"joint_sigma_rad", noise.joint_sigma},
                              {"torque_sigma_Nm", noise.torque_sigma},
                              {"hand_eye_position_m", noise.hand_eye_position},
                              {"hand_eye_orientation_rad", noise.hand_eye_orientation},
                              {"pixel_sigma", noise.pixel_sigma},
                              {"blur_sigma_px", camera_sim ? 0.0 : noise.blur_sigma},
                              {"pixel_sigma_effective", camera_sim ? 0.0 : noise.pixel_sigma},
                              {"occluders", noise.occluders},
                              {"effects", effects.Names()}}}};
  if (effects.Any())
    provenance["realism"] = {{"scale_sigma", rp.scale_sigma},
                             {"tag_position_m", rp.tag_position},
                             {"tag_orientation_rad", rp.tag_orientation},
                             {"colour_sigma", rp.colour_sigma},
                             {"joint_origin_sigma_m", rp.joint_origin_sigma},
                             {"joint_stiffness_Nm_per_rad", rp.joint_stiffness},
                             {"joint_stiffness_sigma", rp.joint_stiffness_sigma},
                             {"pad_stiffness_N_per_m", rp.pad_stiffness},
                             {"pad_damping_Ns_per_m", rp.pad_damping},
                             {"torque_drift_sigma_Nm", rp.drift_sigma},
                             {"torque_drift_time_s", rp.drift_time},
                             {"friction_residue_Nm", rp.friction_residue},
                             {"gravity_residue", rp.gravity_residue},
                             {"torque_lag_s", rp.torque_lag},
                             {"intrinsics_scale_sigma", rp.intrinsics_scale_sigma},
                             {"intrinsics_centre_sigma_px", rp.intrinsics_centre_sigma},
                             {"distortion_error", rp.distortion_error},
                             {"exposure_sigma", rp.exposure_sigma},
                             {"white_balance_sigma", rp.white_balance_sigma},
                             {"vignetting", rp.vignetting},
                             {"exposure_time_s", rp.exposure_time},
                             {"blur_subframes", rp.blur_subframes},
                             {"full_well_e", rp.full_well},
                             {"read_noise_e", rp.read_noise},
                             {"jpeg_quality", rp.jpeg_quality}};
  return provenance;
}

jsonf::Json TruthJson(const TrueWorld& w, const ObjectModel& model_object,
                      const CameraSetup& camera, const LightRig* light, bool images,
                      const Effects& effects, const RealismParams& rp, const Transform& T_PO0,
                      const SimulationSummary& summary) {
  const HandModel& hand = w.hand;
  const int m = hand.num_q();
  jsonf::Json biases = jsonf::Json::object();
  for (int j = 0; j < m; ++j) biases[hand.QJoint(j).name] = w.bias[j];
  jsonf::Json realism = {{"effects", effects.Names()}};
  const Vec3 world_size = w.object.Bounds().Size(), model_size = model_object.Bounds().Size();
  realism["world_object_size_m"] = {world_size.x(), world_size.y(), world_size.z()};
  realism["model_object_size_m"] = {model_size.x(), model_size.y(), model_size.z()};
  if (effects.Has(Effect::kObjectScale))
    realism["object_scale"] = {w.object_scale.x(), w.object_scale.y(), w.object_scale.z()};
  if (w.simplified)
    realism["simplified_model"] = {{"triangles", w.simplified->triangles_after},
                                   {"model_triangles", w.simplified->triangles_before},
                                   {"pieces", w.simplified->pieces_after},
                                   {"model_pieces", w.simplified->pieces_before}};
  if (effects.Has(Effect::kObjectColour))
    realism["colour_gains_rgb"] = {w.colour_gains.x(), w.colour_gains.y(), w.colour_gains.z()};
  if (effects.Has(Effect::kObjectTags)) {
    jsonf::Json tags = jsonf::Json::array();
    for (const TagPlacement& t : w.object.tags)
      tags.push_back({{"id", t.id}, {"true_pose", jsonf::PoseToJson(t.T_OT)}});
    realism["tags"] = tags;
  }
  if (effects.Has(Effect::kHandGeometry)) {
    jsonf::Json offsets = jsonf::Json::object();
    for (std::size_t j = 0; j < hand.joints.size(); ++j)
      offsets[hand.joints[j].name] = {w.joint_origin_offsets[j].x(), w.joint_origin_offsets[j].y(),
                                      w.joint_origin_offsets[j].z()};
    realism["joint_origin_offsets_m"] = offsets;
  }
  if (effects.Has(Effect::kHandDeflection)) {
    jsonf::Json ks = jsonf::Json::object();
    const std::vector<std::string> q_names = hand.QNames();
    for (int j = 0; j < m; ++j) ks[q_names[static_cast<std::size_t>(j)]] = w.stiffness[j];
    realism["joint_stiffness_Nm_per_rad"] = ks;
    realism["nominal_joint_stiffness_Nm_per_rad"] = rp.joint_stiffness;
    realism["deflection_convention"] =
        "q_motor (recorded, before bias and noise) = q_link + tau_contact / k";
  }
  if (images) {
    realism["true_intrinsics"] = {
        {"fx", camera.K_lens.fx},
        {"fy", camera.K_lens.fy},
        {"cx", camera.K_lens.cx},
        {"cy", camera.K_lens.cy},
        {"distortion",
         {camera.K_lens.distortion[0], camera.K_lens.distortion[1], camera.K_lens.distortion[2],
          camera.K_lens.distortion[3], camera.K_lens.distortion[4]}}};
    if (light) realism["lamp"] = {light->lamp.x(), light->lamp.y(), light->lamp.z()};
  }
  return {{"joint_biases_rad", biases},
          {"bias_convention", "q_true = q_meas + bias"},
          {"hand_eye_error", jsonf::PoseToJson(w.hand_eye_error)},
          {"hand_eye_convention", "T_PC_recorded = T_PC_true * error"},
          {"true_initial_T_PO", jsonf::PoseToJson(T_PO0)},
          {"max_penetration_m", summary.max_penetration},
          {"held_fraction", summary.held_fraction},
          {"tilt_in_hand_deg", summary.tilt_in_hand_deg},
          {"max_in_hand_rotation_deg", summary.max_in_hand_rotation_deg},
          {"table_travel_before_grasp_m", summary.table_travel_before_grasp},
          {"lift_height_m", summary.lift_height},
          {"realism", realism}};
}

}  // namespace inhand::sim
