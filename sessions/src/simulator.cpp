#include "inhand/sessions/simulator.hpp"

#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/printed_tags.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/camera_sim.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "inhand/sessions/session.hpp"
#include "scenarios.hpp"
#include "sim_world.hpp"

namespace fs = std::filesystem;

namespace inhand {

NoiseProfile ParseNoiseProfile(const std::string& name) {
  if (name == "none") return NoiseProfile::kNone;
  if (name == "paper") return NoiseProfile::kPaper;
  if (name == "hard") return NoiseProfile::kHard;
  if (name == "realistic") return NoiseProfile::kRealistic;
  throw InputError("noise profile '" + name +
                   "' is unknown, expected none, paper, hard or realistic");
}

const char* NoiseProfileName(NoiseProfile p) {
  switch (p) {
    case NoiseProfile::kNone:
      return "none";
    case NoiseProfile::kPaper:
      return "paper";
    case NoiseProfile::kHard:
      return "hard";
    case NoiseProfile::kRealistic:
      return "realistic";
  }
  return "?";
}

Effects EffectsOf(const SimulateOptions& options) {
  if (options.effects) return *options.effects;
  return options.noise == NoiseProfile::kRealistic ? Effects::All() : Effects::None();
}

namespace {

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

const char* StartName(sim::Scenario::Start start) {
  switch (start) {
    case sim::Scenario::Start::kTracked:
      return "tracked";
    case sim::Scenario::Start::kTooHigh:
      return "too_high";
    case sim::Scenario::Start::kByHand:
      return "by_hand";
  }
  return "?";
}

// Position [m] and orientation [rad] error of the initial estimate. Set too high (Exp. I), the
// position is off by the hand-set amount straight up and the orientation still by the tracker's.
std::pair<double, double> StartError(const Noise& n, sim::Scenario::Start start) {
  switch (start) {
    case sim::Scenario::Start::kTracked:
      return {n.tracked_position, n.tracked_orientation};
    case sim::Scenario::Start::kTooHigh:
      return {n.initial_position, n.tracked_orientation};
    case sim::Scenario::Start::kByHand:
      return {n.initial_position, n.initial_orientation};
  }
  return {0.0, 0.0};
}

std::string AssetDir() {
  if (const char* env = std::getenv("INHAND_ASSETS"); env && *env) return env;
  return INHAND_ASSET_DIR;
}

std::string ReadBinary(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Copies a model folder into the session, so the session is self-contained.
void CopyFolder(SessionWriter& w, const fs::path& from, const std::string& to) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(from))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files)
    w.AddFile(to + "/" + fs::relative(f, from).string(), ReadBinary(f));
}

// A flat textured rectangle (table top, backdrop) with a procedural pattern.
TriangleMesh TexturedBox(const Vec3& half, const cv::Mat& texture_bgr) {
  TriangleMesh m = ConvexPiece::Box(half, Transform::Identity()).ToMesh();
  m.uvs.clear();
  for (const Vec3& v : m.vertices)
    m.uvs.emplace_back(0.5 + 0.5 * v.x() / half.x(), 0.5 + 0.5 * v.y() / half.y());
  std::vector<std::uint8_t> png;
  cv::imencode(".png", texture_bgr, png);
  m.material.texture_blob = png;
  m.material.rgba = Eigen::Vector4d(1, 1, 1, 1);
  return m;
}

cv::Mat WoodTexture() {
  cv::Mat t(256, 256, CV_8UC3);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      const double g =
          0.5 + 0.5 * std::sin(0.09 * x + 2.5 * std::sin(0.021 * y) + 0.7 * std::sin(0.13 * y));
      t.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<std::uint8_t>(70 + 25 * g), static_cast<std::uint8_t>(110 + 30 * g),
                    static_cast<std::uint8_t>(150 + 35 * g));
    }
  return t;
}

cv::Mat ClutterTexture(std::mt19937& rng) {
  cv::Mat t(512, 512, CV_8UC3, cv::Scalar(200, 205, 210));
  std::uniform_int_distribution<int> pos(0, 511), size(20, 140), colour(30, 240);
  for (int i = 0; i < 60; ++i)
    cv::rectangle(t, cv::Rect(pos(rng), pos(rng), size(rng), size(rng)),
                  cv::Scalar(colour(rng), colour(rng), colour(rng)), cv::FILLED);
  return t;
}

Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace

SimulationSummary Simulate(const SimulateOptions& opt) {
  const sim::Scenario* scenario = sim::FindScenario(opt.scenario);
  if (scenario == nullptr) {
    std::string names;
    for (const auto& s : sim::Scenarios()) names += (names.empty() ? "" : ", ") + s.name;
    throw InputError("unknown scenario '" + opt.scenario + "', expected one of: " + names);
  }
  if (!(opt.physics_rate >= 500.0) || !(opt.joint_rate > 0.0) ||
      opt.joint_rate > opt.physics_rate || !(opt.camera_rate > 0.0) ||
      opt.camera_rate > opt.joint_rate)
    throw InputError("simulation rates must satisfy physics >= 500 Hz >= joints >= camera > 0");
  if (opt.image_width < 16 || opt.image_height < 16 || opt.image_width % 2 || opt.image_height % 2)
    throw InputError("image size must be even and at least 16x16");
  if (fs::exists(opt.out_dir) && !opt.overwrite)
    throw InputError(opt.out_dir + ": already exists (pass overwrite to replace it)");
  CheckOutputFolder(opt.out_dir);  // before the work, not after it
  const auto wall_start = std::chrono::steady_clock::now();
  const std::string assets = AssetDir();
  const fs::path hand_dir = fs::path(assets) / "hands" / "inhand_hand";
  const fs::path object_dir = fs::path(assets) / "objects" / scenario->object;
  // The estimator's models (copied into the session) and the world's (realism.hpp: not the
  // same under the `realistic` profile).
  const HandModel model_hand = LoadHandModel((hand_dir / "inhand_hand.urdf").string());
  const ObjectModel model_object = LoadObjectModel((object_dir / "object.json").string());
  const int m = model_hand.num_q();
  const Noise noise = NoiseFor(opt.noise);
  const Effects effects = EffectsOf(opt);
  const RealismParams& rp = opt.realism;
  std::mt19937 rng(opt.seed * 7919u + 17u);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Each effect draws from its own stream, so switching one leaves the others' draws alone.
  const auto effect_rng = [&](Effect e) {
    std::seed_seq seq{opt.seed, 0x5eedu, static_cast<unsigned>(e)};
    return std::mt19937(seq);
  };
  Vec3 object_scale = Vec3::Ones(), colour_gains = Vec3::Ones();
  ObjectModel object = model_object;
  if (effects.Has(Effect::kObjectScale)) {
    std::mt19937 r = effect_rng(Effect::kObjectScale);
    for (int a = 0; a < 3; ++a) object_scale[a] = 1.0 + rp.scale_sigma * gauss(r);
    object = ScaledObject(model_object, object_scale);
  }
  if (effects.Has(Effect::kObjectTags)) {
    std::mt19937 r = effect_rng(Effect::kObjectTags);
    MisplaceTags(object, rp.tag_position, rp.tag_orientation, r);
  }
  if (effects.Has(Effect::kObjectColour)) {
    std::mt19937 r = effect_rng(Effect::kObjectColour);
    for (int c = 0; c < 3; ++c) colour_gains[c] = 1.0 + rp.colour_sigma * gauss(r);
    TintObject(object, colour_gains);
  }
  // The estimator's model is simplified, the world keeps the detailed one.
  std::optional<SimplifiedModel> simplified;
  if (effects.Has(Effect::kObjectMesh))
    simplified = SimplifyModel(model_object, ReadBinary(object_dir / "object.json"),
                               object_dir.string(), rp);
  std::vector<Vec3> joint_origin_offsets;
  HandModel hand = model_hand;
  if (effects.Has(Effect::kHandGeometry)) {
    std::mt19937 r = effect_rng(Effect::kHandGeometry);
    hand = PerturbedHand(model_hand, rp.joint_origin_sigma, r, &joint_origin_offsets);
  }
  // Each joint's true stiffness, around the nominal one the session states (a maker's figure,
  // or a calibration): log-normal, so that it stays positive.
  Eigen::VectorXd stiffness = Eigen::VectorXd::Constant(m, rp.joint_stiffness);
  if (effects.Has(Effect::kHandDeflection)) {
    std::mt19937 r = effect_rng(Effect::kHandDeflection);
    std::normal_distribution<double> g(0.0, 1.0);  // its own: no value cached from another stream
    for (int j = 0; j < m; ++j)
      stiffness[j] = rp.joint_stiffness * std::exp(rp.joint_stiffness_sigma * g(r));
  }
  std::mt19937 torque_rng = effect_rng(Effect::kTorqueDrift);
  TorqueErrors torque_errors(m, rp, effects, torque_rng);
  const bool camera_sim = opt.images && effects.AnyCamera();

  // Constant errors of this session: joint biases, hand-eye calibration, initial estimate.
  Eigen::VectorXd bias(m);
  for (int j = 0; j < m; ++j) bias[j] = noise.bias_sigma * gauss(rng);
  const Transform hand_eye_error =
      MakeTransform(noise.hand_eye_position * RandomUnit(rng),
                    ExpSO3(noise.hand_eye_orientation * RandomUnit(rng)));

  const double dt = 1.0 / opt.physics_rate;
  const double duration = scenario->duration() * opt.duration_scale;
  const int steps = static_cast<int>(std::lround(duration / dt));
  const int joint_every =
      std::max(1, static_cast<int>(std::lround(opt.physics_rate / opt.joint_rate)));
  const int camera_every =
      std::max(1, static_cast<int>(std::lround(opt.physics_rate / opt.camera_rate)));

  // Joint state from the first targets.
  Eigen::VectorXd q(m), tau_filtered = Eigen::VectorXd::Zero(m), tau_contact(m);
  double grip = 1.0;
  {
    const auto targets = sim::TargetsAt(*scenario, 0.0, &grip);
    for (int j = 0; j < m; ++j) {
      const auto it = targets.find(hand.joints[hand.q_joints[j]].name);
      q[j] = it == targets.end() ? 0.0 : it->second;
    }
  }
  KinematicsData kin(hand);
  std::vector<Transform> T_WL(hand.links.size());
  const auto place_links = [&](const Transform& T_WP) {
    kin.Update(hand, q);
    for (std::size_t l = 0; l < hand.links.size(); ++l)
      T_WL[l] = T_WP * kin.T_PL(static_cast<int>(l));
  };
  const Transform T_WO0 = scenario->T_WO;
  std::vector<std::pair<Transform, Vec3>> props;
  for (const sim::Scenario::Prop& p : scenario->props) props.emplace_back(p.T_W, p.half_extents);
  sim::World world(hand, object, T_WO0, 1.5, sim::PalmAt(*scenario, 0.0), q,
                   props,  // rubber-like fingers
                   effects.Has(Effect::kHandPads) ? rp.pad_stiffness : 0.0, rp.pad_damping);
  place_links(sim::PalmAt(*scenario, 0.0));

  // Camera fixed in the world, looking at the workspace.
  Intrinsics K;
  K.width = opt.image_width;
  K.height = opt.image_height;
  K.fx = K.fy = 580.0 * opt.image_width / 640.0;
  K.cx = 0.5 * opt.image_width - 0.5;
  K.cy = 0.5 * opt.image_height - 0.5;
  const Transform T_WC = LookAt(scenario->camera_eye, scenario->camera_target, Vec3::UnitZ());
  // What the session says about the camera: with camera.intrinsics / camera.distortion, not
  // the truth (the true K renders; its distortion is the lens').
  Intrinsics K_session = K, K_lens = K;
  if (effects.Has(Effect::kCameraDistortion)) {
    std::mt19937 r = effect_rng(Effect::kCameraDistortion);
    for (std::size_t i = 0; i < 5; ++i) {
      K_lens.distortion[i] = rp.distortion[i];
      K_session.distortion[i] = rp.distortion[i] * (1.0 + rp.distortion_error * gauss(r));
    }
  }
  if (effects.Has(Effect::kCameraIntrinsics)) {
    std::mt19937 r = effect_rng(Effect::kCameraIntrinsics);
    K_session.fx *= 1.0 + rp.intrinsics_scale_sigma * gauss(r);
    K_session.fy *= 1.0 + rp.intrinsics_scale_sigma * gauss(r);
    K_session.cx += rp.intrinsics_centre_sigma * gauss(r);
    K_session.cy += rp.intrinsics_centre_sigma * gauss(r);
  }

  std::unique_ptr<Renderer> renderer;
  Scene world_scene;
  HandMeshes hand_meshes;
  std::vector<int> object_meshes;
  if (opt.images) {
    renderer = std::make_unique<Renderer>();
    hand_meshes = UploadHand(*renderer, hand);
    object_meshes = UploadObject(*renderer, object, PrintedTagMeshes(object));
    std::mt19937 clutter_rng(12345);  // the same room for every seed
    world_scene.K = K;
    world_scene.T_PC = T_WC;
    world_scene.background = Vec3(0.55, 0.58, 0.62);
    const int table = renderer->AddMesh(TexturedBox(Vec3(0.6, 0.4, 0.025), WoodTexture()));
    world_scene.items.push_back({table, MakeTransform(Vec3(0, 0, -0.025), Mat3::Identity()),
                                 kExtraLabelBase, std::nullopt, 1.0, false});
    const int wall =
        renderer->AddMesh(TexturedBox(Vec3(0.8, 0.5, 0.01), ClutterTexture(clutter_rng)));
    world_scene.items.push_back({wall,
                                 MakeTransform(Vec3(-0.1, 0.45, 0.3), ExpSO3(Vec3(M_PI / 2, 0, 0))),
                                 kExtraLabelBase + 1, std::nullopt, 1.0, false});
    for (const sim::Scenario::Prop& p : scenario->props) {
      TriangleMesh mesh = ConvexPiece::Box(p.half_extents, Transform::Identity()).ToMesh();
      mesh.material.rgba = p.rgba;
      world_scene.items.push_back({renderer->AddMesh(mesh), p.T_W,
                                   static_cast<std::uint16_t>(kExtraLabelBase + 50), std::nullopt,
                                   1.0, false});
    }
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 6 + noise.occluders; ++i) {
      const bool occluder = i >= 6;
      TriangleMesh mesh =
          i % 2 ? ConvexPiece::Cylinder(0.02 + 0.03 * u(clutter_rng), 0.03 + 0.05 * u(clutter_rng),
                                        Transform::Identity())
                      .ToMesh()
                : ConvexPiece::Box(Vec3(0.02 + 0.04 * u(clutter_rng), 0.02 + 0.04 * u(clutter_rng),
                                        0.03 + 0.04 * u(clutter_rng)),
                                   Transform::Identity())
                      .ToMesh();
      mesh.material.rgba = Eigen::Vector4d(0.2 + 0.7 * u(clutter_rng), 0.2 + 0.7 * u(clutter_rng),
                                           0.2 + 0.7 * u(clutter_rng), 1.0);
      const int id = renderer->AddMesh(mesh);
      const double h = mesh.Bounds().Size().z() / 2;
      Vec3 where;
      if (occluder) {  // between the camera and the grasp, low in the view
        where = scenario->camera_target +
                (scenario->camera_eye - scenario->camera_target) * (0.35 + 0.1 * i / 8.0);
        where.x() += (i % 2 ? 0.05 : -0.05);
        where.z() = h;
      } else {
        const double a = -0.6 + 1.3 * i / 6.0;
        where = Vec3(-0.25 + 0.45 * std::cos(a) * 0.0 + 0.22 * std::sin(a * 3.0) - 0.1,
                     0.25 + 0.06 * std::cos(a * 2.0), h);
        where.x() = -0.35 + 0.14 * i;
      }
      world_scene.items.push_back({id, MakeTransform(where, ExpSO3(Vec3(0, 0, 0.4 * i))),
                                   static_cast<std::uint16_t>(kExtraLabelBase + 2 + i),
                                   std::nullopt, 1.0, false});
    }
  }
  std::unique_ptr<CameraSimulator> camera;
  LightRig light;
  if (camera_sim) {
    light.lamp = scenario->camera_target + Vec3(0.45, -0.35, 0.85);
    light.lamp_target = scenario->camera_target;
    camera = std::make_unique<CameraSimulator>(*renderer, K_lens, rp, effects, light,
                                               opt.seed * 31337u + 5u);
  }
  // The world over the last exposure (motion blur): link poses and object pose per physics step.
  const int exposure_steps = effects.Has(Effect::kCameraMotionBlur)
                                 ? std::max(0, static_cast<int>(std::lround(rp.exposure_time / dt)))
                                 : 0;
  std::deque<std::pair<std::vector<Transform>, Transform>> recent;

  // Session metadata.
  SessionInfo info;
  info.name =
      scenario->name + "-seed" + std::to_string(opt.seed) + "-" + NoiseProfileName(opt.noise);
  info.hand_urdf = "model/hand/inhand_hand.urdf";
  info.object = "model/object/object.json";
  if (opt.images) info.camera = K_session;
  if (effects.Has(Effect::kHandDeflection)) info.joint_stiffness["*"] = rp.joint_stiffness;
  // The recording starts when the hand is in place around the object (as with a real robot,
  // whose estimator is seeded by a vision system before the manipulation): the initial estimate
  // is the truth at that moment, off by the profile's error.
  const double record_start = scenario->record_start;
  const Vec3 error_dir_random = RandomUnit(rng);
  const Vec3 error_axis = RandomUnit(rng);
  const std::pair<double, double> start_error = StartError(noise, scenario->start);
  Transform T_PO0 = Transform::Identity();
  info.sigma_position = 0.020;
  info.sigma_orientation = 5.0 * M_PI / 180;
  info.sigma_joint_bias = 5.0 * M_PI / 180;
  jsonf::Json provenance = {{"generator", "inhand simulate"},
                            {"scenario", scenario->name},
                            {"seed", opt.seed},
                            {"noise", NoiseProfileName(opt.noise)},
                            {"physics_rate", opt.physics_rate},
                            {"joint_rate", opt.joint_rate},
                            {"camera_rate", opt.camera_rate},
                            {"duration", duration},
                            {"noise_parameters",
                             {{"start", StartName(scenario->start)},
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
  std::unique_ptr<SessionWriter> writer;
  const auto start_recording = [&](const Transform& T_WP_now, const Transform& T_PO_now) {
    T_PO0 = T_PO_now;
    const Vec3 dir = scenario->start == sim::Scenario::Start::kTooHigh
                         ? Vec3(T_WP_now.linear().transpose() * Vec3::UnitZ())
                         : error_dir_random;
    info.initial_T_PO = MakeTransform(T_PO0.translation() + start_error.first * dir,
                                      ExpSO3(start_error.second * error_axis) * T_PO0.linear());
    provenance["record_start"] = record_start;
    info.provenance_json = provenance.dump();
    writer = std::make_unique<SessionWriter>(opt.out_dir, info, model_hand.QNames(), opt.overwrite);
    CopyFolder(*writer, hand_dir, "model/hand");
    CopyFolder(*writer, object_dir, "model/object");
    if (simplified)
      for (const auto& [name, contents] : simplified->files)
        writer->AddFile("model/object/" + name, contents);
  };

  // Truth for diagnostics and the plausibility checks.
  BulletContactQuery truth_contacts(hand, object);
  std::vector<ContactPair> pairs;
  std::ostringstream contacts_csv, joints_true_csv;
  contacts_csv << "t,link,distance,force\n";
  joints_true_csv << "t";
  for (const std::string& name : model_hand.QNames()) joints_true_csv << "," << name;
  joints_true_csv << "\n";
  Eigen::VectorXd q_prev = q, tau_gravity = Eigen::VectorXd::Zero(m);
  SimulationSummary summary;
  summary.session_dir = opt.out_dir;
  summary.duration = duration;
  Transform T_PO_grasp = Transform::Identity();
  bool have_grasp = false;
  int held = 0, after_grasp = 0;
  Vec3 p_WO_close = T_WO0.translation();
  cv::RNG pixel_rng(opt.seed * 104729u + 3u);

  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    const Transform T_WP_script = sim::PalmAt(*scenario, t);
    // Motor targets: the palm along its script, the joints within their torque limits.
    const auto targets = sim::TargetsAt(*scenario, t, &grip);
    Eigen::VectorXd q_target(m), tau_max(m);
    for (int j = 0; j < m; ++j) {
      const Joint& joint = hand.joints[hand.q_joints[j]];
      const auto it = targets.find(joint.name);
      q_target[j] = it == targets.end() ? q[j] : it->second;
      tau_max[j] = std::max(joint.effort_limit, 0.1) * grip;
    }
    world.SetTargets(T_WP_script, q_target, tau_max);
    world.Step(dt);
    q = world.JointPositions();
    const Transform T_WP = world.PalmPose();
    place_links(T_WP);

    // Contact torques from the solver's impulses: τ = Σ J(c)ᵀ λ, λ in the palm frame.
    tau_contact.setZero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, m);
    const Transform T_PW = T_WP.inverse();
    for (const sim::LinkContact& c : world.contacts()) {
      PointJacobian(hand, kin, c.link, T_PW * c.point_W, J);
      tau_contact += J.transpose() * (T_PW.linear() * c.force_W);
    }
    tau_filtered += (dt / (dt + 0.005)) * (tau_contact - tau_filtered);
    // The fingers' gravity torque (the simulator's link masses), whose estimate a real torque
    // estimate subtracts imperfectly.
    if (effects.Has(Effect::kTorqueResidue)) {
      tau_gravity.setZero();
      const Vec3 g_P = T_PW.linear() * Vec3(0, 0, -9.81 * sim::kLinkMass);
      for (std::size_t l = 0; l < hand.links.size(); ++l) {
        if (static_cast<int>(l) == hand.root_link) continue;
        PointJacobian(hand, kin, static_cast<int>(l), kin.T_PL(static_cast<int>(l)).translation(),
                      J);
        tau_gravity -= J.transpose() * g_P;  // what the motors hold against gravity
      }
    }
    const Eigen::VectorXd tau_estimate =
        torque_errors.Step(dt, tau_filtered, (q - q_prev) / dt, tau_gravity);
    q_prev = q;

    const Transform T_WO = world.ObjectPose();
    const Transform T_PO = T_PW * T_WO;
    if (t <= scenario->close_start + 1e-9) p_WO_close = T_WO.translation();
    const bool recording = t >= record_start - 1e-9;
    if (recording && !writer) start_recording(T_WP, T_PO);

    if (recording && k % joint_every == 0) {
      Eigen::VectorXd q_meas(m), tau_meas(m);
      for (int j = 0; j < m; ++j) {
        // The encoder reads the motor side: ahead of the link by the load over the stiffness.
        const double deflection =
            effects.Has(Effect::kHandDeflection) ? tau_filtered[j] / stiffness[j] : 0.0;
        q_meas[j] = q[j] + deflection - bias[j] + noise.joint_sigma * gauss(rng);
        tau_meas[j] = tau_estimate[j] + noise.torque_sigma * gauss(rng);
      }
      writer->AddJointSample(t, q_meas, tau_meas);
      joints_true_csv << FormatDouble(t);
      for (int j = 0; j < m; ++j) joints_true_csv << "," << FormatDouble(q[j]);
      joints_true_csv << "\n";
      writer->AddGroundTruth(t, T_PO);
      ++summary.joint_samples;
      // Truth checks with the estimator's own GJK on the true configuration.
      truth_contacts.Query(kin.link_poses(), T_PO, 0.001, pairs);
      int touching = 0;
      for (const ContactPair& p : pairs) {
        summary.max_penetration = std::max(summary.max_penetration, -p.distance);
        touching += p.distance < 0.001;
        contacts_csv << FormatDouble(t) << "," << hand.links[p.link].name << ","
                     << FormatDouble(p.distance) << ",0\n";
      }
      // In-hand rotation: the object's orientation in the palm frame since the fingers began
      // to close (what closing, lifting and manipulating did to it).
      if (t >= scenario->close_start) {
        if (!have_grasp) {
          T_PO_grasp = T_PO;
          have_grasp = true;
        }
        const double rot = RotationDistance(T_PO.linear(), T_PO_grasp.linear()) * 180.0 / M_PI;
        summary.max_in_hand_rotation_deg = std::max(summary.max_in_hand_rotation_deg, rot);
        summary.tilt_in_hand_deg = rot;
      }
      if (t >= scenario->grasp_closed) {
        ++after_grasp;
        held += touching >= 2;
      }
    }
    if (camera) {
      recent.emplace_back(T_WL, T_WO);
      while (static_cast<int>(recent.size()) > exposure_steps + 1) recent.pop_front();
    }
    if (recording && camera && k % camera_every == 0) {
      // Sub-frames spread over the exposure, ending now.
      std::vector<Scene> subframes;
      const int count = exposure_steps > 0 ? std::max(1, rp.blur_subframes) : 1;
      for (int i = 0; i < count; ++i) {
        const int back = count > 1 ? static_cast<int>(std::lround(double(exposure_steps) *
                                                                  (count - 1 - i) / (count - 1)))
                                   : 0;
        const auto& [links, T_WO_then] =
            recent[recent.size() - 1 - std::min<std::size_t>(back, recent.size() - 1)];
        Scene scene = world_scene;
        AddHand(scene, hand_meshes, links);
        AddObject(scene, object_meshes, T_WO_then);
        subframes.push_back(std::move(scene));
      }
      Image8 image;
      camera->Capture(subframes, image);
      writer->AddCameraFrame(t, image, T_PW * T_WC * hand_eye_error);
      ++summary.camera_frames;
    } else if (recording && opt.images && k % camera_every == 0) {
      Scene scene = world_scene;
      AddHand(scene, hand_meshes, T_WL);
      AddObject(scene, object_meshes, T_WO);
      RenderOutput out;
      renderer->Render(scene, out, false);
      cv::Mat img(K.height, K.width, CV_8UC3, out.colour.data.data());
      if (noise.blur_sigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), noise.blur_sigma);
      if (noise.pixel_sigma > 0) {
        cv::Mat n(img.size(), CV_16SC3);
        pixel_rng.fill(n, cv::RNG::NORMAL, 0.0, noise.pixel_sigma);
        cv::Mat sum;
        img.convertTo(sum, CV_16SC3);
        sum += n;
        sum.convertTo(img, CV_8UC3);
      }
      writer->AddCameraFrame(t, out.colour, T_PW * T_WC * hand_eye_error);
      ++summary.camera_frames;
    }
  }
  summary.held_fraction = after_grasp ? double(held) / after_grasp : 0.0;
  summary.table_travel_before_grasp = (p_WO_close - T_WO0.translation()).norm();
  summary.lift_height = world.ObjectPose().translation().z() - T_WO0.translation().z();

  jsonf::Json biases = jsonf::Json::object();
  for (int j = 0; j < m; ++j) biases[hand.joints[hand.q_joints[j]].name] = bias[j];
  jsonf::Json realism = {{"effects", effects.Names()}};
  const Vec3 world_size = object.Bounds().Size(), model_size = model_object.Bounds().Size();
  realism["world_object_size_m"] = {world_size.x(), world_size.y(), world_size.z()};
  realism["model_object_size_m"] = {model_size.x(), model_size.y(), model_size.z()};
  if (effects.Has(Effect::kObjectScale))
    realism["object_scale"] = {object_scale.x(), object_scale.y(), object_scale.z()};
  if (simplified)
    realism["simplified_model"] = {{"triangles", simplified->triangles_after},
                                   {"model_triangles", simplified->triangles_before},
                                   {"pieces", simplified->pieces_after},
                                   {"model_pieces", simplified->pieces_before}};
  if (effects.Has(Effect::kObjectColour))
    realism["colour_gains_rgb"] = {colour_gains.x(), colour_gains.y(), colour_gains.z()};
  if (effects.Has(Effect::kObjectTags)) {
    jsonf::Json tags = jsonf::Json::array();
    for (const TagPlacement& t : object.tags)
      tags.push_back({{"id", t.id}, {"true_pose", jsonf::PoseToJson(t.T_OT)}});
    realism["tags"] = tags;
  }
  if (effects.Has(Effect::kHandGeometry)) {
    jsonf::Json offsets = jsonf::Json::object();
    for (std::size_t j = 0; j < hand.joints.size(); ++j)
      offsets[hand.joints[j].name] = {joint_origin_offsets[j].x(), joint_origin_offsets[j].y(),
                                      joint_origin_offsets[j].z()};
    realism["joint_origin_offsets_m"] = offsets;
  }
  if (effects.Has(Effect::kHandDeflection)) {
    jsonf::Json ks = jsonf::Json::object();
    const std::vector<std::string> q_names = hand.QNames();
    for (int j = 0; j < m; ++j) ks[q_names[static_cast<std::size_t>(j)]] = stiffness[j];
    realism["joint_stiffness_Nm_per_rad"] = ks;
    realism["nominal_joint_stiffness_Nm_per_rad"] = rp.joint_stiffness;
    realism["deflection_convention"] =
        "q_motor (recorded, before bias and noise) = q_link + tau_contact / k";
  }
  if (opt.images) {
    realism["true_intrinsics"] = {
        {"fx", K_lens.fx},
        {"fy", K_lens.fy},
        {"cx", K_lens.cx},
        {"cy", K_lens.cy},
        {"distortion",
         {K_lens.distortion[0], K_lens.distortion[1], K_lens.distortion[2], K_lens.distortion[3],
          K_lens.distortion[4]}}};
    if (camera) realism["lamp"] = {light.lamp.x(), light.lamp.y(), light.lamp.z()};
  }
  const Quat he(hand_eye_error.linear());
  jsonf::Json truth = {{"joint_biases_rad", biases},
                       {"bias_convention", "q_true = q_meas + bias"},
                       {"hand_eye_error", jsonf::PoseToJson(hand_eye_error)},
                       {"hand_eye_convention", "T_PC_recorded = T_PC_true * error"},
                       {"true_initial_T_PO", jsonf::PoseToJson(T_PO0)},
                       {"max_penetration_m", summary.max_penetration},
                       {"held_fraction", summary.held_fraction},
                       {"tilt_in_hand_deg", summary.tilt_in_hand_deg},
                       {"max_in_hand_rotation_deg", summary.max_in_hand_rotation_deg},
                       {"table_travel_before_grasp_m", summary.table_travel_before_grasp},
                       {"lift_height_m", summary.lift_height},
                       {"realism", realism}};
  INHAND_CHECK(writer != nullptr, "the script ends before the recording starts");
  writer->AddFile("truth/truth.json", truth.dump(2) + "\n");
  writer->AddFile("truth/contacts.csv", contacts_csv.str());
  writer->AddFile("truth/joints.csv", joints_true_csv.str());
  writer->Commit();
  summary.wall_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return summary;
}

std::vector<ScenarioInfo> ListScenarios() {
  std::vector<ScenarioInfo> out;
  for (const sim::Scenario& s : sim::Scenarios())
    out.push_back({s.name, s.description, s.duration(),
                   (fs::path(AssetDir()) / "objects" / s.object / "object.json").string()});
  return out;
}

}  // namespace inhand
