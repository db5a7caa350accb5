#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/sessions/session.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

const std::string kHand = "hands/inhand_hand/inhand_hand.urdf";
const std::string kObject = "objects/ketchup_bottle/object.json";

SessionInfo Info() {
  SessionInfo info;
  info.name = "unit";
  info.hand_urdf = test::ProjectAsset(kHand);
  info.object = test::ProjectAsset(kObject);
  Intrinsics K;
  K.width = 64;
  K.height = 48;
  K.fx = K.fy = 60.0;
  K.cx = 31.5;
  K.cy = 23.5;
  info.camera = K;
  info.initial_T_PO = MakeTransform(Vec3(0.01, 0.05, 0.04), ExpSO3(Vec3(0.1, 0.2, -0.3)));
  info.provenance_json = R"({"generator": "unit test", "seed": 7})";
  return info;
}

Image8 Pattern(int frame) {
  Image8 img(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      std::uint8_t* p = img.pixel(x, y);
      p[0] = static_cast<std::uint8_t>(x * 4 + frame);
      p[1] = static_cast<std::uint8_t>(y * 5);
      p[2] = static_cast<std::uint8_t>((x ^ y) * 3);
    }
  return img;
}

// Writes a valid session with the project's hand (16 joints, in reverse order to exercise
// column matching), 50 samples, 3 frames and ground truth.
std::string WriteSession(const test::TempDir& dir, const std::string& name = "s") {
  const HandModel hand = LoadHandModel(test::ProjectAsset(kHand), {{}, false});
  std::vector<std::string> names = hand.QNames();
  std::reverse(names.begin(), names.end());
  SessionWriter w(dir / name, Info(), names);
  for (int k = 0; k < 50; ++k) {
    Eigen::VectorXd q(16), tau(16);
    for (int j = 0; j < 16; ++j) {
      q[j] = 0.01 * j + 1e-3 * k + 1.0 / 3.0;
      tau[j] = -0.05 * j + 0.1 * std::sin(k);
    }
    w.AddJointSample(0.001 * k, q, tau);
    w.AddGroundTruth(0.001 * k,
                     MakeTransform(Vec3(0.001 * k, 0, 0.05), ExpSO3(Vec3(0, 0, 0.01 * k))));
  }
  for (int f = 0; f < 3; ++f)
    w.AddCameraFrame(0.015 * f, Pattern(f),
                     MakeTransform(Vec3(0.1, -0.3, 0.4), ExpSO3(Vec3(1.2, 0, 0.1 * f))));
  w.AddFile("truth/biases.json", "{\"biases\": []}\n");
  w.Commit();
  return dir / name;
}

TEST(Session, WriteReadRoundTripIsExact) {
  test::TempDir dir;
  const std::string path = WriteSession(dir);
  Session s = Session::Load(path);
  EXPECT_EQ(s.info().name, "unit");
  ASSERT_EQ(s.num_samples(), 50);
  ASSERT_EQ(s.joint_names().size(), 16u);
  EXPECT_EQ(s.t(7), 0.007);
  // Values written as shortest round-trip decimals come back bit-exact.
  EXPECT_EQ(s.q(3)[15], 0.01 * 15 + 1e-3 * 3 + 1.0 / 3.0);
  EXPECT_EQ(s.tau(9)[0], -0.05 * 0 + 0.1 * std::sin(9));
  EXPECT_EQ(s.joint_names()[15], "index_abduction");  // written in reverse order
  EXPECT_LT((s.info().initial_T_PO.matrix() - Info().initial_T_PO.matrix()).norm(), 1e-15);
  ASSERT_EQ(s.camera_frames().size(), 3u);
  const Image8 img = s.LoadImage(2);
  EXPECT_EQ(img.data, Pattern(2).data);  // PNG is lossless
  EXPECT_TRUE(s.has_groundtruth());
  // Ground truth interpolates between samples.
  const Transform mid = s.GroundTruthAt(0.0105);
  EXPECT_NEAR(mid.translation().x(), 0.0105, 1e-12);
  EXPECT_NEAR(LogSO3(mid.linear()).z(), 0.105, 1e-9);
  EXPECT_TRUE(fs::exists(path + "/truth/biases.json"));
  EXPECT_NE(test::ReadFile(path + "/session.json").find("\"seed\": 7"), std::string::npos);

  // Joints match the hand by name; the session keeps the file's column order.
  const std::vector<std::string> file_order = s.joint_names();
  const SessionModels models = LoadSessionModels(s, false);
  EXPECT_EQ(s.joint_names(), file_order);
  ASSERT_EQ(models.joint_columns.size(), 16u);
  for (std::size_t j = 0; j < 16; ++j)
    EXPECT_EQ(s.joint_names()[static_cast<std::size_t>(models.joint_columns[j])],
              models.hand.QNames()[j]);
  EXPECT_EQ(s.q(3)[models.joint_columns[0]],
            0.01 * 15 + 1e-3 * 3 + 1.0 / 3.0);  // index_abduction, first in the URDF
  EXPECT_EQ(models.object.name, "ketchup_bottle");
}

// hand.joint_stiffness: one value for every joint, or by name with "*" for the rest; the hand
// the session loads carries it in its configuration order.
TEST(Session, JointStiffnessReachesTheHandByName) {
  test::TempDir dir;
  SessionInfo info = Info();
  info.joint_stiffness = {{"*", 20.0}, {"thumb_flex1", 35.0}};
  SessionWriter w(dir / "s", info, LoadHandModel(test::ProjectAsset(kHand), {{}, false}).QNames());
  for (int k = 0; k < 3; ++k)
    w.AddJointSample(0.001 * k, Eigen::VectorXd::Zero(16), Eigen::VectorXd::Zero(16));
  w.Commit();
  const Session s = Session::Load(dir / "s");
  EXPECT_EQ(s.info().joint_stiffness, info.joint_stiffness);
  const SessionModels models = LoadSessionModels(s, false);
  const std::vector<std::string> names = models.hand.QNames();
  ASSERT_EQ(models.hand.joint_stiffness.size(), 16u);
  for (std::size_t j = 0; j < 16; ++j)
    EXPECT_EQ(models.hand.joint_stiffness[j], names[j] == "thumb_flex1" ? 35.0 : 20.0) << names[j];

  // One number for every joint is written as a number.
  info.joint_stiffness = {{"*", 12.5}};
  SessionWriter w2(dir / "t", info, names);
  w2.AddJointSample(0.0, Eigen::VectorXd::Zero(16), Eigen::VectorXd::Zero(16));
  w2.Commit();
  EXPECT_NE(test::ReadFile(dir / "t/session.json").find("\"joint_stiffness\": 12.5"),
            std::string::npos);
  const SessionModels rigid_unless_named = LoadSessionModels(Session::Load(dir / "t"), false);
  EXPECT_EQ(rigid_unless_named.hand.joint_stiffness, std::vector<double>(16, 12.5));
  // Without the field every joint is rigid.
  EXPECT_TRUE(
      LoadSessionModels(Session::Load(WriteSession(dir, "u")), false).hand.joint_stiffness.empty());
}

TEST(Session, WriterIsAllOrNothing) {
  test::TempDir dir;
  {
    SessionWriter w(dir / "half", Info(), {"a"});
    w.AddJointSample(0.0, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1));
    // destroyed without Commit(): nothing is left behind
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), {}), 0);
  WriteSession(dir, "done");
  EXPECT_THROW(SessionWriter(dir / "done", Info(), {"a"}), InputError);  // no silent overwrite
}

// Corrupts a copy of a valid session and checks the message names what is wrong.
class BadSession : public ::testing::Test {
 protected:
  void SetUp() override { path_ = WriteSession(dir_); }
  void Replace(const std::string& file, const std::string& pattern, const std::string& with) {
    const std::string text = test::ReadFile(path_ + "/" + file);
    const std::string out = std::regex_replace(text, std::regex(pattern), with,
                                               std::regex_constants::format_first_only);
    ASSERT_NE(out, text) << "pattern not found: " << pattern;
    std::ofstream(path_ + "/" + file) << out;
  }
  void ExpectError(const std::vector<std::string>& fragments, bool load_models = false) {
    try {
      Session s = Session::Load(path_);
      if (load_models) LoadSessionModels(s, false);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      for (const auto& f : fragments)
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
            << e.what() << "\nmissing: " << f;
    }
  }
  test::TempDir dir_;
  std::string path_;
};

TEST_F(BadSession, MissingFiles) {
  fs::remove(path_ + "/joints.csv");
  ExpectError({"joints.csv", "cannot open"});
}

TEST_F(BadSession, MissingImage) {
  fs::remove(path_ + "/images/frame_000001.png");
  ExpectError({"camera.csv:3", "frame_000001.png", "not found"});
}

TEST_F(BadSession, WrongColumnCount) {
  Replace("joints.csv", "\n0.005,", "\n0.005,1,");
  ExpectError({"joints.csv:7", "34 columns, expected 33"}, false);
}

TEST_F(BadSession, NaNAndText) {
  Replace("joints.csv", "\n0.004,([^,]*),", "\n0.004,nan,");
  ExpectError({"joints.csv:6", "column 'q:thumb_flex3'", "'nan'", "finite number"});
}

TEST_F(BadSession, NonNumeric) {
  Replace("groundtruth.csv", "\n0.002,", "\n0.002x,");
  ExpectError({"groundtruth.csv:4", "column 't'"});
}

TEST_F(BadSession, TimeGoesBackwards) {
  Replace("joints.csv", "\n0.006,", "\n0.004,");
  ExpectError({"joints.csv:8", "does not increase"});
}

TEST_F(BadSession, JointNotInUrdf) {
  Replace("joints.csv", "q:ring_flex2", "q:pinky_flex2");
  Replace("joints.csv", "tau:ring_flex2", "tau:pinky_flex2");
  ExpectError({"joint 'pinky_flex2'", "inhand_hand.urdf"}, true);
}

TEST_F(BadSession, TorqueColumnsMustFollowPositions) {
  Replace("joints.csv", "tau:ring_flex2", "tau:ring_flexX");
  ExpectError({"joints.csv:1", "expected 'tau:ring_flex2'"});
}

TEST_F(BadSession, MalformedJson) {
  Replace("session.json", "\"name\": \"unit\",", "\"name\": \"unit\"");
  ExpectError({"session.json:", "malformed JSON"});
}

TEST_F(BadSession, JointStiffness) {
  const std::string good = test::ReadFile(path_ + "/session.json");
  const auto with = [&](const std::string& value) {
    std::ofstream(path_ + "/session.json") << std::regex_replace(
        good, std::regex("\"hand\": \\{"), "\"hand\": {\"joint_stiffness\": " + value + ",");
  };
  with("-20");
  ExpectError({"session.json", "'hand.joint_stiffness'", "-20"});
  with("0");
  ExpectError({"session.json", "'hand.joint_stiffness'"});
  with("\"stiff\"");
  ExpectError({"session.json", "'hand.joint_stiffness'", "N m/rad"});
  with("{}");
  ExpectError({"session.json", "'hand.joint_stiffness'", "N m/rad"});
  with("{\"index_flex1\": null}");
  ExpectError({"session.json", "'hand.joint_stiffness.index_flex1'"});
  with("{\"pinky_flex2\": 20}");
  ExpectError({"session.json", "'hand.joint_stiffness.pinky_flex2'", "no independent joint"}, true);
  with("{\"index_flex1\": 20, \"*\": 30}");
  EXPECT_EQ(LoadSessionModels(Session::Load(path_), false).hand.joint_stiffness[1],
            20.0);  // index_flex1, second in the URDF
}

TEST_F(BadSession, ImpossibleIntrinsics) {
  Replace("session.json", "\"fx\": 60.0", "\"fx\": -60.0");
  ExpectError({"session.json", "'fx'"});
}

// Numbers no recording can hold are refused by name, not carried into the filter: a camera
// 1e300 m away, a time of 1e300 s, an initial pose 1e300 m off, distortion of 1e6.
TEST_F(BadSession, AbsurdMagnitudes) {
  const std::string camera = test::ReadFile(path_ + "/camera.csv"),
                    joints = test::ReadFile(path_ + "/joints.csv"),
                    json = test::ReadFile(path_ + "/session.json");
  const auto restore = [&] {
    std::ofstream(path_ + "/camera.csv") << camera;
    std::ofstream(path_ + "/joints.csv") << joints;
    std::ofstream(path_ + "/session.json") << json;
  };
  Replace("camera.csv", "(\n[^,]*,[^,]*,)[^,]*,", "$011e300,");
  ExpectError({"camera.csv:2", "position (px, py, pz)", "within 10 m"});
  restore();
  Replace("joints.csv", "\n0.005,", "\n1e300,");
  ExpectError({"joints.csv:7", "time 1e+300 s", "within +-1e9 s"});
  restore();
  Replace("session.json", "\"xyz\": \\[\\s*[^,\\]]*", "\"xyz\": [1e300");
  ExpectError({"session.json", "initial_estimate.T_PO.xyz", "within 10 m of the palm"});
  restore();
  Session::Load(path_);  // restored: accepted again
  Replace("session.json", "\"fx\": 60.0", "\"fx\": 60.0, \"distortion\": [1e6, 0, 0, 0, 0]");
  ExpectError({"session.json", "'distortion'", "inverted"});
}

TEST_F(BadSession, NonUnitQuaternion) {
  Replace("groundtruth.csv", "\n0.003,([^,]*),([^,]*),([^,]*),([^,]*),", "\n0.003,$1,$2,$3,3,");
  ExpectError({"groundtruth.csv:5", "norm"});
}

TEST_F(BadSession, UnknownPackageAndMissingMesh) {
  test::TempDir hand_dir;
  hand_dir.Write("h.urdf",
                 "<robot name='r'><link name='palm'><visual><geometry><mesh "
                 "filename='package://nowhere/x.stl'/>"
                 "</geometry></visual></link></robot>");
  Replace("session.json", "\"urdf\": \"[^\"]*\"", "\"urdf\": \"" + (hand_dir / "h.urdf") + "\"");
  ExpectError({"unknown package 'nowhere'"}, true);
  hand_dir.Write("h.urdf",
                 "<robot name='r'><link name='palm'><visual><geometry><mesh filename='gone.stl'/>"
                 "</geometry></visual></link></robot>");
  ExpectError({"gone.stl", "not found"}, true);
  hand_dir.Write("h.urdf", "<robot name='r'><link name='palm'>");
  ExpectError({"h.urdf:", "malformed XML"}, true);
}

TEST_F(BadSession, UnreadableImage) {
  std::ofstream(path_ + "/images/frame_000000.png") << "garbage";
  Session s = Session::Load(path_);
  EXPECT_THROW(s.LoadImage(0), InputError);
  EXPECT_NO_THROW(s.LoadImage(1));
}

}  // namespace
}  // namespace inhand
