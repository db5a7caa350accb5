// The `realistic` profile: every effect measured where it acts (sessions/realism.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/camera_sim.hpp"
#include "inhand/sessions/simulator.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

// ---------------------------------------------------------------------------------------------
// Effect names.

TEST(RealismEffects, ListsGroupsAndNamesTheUnknown) {
  EXPECT_EQ(Effects::Parse("camera", "--effects").Names().size(), 8u);
  EXPECT_EQ(Effects::Parse("all", "--effects").Names().size(),
            static_cast<std::size_t>(Effect::kCount));
  const Effects e = Effects::Parse("hand.pads, torque", "--effects");
  EXPECT_EQ(e.Names(), (std::vector<std::string>{"hand.pads", "torque.drift", "torque.residue",
                                                 "torque.lag"}));
  EXPECT_FALSE(e.AnyCamera());
  EXPECT_FALSE(Effects::Parse("camera.intrinsics", "x")
                   .AnyCamera());  // the session's numbers, not the image
  EXPECT_EQ(Effects::All().Without(Effects::Parse("camera", "x")).Names().size(),
            static_cast<std::size_t>(Effect::kCount) - 8);
  try {
    Effects::Parse("hand.pads,camera.fog", "--without");
    FAIL() << "no error";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("--without: effect 'camera.fog' is unknown"),
              std::string::npos)
        << err.what();
  }
  EXPECT_EQ(ParseNoiseProfile("realistic"), NoiseProfile::kRealistic);
}

// ---------------------------------------------------------------------------------------------
// The object is not its model.

TEST(RealismObject, ScaledBoxHasTheScaledSizeMassAndInertia) {
  ObjectModel box;
  const Vec3 half(0.03, 0.02, 0.05);
  box.pieces.push_back(ConvexPiece::Box(half, MakeTransform(Vec3(0.01, 0, 0), Mat3::Identity())));
  box.visual.push_back(box.pieces.back().ToMesh());
  box.mass = 0.4;
  box.com_O = Vec3(0.01, 0, 0);
  const auto inertia = [](double m, const Vec3& h) {
    return Vec3(m / 3 * (h.y() * h.y() + h.z() * h.z()), m / 3 * (h.x() * h.x() + h.z() * h.z()),
                m / 3 * (h.x() * h.x() + h.y() * h.y()));
  };
  box.inertia_com = inertia(box.mass, half).asDiagonal();
  TagPlacement tag;
  tag.T_OT = MakeTransform(Vec3(0.0, -0.02, 0.01), Mat3::Identity());
  box.tags.push_back(tag);
  const Vec3 s(1.01, 0.995, 1.004);
  const ObjectModel w = ScaledObject(box, s);
  EXPECT_NEAR(w.mass, 0.4 * s.prod(), 1e-12);
  const Vec3 h2 = half.cwiseProduct(s);
  EXPECT_LT((w.inertia_com.diagonal() - inertia(w.mass, h2)).norm(), 1e-12);
  EXPECT_LT((w.Bounds().Size() - 2 * h2).norm(), 1e-12);
  const Aabb pb = [&] {
    Aabb b;
    for (const Vec3& v : w.pieces[0].hull_vertices) b.Extend(v);
    return b;
  }();
  EXPECT_LT((pb.min - Vec3(0.01 * s.x(), 0, 0) + h2).norm(), 1e-12);
  EXPECT_LT((w.com_O - Vec3(0.01 * s.x(), 0, 0)).norm(), 1e-12);
  EXPECT_LT((w.tags[0].T_OT.translation() - Vec3(0, -0.02 * s.y(), 0.01 * s.z())).norm(), 1e-12);
  EXPECT_EQ(w.field, nullptr);
}

TEST(RealismObject, TagsMovedInTheirPlaneAndTurnedByTheGivenAmounts) {
  ObjectModel o = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  ASSERT_EQ(o.tags.size(), 2u);
  const ObjectModel before = o;
  std::mt19937 rng(7);
  MisplaceTags(o, 0.0005, M_PI / 180, rng);
  for (std::size_t i = 0; i < o.tags.size(); ++i) {
    const Vec3 d = before.tags[i].T_OT.linear().transpose() *
                   (o.tags[i].T_OT.translation() - before.tags[i].T_OT.translation());
    EXPECT_NEAR(d.norm(), 0.0005, 1e-12);
    EXPECT_NEAR(d.z(), 0.0, 1e-12);  // in the tag's plane
    EXPECT_NEAR(RotationDistance(o.tags[i].T_OT.linear(), before.tags[i].T_OT.linear()), M_PI / 180,
                1e-9);
  }
}

TEST(RealismObject, TintChangesMaterialAndTextureColours) {
  ObjectModel o = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  const ObjectModel before = o;
  TintObject(o, Vec3(1.1, 1.0, 0.9));
  bool textured = false;
  for (std::size_t i = 0; i < o.visual.size(); ++i) {
    const Eigen::Vector4d a = before.visual[i].material.rgba, b = o.visual[i].material.rgba;
    EXPECT_NEAR(b[0], std::min(1.0, a[0] * 1.1), 1e-12);
    EXPECT_NEAR(b[2], a[2] * 0.9, 1e-12);
    textured |= !o.visual[i].material.texture_blob.empty();
  }
  EXPECT_TRUE(textured);  // the ketchup label
}

// ---------------------------------------------------------------------------------------------
// The hand is not its URDF.

TEST(RealismHand, JointOriginsOffByTheirSigma) {
  const HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  std::mt19937 rng(3);
  std::vector<Vec3> offsets;
  const HandModel w = PerturbedHand(hand, 0.0003, rng, &offsets);
  ASSERT_EQ(offsets.size(), hand.joints.size());
  double sum2 = 0.0;
  for (std::size_t j = 0; j < hand.joints.size(); ++j) {
    EXPECT_LT(
        (w.joints[j].T_LJ.translation() - hand.joints[j].T_LJ.translation() - offsets[j]).norm(),
        1e-15);
    sum2 += offsets[j].squaredNorm();
  }
  const double sigma = std::sqrt(sum2 / (3.0 * offsets.size()));
  EXPECT_GT(sigma, 0.0002);
  EXPECT_LT(sigma, 0.0004);
  // The fingertips move by the chain's accumulated offsets: sub-millimetre to about a millimetre.
  KinematicsData a(hand), b(w);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(hand.num_q(), 0.3);
  a.Update(hand, q);
  b.Update(w, q);
  double worst = 0.0;
  for (std::size_t l = 0; l < hand.links.size(); ++l)
    worst = std::max(worst, (a.T_PL(static_cast<int>(l)).translation() -
                             b.T_PL(static_cast<int>(l)).translation())
                                .norm());
  EXPECT_GT(worst, 0.0003);
  EXPECT_LT(worst, 0.003);
}

// ---------------------------------------------------------------------------------------------
// Simulated sessions (joints only, shortened).

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  int Col(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i);
    return -1;
  }
};
Csv ReadCsv(const std::string& path) {
  Csv c;
  std::ifstream in(path);
  std::string line, cell;
  std::getline(in, line);
  std::stringstream hs(line);
  while (std::getline(hs, cell, ',')) c.header.push_back(cell);
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::vector<double> row;
    while (std::getline(ls, cell, ',')) row.push_back(std::stod(cell));
    c.rows.push_back(row);
  }
  return c;
}

SimulationSummary Sim(const std::string& out, const std::string& effects,
                      double duration_scale = 0.5,
                      const std::string& scenario = "ketchup-power-grasp") {
  SimulateOptions o;
  o.scenario = scenario;
  o.out_dir = out;
  o.seed = 5;
  o.noise = NoiseProfile::kNone;
  o.images = false;
  o.duration_scale = duration_scale;
  o.effects = effects.empty() ? Effects::None() : Effects::Parse(effects, "test");
  return Simulate(o);
}

TEST(RealisticSimulation, NoneStillGivesExactJointMeasurements) {
  test::TempDir dir;
  Sim(dir / "s", "");
  const Csv meas = ReadCsv(dir / "s/joints.csv"), truth = ReadCsv(dir / "s/truth/joints.csv");
  ASSERT_EQ(meas.rows.size(), truth.rows.size());
  ASSERT_GT(meas.rows.size(), 500u);
  for (std::size_t i = 1; i < truth.header.size(); ++i) {
    const int c = meas.Col("q:" + truth.header[i]);
    ASSERT_GE(c, 0) << truth.header[i];
    for (std::size_t k = 0; k < meas.rows.size(); ++k)
      ASSERT_EQ(meas.rows[k][c], truth.rows[k][i]) << truth.header[i] << " sample " << k;
  }
}

TEST(RealisticSimulation, JointDeflectionFollowsTorqueOverStiffness) {
  test::TempDir dir;
  Sim(dir / "s", "hand.deflection");
  const Csv meas = ReadCsv(dir / "s/joints.csv"), truth = ReadCsv(dir / "s/truth/joints.csv");
  // The session states the nominal stiffness; each joint's true one is drawn around it.
  const double nominal = RealismParams().joint_stiffness,
               sigma = RealismParams().joint_stiffness_sigma;
  EXPECT_EQ(nlohmann::json::parse(test::ReadFile(dir / "s/session.json"))
                .at("hand")
                .at("joint_stiffness")
                .get<double>(),
            nominal);
  const nlohmann::json drawn = nlohmann::json::parse(test::ReadFile(dir / "s/truth/truth.json"))
                                   .at("realism")
                                   .at("joint_stiffness_Nm_per_rad");
  ASSERT_EQ(drawn.size(), truth.header.size() - 1);
  double largest = 0.0, sum_log = 0.0, sum_log2 = 0.0;
  for (std::size_t i = 1; i < truth.header.size(); ++i) {
    const int q = meas.Col("q:" + truth.header[i]), tau = meas.Col("tau:" + truth.header[i]);
    ASSERT_GE(q, 0);
    ASSERT_GE(tau, 0);
    const double k = drawn.at(truth.header[i]).get<double>();
    const double z = std::log(k / nominal) / sigma;
    EXPECT_LT(std::abs(z), 4.0) << truth.header[i] << ": k " << k;
    sum_log += z;
    sum_log2 += z * z;
    for (std::size_t s = 0; s < meas.rows.size(); ++s) {
      // The encoder (motor side) is ahead of the link by the load over the stiffness.
      ASSERT_NEAR(meas.rows[s][q] - truth.rows[s][i], meas.rows[s][tau] / k, 1e-12)
          << truth.header[i] << " sample " << s;
      largest = std::max(largest, std::abs(meas.rows[s][q] - truth.rows[s][i]));
    }
  }
  // 16 draws of N(0, 1) in log(k / nominal) / σ: a spread, not one value for every joint.
  const double n = static_cast<double>(truth.header.size() - 1);
  const double sd = std::sqrt(sum_log2 / n - (sum_log / n) * (sum_log / n));
  EXPECT_GT(sd, 0.4);
  EXPECT_LT(sd, 1.8);
  EXPECT_GT(largest, 0.03);  // the grasp loads the joints: > 1.7 deg of deflection somewhere
}

// Torque columns of a session, per sample.
std::vector<Eigen::VectorXd> Torques(const Csv& c) {
  std::vector<int> cols;
  for (std::size_t i = 0; i < c.header.size(); ++i)
    if (c.header[i].rfind("tau:", 0) == 0) cols.push_back(static_cast<int>(i));
  std::vector<Eigen::VectorXd> out;
  for (const auto& row : c.rows) {
    Eigen::VectorXd v(static_cast<int>(cols.size()));
    for (std::size_t j = 0; j < cols.size(); ++j)
      v[static_cast<int>(j)] = row[static_cast<std::size_t>(cols[j])];
    out.push_back(v);
  }
  return out;
}

TEST(RealisticSimulation, TorqueDriftIsASlowOffsetOfItsSigma) {
  test::TempDir dir;
  Sim(dir / "a", "", 0.4);
  Sim(dir / "b", "torque.drift", 0.4);  // the same physics: the torque effects change no motion
  const auto a = Torques(ReadCsv(dir / "a/joints.csv")), b = Torques(ReadCsv(dir / "b/joints.csv"));
  ASSERT_EQ(a.size(), b.size());
  const Eigen::VectorXd d0 = b.front() - a.front();
  const double sigma = std::sqrt(d0.squaredNorm() / d0.size());
  EXPECT_GT(sigma, 0.025);
  EXPECT_LT(sigma, 0.09);
  // Ornstein-Uhlenbeck: over 0.1 s (50 samples at 500 Hz) the offset changes by
  // sigma sqrt(2 (1 - exp(-0.1 s / T))), 0.007 N m for 10 s: slow against its size.
  const RealismParams p;
  const double expected = p.drift_sigma * std::sqrt(2.0 * (1.0 - std::exp(-0.1 / p.drift_time)));
  double sum2 = 0.0;
  int n = 0;
  for (std::size_t k = 50; k < a.size(); k += 50, n += static_cast<int>(d0.size()))
    sum2 += ((b[k] - a[k]) - (b[k - 50] - a[k - 50])).squaredNorm();
  EXPECT_NEAR(std::sqrt(sum2 / n) / expected, 1.0, 0.3);
}

TEST(RealisticSimulation, TorqueLagIsAFirstOrderLowPass) {
  test::TempDir dir;
  Sim(dir / "a", "", 0.4);
  Sim(dir / "b", "torque.lag", 0.4);
  const auto a = Torques(ReadCsv(dir / "a/joints.csv")), b = Torques(ReadCsv(dir / "b/joints.csv"));
  ASSERT_EQ(a.size(), b.size());
  // The same low pass applied to the recorded (500 Hz) contact part predicts it.
  const double dt = 0.002, T = RealismParams().torque_lag;
  Eigen::VectorXd lp = a.front();
  double err_lp = 0.0, err_raw = 0.0;
  for (std::size_t k = 1; k < a.size(); ++k) {
    lp += (dt / (dt + T)) * (a[k] - lp);
    err_lp += (b[k] - lp).squaredNorm();
    err_raw += (b[k] - a[k]).squaredNorm();
  }
  EXPECT_GT(err_raw, 1e-3);  // the grasp's torques change, so the lag shows
  EXPECT_LT(err_lp, 0.1 * err_raw);
}

TEST(RealisticSimulation, FingertipPadsSinkUnderTheGraspForce) {
  test::TempDir dir;
  const SimulationSummary pads = Sim(dir / "p", "hand.pads", 0.7);
  EXPECT_GT(pads.max_penetration, 0.0005);
  EXPECT_LT(pads.max_penetration, 0.0025);
  EXPECT_GT(pads.held_fraction, 0.95);
}

TEST(RealisticSimulation, WorldObjectAndHandAreNotTheModels) {
  test::TempDir dir;
  Sim(dir / "s", "object.scale,hand.geometry", 0.2);
  const nlohmann::json t =
      nlohmann::json::parse(test::ReadFile(dir / "s/truth/truth.json")).at("realism");
  const auto world = t.at("world_object_size_m").get<std::vector<double>>();
  const auto model = t.at("model_object_size_m").get<std::vector<double>>();
  const auto scale = t.at("object_scale").get<std::vector<double>>();
  double off = 0.0;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(world[a], model[a] * scale[a], 1e-9);
    off = std::max(off, std::abs(scale[a] - 1.0));
  }
  EXPECT_GT(off, 1e-4);
  EXPECT_LT(off, 0.025);  // 5 sigma
  EXPECT_EQ(t.at("joint_origin_offsets_m").size(),
            LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf")).joints.size());
  // The session still carries the nominal models.
  EXPECT_EQ(test::ReadFile(dir / "s/model/object/ketchup_bottle.obj"),
            test::ReadFile(test::ProjectAsset("objects/ketchup_bottle/ketchup_bottle.obj")));
  EXPECT_EQ(test::ReadFile(dir / "s/model/hand/inhand_hand.urdf"),
            test::ReadFile(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf")));
}

// The estimator's object is a simplified mesh with its own decomposition; the world's is the
// detailed one. The effect left out, the session's object.json is the model's, byte for byte.
TEST(RealisticSimulation, TheEstimatorGetsASimplifiedMeshWithItsOwnPieces) {
  test::TempDir dir;
  Sim(dir / "s", "object.mesh", 0.2);
  const ObjectModel nominal =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  const ObjectModel model = LoadObjectModel(dir / "s/model/object/object.json");
  const nlohmann::json t = nlohmann::json::parse(test::ReadFile(dir / "s/truth/truth.json"))
                               .at("realism")
                               .at("simplified_model");
  EXPECT_EQ(t.at("model_triangles").get<std::size_t>(), nominal.NumVisualTriangles());
  EXPECT_EQ(t.at("triangles").get<std::size_t>(), model.NumVisualTriangles());
  EXPECT_LT(model.NumVisualTriangles(), 0.7 * static_cast<double>(nominal.NumVisualTriangles()));
  EXPECT_EQ(t.at("pieces").get<std::size_t>(), model.pieces.size());
  EXPECT_NE(model.pieces.size(), nominal.pieces.size());
  // Every vertex kept is a vertex of the detailed mesh, with its uv: the label stays in place.
  std::size_t textured = 0;
  for (const TriangleMesh& m : model.visual) {
    textured += m.material.HasTexture() ? 1 : 0;
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      bool found = false;
      for (const TriangleMesh& n : nominal.visual)
        for (std::size_t j = 0; j < n.vertices.size() && !found; ++j)
          found = (m.vertices[i] - n.vertices[j]).norm() < 1e-8 &&
                  (m.uvs.empty() || (m.uvs[i] - n.uvs[j]).norm() < 1e-8);
      ASSERT_TRUE(found) << "simplified vertex " << i << " is not a model vertex";
    }
  }
  EXPECT_GE(textured, 1u);
  std::vector<const TriangleMesh*> a, b;
  for (const TriangleMesh& m : nominal.visual) a.push_back(&m);
  for (const TriangleMesh& m : model.visual) b.push_back(&m);
  const double v_nominal = ComputeMassProperties(a).volume,
               v_model = ComputeMassProperties(b).volume;
  EXPECT_NEAR(v_model / v_nominal, 1.0, 0.02);
  // The pieces enclose the simplified surface (within 0.1 mm) and its volume (within 3 %).
  double v_pieces = 0.0;
  for (const ConvexPiece& p : model.pieces) {
    const TriangleMesh hull = p.ToMesh();
    v_pieces += ComputeMassProperties({&hull}).volume;
  }
  EXPECT_NEAR(v_pieces / v_model, 1.0, 0.03);
  for (const TriangleMesh& m : model.visual)
    for (const Vec3& v : m.vertices) {
      double outside = std::numeric_limits<double>::infinity();  // least over the pieces
      for (const ConvexPiece& p : model.pieces) {
        double d = -std::numeric_limits<double>::infinity();  // most over the hull's planes
        for (const auto& tri : p.hull_triangles) {
          const Vec3& q0 = p.hull_vertices[static_cast<std::size_t>(tri[0])];
          const Vec3 n = (p.hull_vertices[static_cast<std::size_t>(tri[1])] - q0)
                             .cross(p.hull_vertices[static_cast<std::size_t>(tri[2])] - q0);
          if (n.norm() > 0) d = std::max(d, n.normalized().dot(v - q0));
        }
        outside = std::min(outside, d);
      }
      ASSERT_LT(outside, 1e-4) << "a surface vertex outside every piece";
    }
  // The world collides and renders the detailed mesh: with the effect off the session's model is
  // the asset's.
  Sim(dir / "n", "object.scale", 0.2);
  EXPECT_EQ(test::ReadFile(dir / "n/model/object/object.json"),
            test::ReadFile(test::ProjectAsset("objects/ketchup_bottle/object.json")));
  EXPECT_FALSE(fs::exists(dir / "n/model/object/simplified.obj"));
}

TEST(RealisticSimulation, SameSeedGivesByteIdenticalSessionsWithEveryEffect) {
  test::TempDir dir;
  const auto run = [&](const std::string& name, unsigned seed) {
    SimulateOptions o;
    o.scenario = "ketchup-power-grasp";
    o.out_dir = dir / name;
    o.seed = seed;
    o.noise = NoiseProfile::kRealistic;
    o.duration_scale = 0.3;
    o.image_width = 160;
    o.image_height = 120;
    Simulate(o);
  };
  run("a", 2);
  run("b", 2);
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir / "a"))
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), dir / "a").string());
  ASSERT_GT(files.size(), 10u);
  for (const std::string& f : files)
    EXPECT_EQ(test::ReadFile(dir / ("b/" + f)), test::ReadFile(dir / ("a/" + f))) << f;
  run("c", 3);
  EXPECT_NE(test::ReadFile(dir / "c/images/frame_000001.png"),
            test::ReadFile(dir / "a/images/frame_000001.png"));
  // The session's camera is not the true one.
  const nlohmann::json s =
      nlohmann::json::parse(test::ReadFile(dir / "a/session.json")).at("camera");
  const nlohmann::json t = nlohmann::json::parse(test::ReadFile(dir / "a/truth/truth.json"))
                               .at("realism")
                               .at("true_intrinsics");
  EXPECT_NE(s.at("fx").get<double>(), t.at("fx").get<double>());
  EXPECT_NEAR(s.at("fx").get<double>() / t.at("fx").get<double>(), 1.0, 0.025);
  EXPECT_NEAR(s.at("cx").get<double>(), t.at("cx").get<double>(), 10.0);
  const double k1_session = s.at("distortion")[0].get<double>(),
               k1_true = t.at("distortion")[0].get<double>();
  EXPECT_NE(k1_session, k1_true);
  EXPECT_NEAR(k1_session / k1_true, 1.0, 0.25);
}

}  // namespace
}  // namespace inhand
