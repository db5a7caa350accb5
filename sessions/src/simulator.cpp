#include "inhand/sessions/simulator.hpp"

#include <chrono>
#include <deque>
#include <filesystem>
#include <random>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/core/time.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/printed_tags.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/camera_sim.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "inhand/sessions/session.hpp"
#include "scenarios.hpp"
#include "sim_room.hpp"
#include "sim_setup.hpp"
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

using sim::AssetDir;
using sim::CameraSetup;
using sim::DrawCamera;
using sim::Draws;
using sim::DrawWorld;
using sim::LoadModels;
using sim::Models;
using sim::Noise;
using sim::NoiseFor;
using sim::Provenance;
using sim::ReadBinary;
using sim::StartError;
using sim::TrueWorld;
using sim::TruthJson;

// Copies a model folder into the session, so the session is self-contained.
void CopyFolder(SessionWriter& w, const fs::path& from, const std::string& to) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(from))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files)
    w.AddFile(to + "/" + fs::relative(f, from).string(), ReadBinary(f));
}

// One simulation: the world stepped at the physics rate, joint samples and camera frames recorded
// at theirs once the recording starts, the truth checked on every joint sample.
class SimulationRun {
 public:
  SimulationRun(const SimulateOptions& opt, const sim::Scenario& scenario);
  SimulationSummary Execute();

 private:
  Transform StepPhysics(double t);  // the palm pose T_WP after the step
  void StartRecording(const Transform& T_WP, const Transform& T_PO);
  void RecordJointSample(double t, const Transform& T_PO);
  void RecordCameraFrame(double t, const Transform& T_PW, const Transform& T_WO);
  void WriteTruth();

  const SimulateOptions& opt_;
  const sim::Scenario& scenario_;
  const Noise noise_;
  const Effects effects_;
  const RealismParams& rp_;
  Draws draws_;
  const Models models_;
  const TrueWorld world_;
  const HandModel& hand_;
  const int m_;
  std::mt19937 torque_rng_;
  TorqueErrors torque_errors_;
  const bool camera_sim_;
  double dt_ = 0.0, duration_ = 0.0;
  int steps_ = 0, joint_every_ = 1, camera_every_ = 1;
  // Joint state: positions, contact torques (filtered as a torque sensor would), their estimate.
  Eigen::VectorXd q_, q_prev_, tau_filtered_, tau_contact_, tau_gravity_, tau_estimate_;
  double grip_ = 1.0;
  KinematicsData kin_;
  std::vector<Transform> T_WL_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J_;
  std::unique_ptr<sim::World> physics_;
  CameraSetup camera_;
  // Rendering: the world's scene, the hand's and object's meshes, the camera's image formation.
  std::unique_ptr<Renderer> renderer_;
  Scene room_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::unique_ptr<CameraSimulator> camera_sim_model_;
  LightRig light_;
  // The world over the last exposure (motion blur): link poses and object pose per physics step.
  int exposure_steps_ = 0;
  std::deque<std::pair<std::vector<Transform>, Transform>> recent_;
  // The recording.
  SessionInfo info_;
  jsonf::Json provenance_;
  Vec3 error_dir_random_, error_axis_;
  std::pair<double, double> start_error_;
  std::unique_ptr<SessionWriter> writer_;
  Transform T_PO0_ = Transform::Identity();
  cv::RNG pixel_rng_;
  // Truth for diagnostics and the plausibility checks.
  BulletContactQuery truth_contacts_;
  std::vector<ContactPair> pairs_;
  std::ostringstream contacts_csv_, joints_true_csv_;
  SimulationSummary summary_;
  Transform T_PO_grasp_ = Transform::Identity();
  bool have_grasp_ = false;
  int held_ = 0, after_grasp_ = 0;
  Vec3 p_WO_close_ = Vec3::Zero();
};

SimulationRun::SimulationRun(const SimulateOptions& opt, const sim::Scenario& scenario)
    : opt_(opt),
      scenario_(scenario),
      noise_(NoiseFor(opt.noise)),
      effects_(EffectsOf(opt)),
      rp_(opt.realism),
      draws_(opt.seed),
      models_(LoadModels(scenario)),
      world_(DrawWorld(models_, noise_, effects_, rp_, draws_)),
      hand_(world_.hand),
      m_(models_.hand.num_q()),
      torque_rng_(draws_.ForEffect(Effect::kTorqueDrift)),
      torque_errors_(m_, rp_, effects_, torque_rng_),
      camera_sim_(opt.images && effects_.AnyCamera()),
      kin_(world_.hand),
      T_WL_(world_.hand.links.size()),
      J_(3, m_),
      pixel_rng_(opt.seed * 104729u + 3u),
      truth_contacts_(world_.hand, world_.object) {
  dt_ = 1.0 / opt.physics_rate;
  duration_ = scenario.duration() * opt.duration_scale;
  steps_ = static_cast<int>(std::lround(duration_ / dt_));
  joint_every_ = std::max(1, static_cast<int>(std::lround(opt.physics_rate / opt.joint_rate)));
  camera_every_ = std::max(1, static_cast<int>(std::lround(opt.physics_rate / opt.camera_rate)));

  // Joint state from the first targets; the physics from there.
  q_.resize(m_);
  const auto targets = sim::TargetsAt(scenario, 0.0, &grip_);
  for (int j = 0; j < m_; ++j) {
    const auto it = targets.find(hand_.QJoint(j).name);
    q_[j] = it == targets.end() ? 0.0 : it->second;
  }
  q_prev_ = q_;
  tau_filtered_ = tau_gravity_ = Eigen::VectorXd::Zero(m_);
  tau_contact_.resize(m_);
  std::vector<std::pair<Transform, Vec3>> props;
  for (const sim::Scenario::Prop& p : scenario.props) props.emplace_back(p.T_W, p.half_extents);
  physics_ = std::make_unique<sim::World>(
      hand_, world_.object, scenario.T_WO, 1.5, sim::PalmAt(scenario, 0.0), q_, props,
      effects_.Has(Effect::kHandPads) ? rp_.pad_stiffness : 0.0, rp_.pad_damping);  // rubber pads

  camera_ = DrawCamera(opt, scenario, effects_, draws_);
  if (opt.images) {
    renderer_ = std::make_unique<Renderer>();
    hand_meshes_ = UploadHand(*renderer_, hand_);
    object_meshes_ = UploadObject(*renderer_, world_.object, PrintedTagMeshes(world_.object));
    room_ = sim::BuildRoom(*renderer_, scenario, noise_.occluders, camera_.K, camera_.T_WC);
  }
  if (camera_sim_) {
    light_.lamp = scenario.camera_target + Vec3(0.45, -0.35, 0.85);
    light_.lamp_target = scenario.camera_target;
    camera_sim_model_ = std::make_unique<CameraSimulator>(*renderer_, camera_.K_lens, rp_, effects_,
                                                          light_, opt.seed * 31337u + 5u);
  }
  exposure_steps_ = effects_.Has(Effect::kCameraMotionBlur)
                        ? std::max(0, static_cast<int>(std::lround(rp_.exposure_time / dt_)))
                        : 0;

  // Session metadata. The recording starts when the hand is in place around the object (as with
  // a real robot, whose estimator is seeded by a vision system before the manipulation): the
  // initial estimate is the truth at that moment, off by the profile's error.
  info_.name =
      scenario.name + "-seed" + std::to_string(opt.seed) + "-" + NoiseProfileName(opt.noise);
  info_.hand_urdf = "model/hand/inhand_hand.urdf";
  info_.object = "model/object/object.json";
  if (opt.images) info_.camera = camera_.K_session;
  if (effects_.Has(Effect::kHandDeflection)) info_.joint_stiffness["*"] = rp_.joint_stiffness;
  error_dir_random_ = RandomUnitVector(draws_.main);
  error_axis_ = RandomUnitVector(draws_.main);
  start_error_ = StartError(noise_, scenario.start);
  info_.sigma_position = 0.020;
  info_.sigma_orientation = 5.0 * M_PI / 180;
  info_.sigma_joint_bias = 5.0 * M_PI / 180;
  provenance_ = Provenance(opt, scenario, duration_, noise_, start_error_, effects_, camera_sim_);

  contacts_csv_ << "t,link,distance,force\n";
  joints_true_csv_ << "t";
  for (const std::string& name : models_.hand.QNames()) joints_true_csv_ << "," << name;
  joints_true_csv_ << "\n";
  summary_.session_dir = opt.out_dir;
  summary_.duration = duration_;
  p_WO_close_ = scenario.T_WO.translation();
}

SimulationSummary SimulationRun::Execute() {
  for (int k = 0; k <= steps_; ++k) {
    const double t = k * dt_;
    const Transform T_WP = StepPhysics(t);
    const Transform T_PW = T_WP.inverse();
    const Transform T_WO = physics_->ObjectPose();
    const Transform T_PO = T_PW * T_WO;
    if (t <= scenario_.close_start + kTimeTolerance) p_WO_close_ = T_WO.translation();
    const bool recording = t >= scenario_.record_start - kTimeTolerance;
    if (recording && !writer_) StartRecording(T_WP, T_PO);
    if (recording && k % joint_every_ == 0) RecordJointSample(t, T_PO);
    if (camera_sim_model_) {
      recent_.emplace_back(T_WL_, T_WO);
      while (static_cast<int>(recent_.size()) > exposure_steps_ + 1) recent_.pop_front();
    }
    if (recording && opt_.images && k % camera_every_ == 0) RecordCameraFrame(t, T_PW, T_WO);
  }
  summary_.held_fraction = after_grasp_ ? double(held_) / after_grasp_ : 0.0;
  summary_.table_travel_before_grasp = (p_WO_close_ - scenario_.T_WO.translation()).norm();
  summary_.lift_height =
      physics_->ObjectPose().translation().z() - scenario_.T_WO.translation().z();
  WriteTruth();
  return summary_;
}

// One physics step towards the script's targets; the links placed, the contact torques and their
// estimate (as a real torque estimate would give them) updated.
Transform SimulationRun::StepPhysics(double t) {
  // Motor targets: the palm along its script, the joints within their torque limits.
  const auto targets = sim::TargetsAt(scenario_, t, &grip_);
  Eigen::VectorXd q_target(m_), tau_max(m_);
  for (int j = 0; j < m_; ++j) {
    const Joint& joint = hand_.QJoint(j);
    const auto it = targets.find(joint.name);
    q_target[j] = it == targets.end() ? q_[j] : it->second;
    tau_max[j] = std::max(joint.effort_limit, 0.1) * grip_;
  }
  physics_->SetTargets(sim::PalmAt(scenario_, t), q_target, tau_max);
  physics_->Step(dt_);
  q_ = physics_->JointPositions();
  const Transform T_WP = physics_->PalmPose();
  kin_.Update(hand_, q_);
  for (std::size_t l = 0; l < hand_.links.size(); ++l)
    T_WL_[l] = T_WP * kin_.T_PL(static_cast<int>(l));

  // Contact torques from the solver's impulses: τ = Σ J(c)ᵀ λ, λ in the palm frame.
  tau_contact_.setZero();
  const Transform T_PW = T_WP.inverse();
  for (const sim::LinkContact& c : physics_->contacts()) {
    PointJacobian(hand_, kin_, c.link, T_PW * c.point_W, J_);
    tau_contact_ += J_.transpose() * (T_PW.linear() * c.force_W);
  }
  tau_filtered_ += (dt_ / (dt_ + 0.005)) * (tau_contact_ - tau_filtered_);
  // The fingers' gravity torque (the simulator's link masses), whose estimate a real torque
  // estimate subtracts imperfectly.
  if (effects_.Has(Effect::kTorqueResidue)) {
    tau_gravity_.setZero();
    const Vec3 g_P = T_PW.linear() * Vec3(0, 0, -9.81 * sim::kLinkMass);
    for (std::size_t l = 0; l < hand_.links.size(); ++l) {
      if (static_cast<int>(l) == hand_.root_link) continue;
      PointJacobian(hand_, kin_, static_cast<int>(l), kin_.T_PL(static_cast<int>(l)).translation(),
                    J_);
      tau_gravity_ -= J_.transpose() * g_P;  // what the motors hold against gravity
    }
  }
  tau_estimate_ = torque_errors_.Step(dt_, tau_filtered_, (q_ - q_prev_) / dt_, tau_gravity_);
  q_prev_ = q_;
  return T_WP;
}

void SimulationRun::StartRecording(const Transform& T_WP, const Transform& T_PO) {
  T_PO0_ = T_PO;
  const Vec3 dir = scenario_.start == sim::Scenario::Start::kTooHigh
                       ? Vec3(T_WP.linear().transpose() * Vec3::UnitZ())
                       : error_dir_random_;
  info_.initial_T_PO = MakeTransform(T_PO0_.translation() + start_error_.first * dir,
                                     ExpSO3(start_error_.second * error_axis_) * T_PO0_.linear());
  provenance_["record_start"] = scenario_.record_start;
  info_.provenance_json = provenance_.dump();
  writer_ =
      std::make_unique<SessionWriter>(opt_.out_dir, info_, models_.hand.QNames(), opt_.overwrite);
  CopyFolder(*writer_, models_.hand_dir, "model/hand");
  CopyFolder(*writer_, models_.object_dir, "model/object");
  if (world_.simplified)
    for (const auto& [name, contents] : world_.simplified->files)
      writer_->AddFile("model/object/" + name, contents);
}

// A joint sample as the encoders and the torque estimate give it, the truth beside it, and the
// truth's checks with the estimator's own GJK on the true configuration.
void SimulationRun::RecordJointSample(double t, const Transform& T_PO) {
  Eigen::VectorXd q_meas(m_), tau_meas(m_);
  for (int j = 0; j < m_; ++j) {
    // The encoder reads the motor side: ahead of the link by the load over the stiffness.
    const double deflection =
        effects_.Has(Effect::kHandDeflection) ? tau_filtered_[j] / world_.stiffness[j] : 0.0;
    q_meas[j] =
        q_[j] + deflection - world_.bias[j] + noise_.joint_sigma * draws_.gauss(draws_.main);
    tau_meas[j] = tau_estimate_[j] + noise_.torque_sigma * draws_.gauss(draws_.main);
  }
  writer_->AddJointSample(t, q_meas, tau_meas);
  joints_true_csv_ << FormatDouble(t);
  for (int j = 0; j < m_; ++j) joints_true_csv_ << "," << FormatDouble(q_[j]);
  joints_true_csv_ << "\n";
  writer_->AddGroundTruth(t, T_PO);
  ++summary_.joint_samples;
  truth_contacts_.Query(kin_.link_poses(), T_PO, 0.001, pairs_);
  int touching = 0;
  for (const ContactPair& p : pairs_) {
    summary_.max_penetration = std::max(summary_.max_penetration, -p.distance);
    touching += p.distance < 0.001;
    contacts_csv_ << FormatDouble(t) << "," << hand_.links[p.link].name << ","
                  << FormatDouble(p.distance) << ",0\n";
  }
  // In-hand rotation: the object's orientation in the palm frame since the fingers began to
  // close (what closing, lifting and manipulating did to it).
  if (t >= scenario_.close_start) {
    if (!have_grasp_) {
      T_PO_grasp_ = T_PO;
      have_grasp_ = true;
    }
    const double rot = RotationDistance(T_PO.linear(), T_PO_grasp_.linear()) * 180.0 / M_PI;
    summary_.max_in_hand_rotation_deg = std::max(summary_.max_in_hand_rotation_deg, rot);
    summary_.tilt_in_hand_deg = rot;
  }
  if (t >= scenario_.grasp_closed) {
    ++after_grasp_;
    held_ += touching >= 2;
  }
}

// A camera frame: through the camera simulator (sub-frames over the exposure, ending now) when a
// camera effect is on, else the rendered image with the profile's blur and pixel noise.
void SimulationRun::RecordCameraFrame(double t, const Transform& T_PW, const Transform& T_WO) {
  const Transform T_PC = T_PW * camera_.T_WC * world_.hand_eye_error;
  if (camera_sim_model_) {
    std::vector<Scene> subframes;
    const int count = exposure_steps_ > 0 ? std::max(1, rp_.blur_subframes) : 1;
    for (int i = 0; i < count; ++i) {
      const int back = count > 1 ? static_cast<int>(std::lround(double(exposure_steps_) *
                                                                (count - 1 - i) / (count - 1)))
                                 : 0;
      const auto& [links, T_WO_then] =
          recent_[recent_.size() - 1 - std::min<std::size_t>(back, recent_.size() - 1)];
      Scene scene = room_;
      AddHand(scene, hand_meshes_, links);
      AddObject(scene, object_meshes_, T_WO_then);
      subframes.push_back(std::move(scene));
    }
    Image8 image;
    camera_sim_model_->Capture(subframes, image);
    writer_->AddCameraFrame(t, image, T_PC);
  } else {
    Scene scene = room_;
    AddHand(scene, hand_meshes_, T_WL_);
    AddObject(scene, object_meshes_, T_WO);
    RenderOutput out;
    renderer_->Render(scene, out, false);
    cv::Mat img(camera_.K.height, camera_.K.width, CV_8UC3, out.colour.data.data());
    if (noise_.blur_sigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), noise_.blur_sigma);
    if (noise_.pixel_sigma > 0) {
      cv::Mat n(img.size(), CV_16SC3);
      pixel_rng_.fill(n, cv::RNG::NORMAL, 0.0, noise_.pixel_sigma);
      cv::Mat sum;
      img.convertTo(sum, CV_16SC3);
      sum += n;
      sum.convertTo(img, CV_8UC3);
    }
    writer_->AddCameraFrame(t, out.colour, T_PC);
  }
  ++summary_.camera_frames;
}

void SimulationRun::WriteTruth() {
  INHAND_CHECK(writer_ != nullptr, "the script ends before the recording starts");
  const jsonf::Json truth =
      TruthJson(world_, models_.object, camera_, camera_sim_model_ ? &light_ : nullptr, opt_.images,
                effects_, rp_, T_PO0_, summary_);
  writer_->AddFile("truth/truth.json", truth.dump(2) + "\n");
  writer_->AddFile("truth/contacts.csv", contacts_csv_.str());
  writer_->AddFile("truth/joints.csv", joints_true_csv_.str());
  writer_->Commit();
}

// The scenario `opt` names, once its options are known to make sense.
const sim::Scenario& CheckedScenario(const SimulateOptions& opt) {
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
  return *scenario;
}

}  // namespace

SimulationSummary Simulate(const SimulateOptions& opt) {
  const sim::Scenario& scenario = CheckedScenario(opt);
  CheckOutputFolder(opt.out_dir);  // before the work, not after it
  const auto wall_start = std::chrono::steady_clock::now();
  SimulationSummary summary = SimulationRun(opt, scenario).Execute();
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
