#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "inhand/core/error.hpp"
#include "inhand/sessions/session.hpp"
#include "inhand/sessions/simulator.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

SimulateOptions Short(const std::string& scenario, const std::string& out) {
  SimulateOptions o;
  o.scenario = scenario;
  o.out_dir = out;
  o.seed = 3;
  o.noise = NoiseProfile::kPaper;
  o.duration_scale = 0.4;
  o.image_width = 160;
  o.image_height = 120;
  return o;
}

TEST(Simulator, SameSeedGivesByteIdenticalSessions) {
  test::TempDir dir;
  Simulate(Short("ketchup-power-grasp", dir / "a"));
  Simulate(Short("ketchup-power-grasp", dir / "b"));
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir / "a"))
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), dir / "a").string());
  ASSERT_GT(files.size(), 10u);
  for (const std::string& f : files)
    EXPECT_EQ(Read(fs::path(dir / "b") / f), Read(fs::path(dir / "a") / f)) << f;
  // Another seed changes the noise.
  SimulateOptions other = Short("ketchup-power-grasp", dir / "c");
  other.seed = 4;
  Simulate(other);
  EXPECT_NE(Read(fs::path(dir / "c") / "joints.csv"), Read(fs::path(dir / "a") / "joints.csv"));
}

TEST(Simulator, EveryScenarioRoundTripsThroughTheReader) {
  test::TempDir dir;
  for (const ScenarioInfo& s : ListScenarios()) {
    SimulateOptions o = Short(s.name, dir / s.name);
    o.images = s.name == "water-push-grasp";  // one scenario with images, the rest fast
    o.duration_scale = 0.25;
    const SimulationSummary summary = Simulate(o);
    Session session = Session::Load(dir / s.name);
    const SessionModels models = LoadSessionModels(session, false);
    EXPECT_EQ(session.num_samples(), summary.joint_samples) << s.name;
    EXPECT_EQ(static_cast<int>(session.camera_frames().size()), summary.camera_frames) << s.name;
    EXPECT_TRUE(session.has_groundtruth());
    EXPECT_EQ(models.hand.num_q(), 16);
    EXPECT_TRUE(fs::exists(fs::path(dir / s.name) / "truth/truth.json"));
    // Ground truth is continuous: no jump larger than 5 mm between samples at 500 Hz.
    double worst = 0.0;
    for (std::size_t k = 1; k < session.groundtruth().size(); ++k)
      worst = std::max(worst, (session.groundtruth()[k].T_PO.translation() -
                               session.groundtruth()[k - 1].T_PO.translation())
                                  .norm());
    EXPECT_LT(worst, 0.005) << s.name;
    EXPECT_LT(summary.max_penetration, 0.001) << s.name;
    if (o.images) {
      const Image8 img = session.LoadImage(0);
      EXPECT_EQ(img.width, 160);
    }
    // The initial estimate is off as in the paper's experiment: from the tracking system (2 mm,
    // 1°), set 20 mm too high (ketchup, the orientation still the tracker's), or by hand (pen).
    const auto truth = nlohmann::json::parse(
        Read(fs::path(dir / s.name) / "truth/truth.json"))["true_initial_T_PO"];
    const auto& xyz = truth["xyz"];
    const auto& q = truth["quat_wxyz"];
    const Transform T_true = MakeTransform(Vec3(xyz[0], xyz[1], xyz[2]),
                                           Quat(q[0], q[1], q[2], q[3]).toRotationMatrix());
    const Transform& T_init = session.info().initial_T_PO;
    const Vec3 error_O =
        T_true.linear().transpose() * (T_init.translation() - T_true.translation());
    const double angle = LogSO3(T_init.linear() * T_true.linear().transpose()).norm();
    const bool too_high = s.name == "ketchup-power-grasp", by_hand = s.name == "pen-fingertip";
    EXPECT_NEAR(error_O.norm(), too_high || by_hand ? 0.020 : 0.002, 1e-9) << s.name;
    EXPECT_NEAR(angle, (by_hand ? 5.0 : 1.0) * M_PI / 180, 1e-9) << s.name;
    if (too_high) {
      EXPECT_GT(error_O.z(), 0.0199) << "the bottle stands: too high is along its axis";
    }
  }
}

TEST(Simulator, RejectsBadOptions) {
  test::TempDir dir;
  SimulateOptions o = Short("no-such-scenario", dir / "x");
  EXPECT_THROW(Simulate(o), InputError);
  o = Short("pen-fingertip", dir / "y");
  o.physics_rate = 100;
  EXPECT_THROW(Simulate(o), InputError);
  EXPECT_THROW(ParseNoiseProfile("loud"), InputError);
  EXPECT_FALSE(fs::exists(dir / "y"));  // nothing half-written
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

SimulationSummary Physics(const std::string& scenario) {
  test::TempDir dir;
  SimulateOptions o;
  o.scenario = scenario;
  o.out_dir = dir / "s";
  o.noise = NoiseProfile::kNone;
  o.images = false;
  return Simulate(o);
}

// Physical plausibility of every scenario (the simulation speed is a benchmark:
// tests/bench/bench_simulator.cpp): held (two links touching) from the moment the fingers have
// closed, lifted at least `lift`, no finger deeper than 1 mm in the object.
void ExpectHeldAndLifted(const SimulationSummary& s, double lift) {
  EXPECT_GT(s.held_fraction, 0.95);
  EXPECT_GT(s.lift_height, lift);
  EXPECT_LT(s.max_penetration, 0.001);
}

TEST(SimulatorPhysics, KetchupIsHeldLiftedAndTiltsInTheHand) {
  const SimulationSummary s = Physics("ketchup-power-grasp");
  ExpectHeldAndLifted(s, 0.08);
  EXPECT_GT(s.tilt_in_hand_deg, 5.0);
}

TEST(SimulatorPhysics, WaterBottleIsPushedAlongTheTableThenHeld) {
  const SimulationSummary s = Physics("water-push-grasp");
  EXPECT_GT(s.table_travel_before_grasp, 0.01);
  ExpectHeldAndLifted(s, 0.08);
}

// The fingertip grasps: pinched between the index and the thumb, lifted off their book, and
// rolled in the fingers by more than 10 deg.
void ExpectPinchedLiftedAndRolled(const std::string& scenario) {
  const SimulationSummary s = Physics(scenario);
  ExpectHeldAndLifted(s, 0.06);
  EXPECT_GT(s.max_in_hand_rotation_deg, 10.0);
}

TEST(SimulatorPhysics, BrushIsPinchedLiftedAndRolledInTheFingers) {
  ExpectPinchedLiftedAndRolled("brush-rotation");
}
TEST(SimulatorPhysics, PenIsPinchedLiftedAndRolledInTheFingers) {
  ExpectPinchedLiftedAndRolled("pen-fingertip");
}

TEST(SimulatorPhysics, ShampooIsHeldAndLifted) {
  ExpectHeldAndLifted(Physics("shampoo-grasp"), 0.08);
}

}  // namespace
}  // namespace inhand
