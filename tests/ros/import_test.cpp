// inhand import, tested on recordings written by the official tools of each format (Debian's
// rosbag writer; @mcap/core, @foxglove/rosmsg2-serialization and sql.js): the synthetic recording
// of tests/ros/synthetic.mjs in five files, round trips of a simulated session, bad input, and
// the real Allegro bag in ../shared/fixtures.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/import.hpp"
#include "inhand/ros/recording.hpp"
#include "inhand/ros/tf_tree.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/session.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

const std::vector<std::string> kFormats = {"synthetic.bag", "synthetic.mcap", "synthetic_zstd.mcap",
                                           "synthetic_lz4.mcap", "synthetic.db3"};
std::string Fixture(const std::string& name) {
  return test::SourceDir() + "/tests/ros/fixtures/" + name;
}
const std::string kHand = test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf");
const std::string kObject = test::ProjectAsset("objects/ketchup_bottle/object.json");

std::string Import(const std::string& recording, const std::string& out,
                   const std::string& extra = "") {
  return "import " + recording + " --out " + out + " --hand " + kHand + " --object " + kObject +
         " " + extra;
}
// The synthetic recording's poses (synthetic.mjs).
Transform AboutZ(const Vec3& p, double a) {
  return MakeTransform(p, Quat(Eigen::AngleAxisd(a, Vec3::UnitZ())));
}
Transform WorldPalm() { return AboutZ(Vec3(0.1, 0.2, 0.3), M_PI / 6); }
Transform CameraLinkOptical() { return MakeTransform(Vec3::Zero(), Quat(0.5, -0.5, 0.5, -0.5)); }
Transform WorldCameraLink(double s) { return AboutZ(Vec3(0.5 + 0.1 * s, -0.2, 0.4), 0.2 * s); }
Transform WorldObject(double s) {
  return MakeTransform(Vec3(0.15, 0.2 + 0.05 * s, 0.35),
                       Quat(Eigen::AngleAxisd(0.1 * s, Vec3::UnitX())));
}
double PoseError(const Transform& a, const Transform& b) {
  return std::max((a.translation() - b.translation()).norm(),
                  LogSO3(a.linear().transpose() * b.linear()).norm());
}

// Every format's file imports to the recording the formulas describe, and to byte-identical
// sessions: joints by name (arm joints ignored, the hand's in reverse order), out-of-order
// stamps sorted, a duplicate dropped, images from rgb8, T_PC through a static + dynamic TF
// chain interpolated between samples, ground truth moved from the world into the palm frame.
TEST(Import, EveryFormatGivesTheSyntheticRecording) {
  test::TempDir dir;
  const HandModel hand = LoadHandModel(kHand, {{}, false});
  const std::vector<std::string> names = hand.QNames();
  std::string first_joints, first_camera, first_truth;
  for (const std::string& format : kFormats) {
    SCOPED_TRACE(format);
    const std::string out = dir / format;
    const test::CommandResult r = test::RunInhand(
        Import(Fixture(format), out,
               "--image /camera/image_raw --object-pose /mocap/object --effort-is external"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("199 samples"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("1 duplicate stamps"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("1 out of order"), std::string::npos) << r.output;
    const Session s = Session::Load(out);
    ASSERT_EQ(s.joint_names(), names);
    ASSERT_TRUE(s.has_torques());
    ASSERT_EQ(s.num_samples(), 199);
    int i = 0;
    for (int kk = 0; kk < 200; ++kk) {
      if (kk == 51) continue;                                // its stamp repeats 50's
      const int k = kk == 100 ? 101 : kk == 101 ? 100 : kk;  // stamps 100 and 101 swapped
      ASSERT_EQ(s.t(i), kk * 5000000 / 1e9) << i;
      for (int j = 0; j < 16; ++j) {
        ASSERT_EQ(s.q(i)[j], 0.1 + 0.02 * j + 0.001 * k) << names[j] << " sample " << i;
        ASSERT_EQ(s.tau(i)[j], 0.01 * j - 0.0005 * k) << names[j] << " sample " << i;
      }
      ++i;
    }
    ASSERT_TRUE(s.info().camera.has_value());
    const Intrinsics& K = *s.info().camera;
    EXPECT_EQ(K.width, 64);
    EXPECT_EQ(K.fx, 60.0);
    EXPECT_EQ(K.cy, 23.5);
    EXPECT_EQ(K.distortion[0], 0.01);
    EXPECT_EQ(K.distortion[3], 0.0003);
    ASSERT_EQ(s.camera_frames().size(), 10u);
    double worst = 0;
    for (int f = 0; f < 10; ++f) {
      const double t = (f * 50000000 + 2500000) / 1e9;
      EXPECT_EQ(s.camera_frames()[static_cast<std::size_t>(f)].t, t);
      const Transform expected = WorldPalm().inverse() * WorldCameraLink(t) * CameraLinkOptical();
      worst =
          std::max(worst, PoseError(expected, s.camera_frames()[static_cast<std::size_t>(f)].T_PC));
      const Image8 img = s.LoadImage(f);
      for (int y = 0; y < 48; y += 7)
        for (int x = 0; x < 64; x += 5) {
          const std::uint8_t* p = img.pixel(x, y);
          ASSERT_EQ(p[0], (x * 4 + f * 7) & 255);
          ASSERT_EQ(p[1], (y * 5 + f) & 255);
          ASSERT_EQ(p[2], ((x ^ y) * 3) & 255);
        }
    }
    EXPECT_LT(worst, 1e-9);
    ASSERT_EQ(s.groundtruth().size(), 100u);
    worst = 0;
    for (int g = 0; g < 100; ++g) {
      const double t = (g * 10000000 + 1000000) / 1e9;
      EXPECT_EQ(s.groundtruth()[static_cast<std::size_t>(g)].t, t);
      worst = std::max(worst, PoseError(WorldPalm().inverse() * WorldObject(t),
                                        s.groundtruth()[static_cast<std::size_t>(g)].T_PO));
    }
    EXPECT_LT(worst, 1e-9);
    EXPECT_LT(PoseError(s.info().initial_T_PO, WorldPalm().inverse() * WorldObject(0.001)), 1e-9);
    // The same bytes whichever writer made the recording.
    if (first_joints.empty()) {
      first_joints = test::ReadFile(out + "/joints.csv"),
      first_camera = test::ReadFile(out + "/camera.csv"),
      first_truth = test::ReadFile(out + "/groundtruth.csv");
    } else {
      EXPECT_EQ(test::ReadFile(out + "/joints.csv"), first_joints);
      EXPECT_EQ(test::ReadFile(out + "/camera.csv"), first_camera);
      EXPECT_EQ(test::ReadFile(out + "/groundtruth.csv"), first_truth);
    }
  }
}

// Ground truth from TransformStamped (in the world) and from Odometry (in camera_link, through the
// dynamic TF edge, interpolated), in every format.
TEST(Import, GroundTruthFromTransformStampedAndOdometry) {
  test::TempDir dir;
  const auto camera_link_object = [](double s) {
    return MakeTransform(Vec3(0.05, 0.1 + 0.02 * s, -0.03),
                         Quat(Eigen::AngleAxisd(0.3 * s, Vec3::UnitX())));
  };
  for (const std::string& format : kFormats) {
    for (const std::string topic : {"/mocap/object_tf", "/odom"}) {
      SCOPED_TRACE(format + " " + topic);
      const std::string out = dir / (format + topic.substr(1));
      const test::CommandResult r =
          test::RunInhand(Import(Fixture(format), out, "--no-images --object-pose " + topic));
      ASSERT_EQ(r.exit_code, 0) << r.output;
      const Session s = Session::Load(out);
      ASSERT_EQ(s.groundtruth().size(), 50u);
      double worst = 0;
      for (int g = 0; g < 50; ++g) {
        const double t = (2 * g * 10000000 + 1000000) / 1e9;
        const Transform expected =
            topic == "/odom" ? WorldPalm().inverse() * WorldCameraLink(t) * camera_link_object(t)
                             : WorldPalm().inverse() * WorldObject(t);
        EXPECT_EQ(s.groundtruth()[static_cast<std::size_t>(g)].t, t);
        worst =
            std::max(worst, PoseError(expected, s.groundtruth()[static_cast<std::size_t>(g)].T_PO));
      }
      EXPECT_LT(worst, 1e-9);
    }
  }
}

// --list names every topic with its type, count and rate, and the TF tree.
TEST(Import, ListShowsTopicsAndFrames) {
  for (const std::string& format : {std::string("synthetic.bag"), std::string("synthetic_lz4.mcap"),
                                    std::string("synthetic.db3")}) {
    const test::CommandResult r = test::RunInhand("import " + Fixture(format) + " --list");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    for (const char* want :
         {"/joint_states", "sensor_msgs/JointState", "200", "200.0", "/camera/image_raw",
          "sensor_msgs/Image", "camera_optical <- camera_link  (static)",
          "camera_link <- world  (101 transforms)", "palm <- world"})
      EXPECT_NE(r.output.find(want), std::string::npos) << format << ": " << want << "\n"
                                                        << r.output;
  }
}

// A window and a time origin: --start/--end cut by the joint samples' clock; --time-origin
// keeps the recording's own time.
TEST(Import, WindowAndTimeOrigin) {
  test::TempDir dir;
  const test::CommandResult r =
      test::RunInhand(Import(Fixture("synthetic.mcap"), dir / "s",
                             "--no-images --initial-pose=-0.03,0.01,0.1,1,0,0,0 --start 0.1 --end "
                             "0.2 --time-origin 1700000000"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Session s = Session::Load(dir / "s");
  EXPECT_FALSE(s.has_torques());
  EXPECT_FALSE(s.info().camera.has_value());
  ASSERT_EQ(s.num_samples(), 21);  // stamps 100 ms to 200 ms, 5 ms apart
  EXPECT_EQ(s.t(0), 250000000 / 1e9 + 0.1);
  EXPECT_NEAR(s.info().initial_T_PO.translation().x(), -0.03, 1e-15);
}

// An elastic hand's stiffness goes into session.json, by joint or for every joint.
TEST(Import, JointStiffnessReachesTheSession) {
  test::TempDir dir;
  const std::string base =
      "--no-images --object-pose /mocap/object --effort-is external --joint-stiffness ";
  ASSERT_EQ(
      test::RunInhand(Import(Fixture("synthetic.mcap"), dir / "s", base + "thumb_flex1=35,*=20"))
          .exit_code,
      0);
  EXPECT_EQ(Session::Load(dir / "s").info().joint_stiffness,
            (std::map<std::string, double>{{"*", 20.0}, {"thumb_flex1", 35.0}}));
  ASSERT_EQ(test::RunInhand(Import(Fixture("synthetic.mcap"), dir / "t", base + "12.5")).exit_code,
            0);
  const SessionModels models = LoadSessionModels(Session::Load(dir / "t"), false);
  EXPECT_EQ(models.hand.joint_stiffness, std::vector<double>(16, 12.5));
}

// Bad input: one clear line naming what is wrong, exit 2, and no output folder.
TEST(Import, BadInputIsOneClearLineAndNoOutput) {
  test::TempDir dir;
  const std::string bag = Fixture("synthetic.bag"), mcap = Fixture("synthetic_zstd.mcap");
  dir.Write("notabag.bag", "this is not a recording\n");
  for (const auto& [name, size] : {std::pair<std::string, double>{"synthetic.bag", 0.6},
                                   {"synthetic_zstd.mcap", 0.6},
                                   {"synthetic.mcap", 0.3}}) {
    const std::string all = test::ReadFile(Fixture(name));
    dir.Write("cut_" + name,
              all.substr(0, static_cast<std::size_t>(size * static_cast<double>(all.size()))));
  }
  dir.Write("finger.urdf",
            "<robot name=\"finger\"><link name=\"palm\"/><link name=\"tip\"/><joint "
            "name=\"finger_joint\" type=\"revolute\">"
            "<parent link=\"palm\"/><child link=\"tip\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" "
            "upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>");
  const std::string gt = "--object-pose /mocap/object";
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {Import(dir / "notabag.bag", dir / "out", gt), "not a ROS recording"},
      {Import(dir / "cut_synthetic.bag", dir / "out", "--image /camera/image_raw " + gt),
       "cut_synthetic.bag"},
      {Import(dir / "cut_synthetic_zstd.mcap", dir / "out", "--image /camera/image_raw " + gt),
       "truncated or corrupt MCAP"},
      {Import(dir / "cut_synthetic.mcap", dir / "out", "--image /camera/image_raw " + gt),
       "truncated or corrupt MCAP"},
      {Import(bag, dir / "out", "--joints /nope " + gt),
       "--joints /nope: no such topic; the recording has /camera/camera_info"},
      {Import(mcap, dir / "out", "--joints /camera/camera_info " + gt),
       "is of type sensor_msgs/CameraInfo, expected sensor_msgs/JointState"},
      {Import(bag, dir / "out", "--image /camera3/image_raw " + gt),
       "image encoding 'yuv422' is not supported"},
      {Import(mcap, dir / "out", "--image /camera2/image_raw " + gt),
       "image is 64x48, camera_info says 640x480"},
      {Import(bag, dir / "out", "--image /camera/image_raw --camera-frame table_marker " + gt),
       "no TF path from 'palm' to 'table_marker'"},
      {Import(mcap, dir / "out", "--image /camera/image_raw"), "no initial estimate"},
      {Import(bag, dir / "out", gt),
       "several sensor_msgs/Image or sensor_msgs/CompressedImage topics"},
      {"import " + bag + " --out " + (dir / "out") + " --hand " + (dir / "finger.urdf") +
           " --object " + kObject + " --no-images " + gt,
       "the hand's joint finger_joint is not in the message, which names arm_joint_1, arm_joint_2, "
       "thumb_flex3"},
      {Import(bag, dir / "out", "--no-images --initial-pose 1,2,3"), "--initial-pose: 3 numbers"},
      {Import(bag, dir / "out", "--no-images --initial-pose=0,0,0,2,0,0,0"), "has norm 2"},
      {Import(bag, dir / "out", "--no-images --effort-is measured " + gt),
       "--effort-is: 'measured'"},
      {Import(bag, dir / "out", "--no-images --joint-stiffness 20 " + gt),
       "--joint-stiffness: the correction q - tau / k needs the external torques"},
      {Import(bag, dir / "out",
              "--no-images --effort-is external --joint-stiffness index_flex1=-3 " + gt),
       "--joint-stiffness: 'index_flex1=-3'"},
      {Import(bag, dir / "out", "--no-images --effort-is external --joint-stiffness stiff " + gt),
       "--joint-stiffness: 'stiff' is not a number"},
      {Import(bag, dir / "out",
              "--no-images --effort-is external --joint-stiffness pinky_flex2=20 " + gt),
       "has no independent joint 'pinky_flex2'"},
  };
  for (const Case& c : cases) {
    const test::CommandResult r = test::RunInhand(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos)
        << c.args << "\nexpected: " << c.expected << "\ngot: " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << c.args;
  }
  // Nothing left beside the target either (no staging folders).
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".out"), std::string::npos) << e.path();
}

#ifdef INHAND_WITH_GUI
// `inhand gui RECORDING` imports it with import's options into a session of its own, opens it and
// removes that session when it closes; import's options beside a session are refused.
TEST(Import, TheGuiOpensARecordingDirectly) {
  test::TempDir dir;
  const auto sessions_left = [] {
    int n = 0;
    for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
      n += e.path().filename().string().rfind("inhand-gui-", 0) == 0;
    return n;
  };
  const int before = sessions_left();
  const std::string options = " --hand " + kHand + " --object " + kObject +
                              " --image /camera/image_raw --object-pose /mocap/object"
                              " --effort-is external";
  // The whole session's events known, at 0.5 s: the same window as for the session imported
  // first.
  dir.Write("look.txt",
            "wait-events\nseek 0.5\nwait 2\nexpect time 0.5 0.003\n"
            "expect events any 1\nscreenshot " +
                (dir / "gui.png") + "\n");
  const test::CommandResult r = test::RunInhand(
      "gui " + Fixture("synthetic.mcap") + options + " --script " + (dir / "look.txt"),
      "env -u DISPLAY");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("199 samples"), std::string::npos) << r.output;  // import's report
  EXPECT_EQ(sessions_left(), before);
  ASSERT_EQ(test::RunInhand(Import(Fixture("synthetic.mcap"), dir / "s",
                                   "--image /camera/image_raw --object-pose /mocap/object "
                                   "--effort-is external"))
                .exit_code,
            0);
  dir.Write("look2.txt",
            "wait-events\nseek 0.5\nwait 2\nscreenshot " + (dir / "session.png") + "\n");
  const test::CommandResult imported =
      test::RunInhand("gui " + (dir / "s") + " --script " + (dir / "look2.txt"), "env -u DISPLAY");
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  const test::CommandResult same =
      test::RunInhand("compare " + (dir / "gui.png") + " " + (dir / "session.png") +
                      " --max-channel-delta 0 --max-bad-fraction 0");
  EXPECT_EQ(same.exit_code, 0) << same.output;
  // Import's options apply to recordings only; a recording that is not there is named.
  const test::CommandResult session =
      test::RunInhand("gui " + (dir / "s") + " --hand " + kHand + " --frames 1");
  EXPECT_EQ(session.exit_code, 2);
  EXPECT_NE(session.output.find("--hand is an import option"), std::string::npos) << session.output;
  const test::CommandResult missing =
      test::RunInhand("gui " + (dir / "none.bag") + options + " --frames 1");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("none.bag"), std::string::npos) << missing.output;
  EXPECT_EQ(sessions_left(), before);
}
#endif

// The TF tree on its own: composition along both branches, interpolation, and the error that
// names the two parts of a split tree.
TEST(TfTree, ComposesInterpolatesAndNamesSplitTrees) {
  ros::TfTree tree;
  const auto add = [&](const std::string& parent, const std::string& child, std::int64_t t,
                       const Transform& T, bool is_static) {
    ros::StampedTransform s;
    s.header.frame_id = parent;
    s.header.stamp_ns = t;
    s.child_frame_id = child;
    s.T = {T.translation(), Quat(T.linear())};
    tree.Add(s, is_static);
  };
  const Transform A = AboutZ(Vec3(1, 2, 3), 0.3),
                  B = MakeTransform(Vec3(-1, 0.5, 0), ExpSO3(Vec3(0.1, -0.2, 0.3)));
  add("world", "a", 0, A, true);
  add("world", "b", 0, B, false);
  add("world", "b", 1000, B * AboutZ(Vec3(0.1, 0, 0), 0.5), false);
  add("island", "rock", 0, A, true);
  tree.Finish();
  const auto T = tree.Lookup("a", "b", 500);
  ASSERT_TRUE(T.has_value());
  EXPECT_LT(PoseError(T->ToTransform(), A.inverse() * B * AboutZ(Vec3(0.05, 0, 0), 0.25)), 1e-12);
  EXPECT_LT(PoseError(tree.Lookup("b", "world", 0)->ToTransform(), B.inverse()), 1e-12);
  try {
    tree.Lookup("a", "rock", 0);
    ADD_FAILURE() << "no error for a split tree";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("{a, b, world} and {island, rock}"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(
      tree.Lookup("a", "b", 5000000000LL, true).has_value());  // 5 s beyond the last sample
  // Covers: a lookup up to the dynamic edge's newest sample interpolates; after it, it would hold.
  EXPECT_TRUE(tree.Covers("a", "b", 0));
  EXPECT_TRUE(tree.Covers("b", "a", 1000));
  EXPECT_FALSE(tree.Covers("a", "b", 1001));
  EXPECT_TRUE(tree.Covers("a", "world", 1LL << 60));  // static only
  EXPECT_FALSE(tree.Covers("a", "rock", 0));          // no chain
  add("world", "b", 2000, B, false);
  tree.Finish();
  EXPECT_TRUE(tree.Covers("a", "b", 1001));
}

// A live tree forgets old samples but answers as before from the newest one before the cut on:
// one sample per second turning about z, samples added out of order (Finish sorts them).
TEST(TfTree, ForgettingKeepsTheAnswersAfterTheCut) {
  ros::TfTree full, live;
  constexpr std::int64_t kSecond = 1000000000;
  for (const int k : {0, 2, 1, 3, 5, 4, 6, 7, 8, 9, 10}) {
    ros::StampedTransform s;
    s.header.frame_id = "palm";
    s.header.stamp_ns = k * kSecond;
    s.child_frame_id = "camera";
    s.T = {Vec3(0.1 * k, 0, 0), Quat(ExpSO3(Vec3(0, 0, 0.05 * k)))};
    full.Add(s, false);
    live.Add(s, false);
  }
  full.Finish();
  live.Finish();
  live.Forget(5 * kSecond + kSecond / 2);  // keeps 5 s (the newest before the cut) and later
  EXPECT_EQ(live.Edges().at("camera").samples, 6u);
  for (const std::int64_t t :
       {5 * kSecond, 5 * kSecond + kSecond / 4, 7 * kSecond + 3, 10 * kSecond}) {
    const auto a = full.Lookup("palm", "camera", t), b = live.Lookup("palm", "camera", t);
    ASSERT_TRUE(a && b) << t;
    EXPECT_EQ(a->p, b->p) << t;
    EXPECT_EQ(a->q.coeffs(), b->q.coeffs()) << t;
  }
  // Before the kept samples the edge holds no sample within the extrapolation limit (0.1 s).
  EXPECT_TRUE(full.Lookup("palm", "camera", 2 * kSecond, true).has_value());
  EXPECT_FALSE(live.Lookup("palm", "camera", 2 * kSecond, true).has_value());
}

// The real Allegro recording (../shared/fixtures): 16 joints named joint_0.0 ... joint_15.0, no
// images, no torques. Every sample imports; replay runs j and renders the 3-D view of the real
// finger motion into a video.
TEST(Import, RealAllegroBagReplaysWithA3dVideo) {
  const fs::path bag =
      fs::path(test::SourceDir()).parent_path() / "shared/fixtures/ros1/allegro_jointstates.bag";
  if (!fs::exists(bag)) GTEST_SKIP() << bag << " is absent";
  INHAND_REQUIRE_SHARED_ASSETS();
  test::TempDir dir;
  const std::string hands = test::SharedAssets() + "/hands/allegro_hand/allegro_hand_right.urdf";
  const test::CommandResult r = test::RunInhand(
      "import " + bag.string() + " --out " + (dir / "s") + " --hand " + hands + " --object " +
      test::SharedAssets() +
      "/objects/ycb/large_marker.urdf --initial-pose=0.05,0,0.09,0.7071068,0.7071068,0,0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Session s = Session::Load(dir / "s");
  EXPECT_EQ(s.num_samples(), 2697);
  EXPECT_FALSE(s.has_torques());
  EXPECT_FALSE(s.info().camera.has_value());
  EXPECT_NEAR(s.t(s.num_samples() - 1), 8.091, 0.001);
  ASSERT_EQ(s.joint_names().size(), 16u);
  EXPECT_EQ(s.joint_names()[15], "joint_15.0");
  // The fingers really move in this recording.
  EXPECT_GT((s.q(s.num_samples() - 1) - s.q(0)).cwiseAbs().maxCoeff(), 0.2);

  const test::CommandResult replay = test::RunInhand("replay " + (dir / "s") + " --out " +
                                                     (dir / "r") + " --frames --video-fps 5");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("  j: "), std::string::npos) << replay.output;
  EXPECT_TRUE(fs::exists(dir / "r/replay.mp4"));
  int frames = 0;
  for (const auto& e : fs::directory_iterator(dir / "r/frames"))
    frames += e.path().extension() == ".png";
  EXPECT_EQ(frames, 41);  // 8.09 s at 5 Hz, from t = 0
  const Image8 first = ReadImage(dir / "r/frames/frame_000000.png");
  EXPECT_EQ(first.width, 960);
  EXPECT_EQ(test::RunInhand("compare " + (dir / "r/frames/frame_000000.png") + " " +
                            (dir / "r/frames/frame_000040.png"))
                .exit_code,
            1);
  // Sequential and parallel replays agree (the blocks end at the pictures' times).
  const test::CommandResult one = test::RunInhand(
      "replay " + (dir / "s") + " --out " + (dir / "r1") + " --frames --video-fps 5 --jobs 1");
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const test::CommandResult two = test::RunInhand(
      "replay " + (dir / "s") + " --out " + (dir / "r2") + " --frames --video-fps 5 --jobs 2");
  ASSERT_EQ(two.exit_code, 0) << two.output;
  EXPECT_EQ(test::RunInhand("compare " + (dir / "r1/frames") + " " + (dir / "r2/frames") +
                            " --max-channel-delta 0 --max-bad-fraction 0")
                .exit_code,
            0);
  const auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(read(dir / "r1/estimates.csv"), read(dir / "r2/estimates.csv"));
#ifdef INHAND_WITH_GUI
  // The GUI shows the same 3-D view instead of "(no image yet)".
  const test::CommandResult gui = test::RunInhand(
      "gui " + (dir / "s") + " --time 4 --frames 2 --screenshot " + (dir / "gui.png"),
      "env -u DISPLAY");
  ASSERT_EQ(gui.exit_code, 0) << gui.output;
  const Image8 shot = ReadImage(dir / "gui.png");
  long bright = 0;  // the 3-D view's light background fills most of the view panel
  for (int y = 100; y < 600; y += 4)
    for (int x = 400; x < 1200; x += 4)
      bright += shot.pixel(x, y)[0] > 200 && shot.pixel(x, y)[2] > 200;
  EXPECT_GT(bright, 10000) << "no 3-D view in the GUI";
#endif
}

}  // namespace
}  // namespace inhand
