// Round trips: a simulated session written into a ROS 1 bag by Debian's rosbag writer and into
// MCAP and .db3 by the official npm tools (tests/ros/session_to_ros*.{py,mjs}) imports back to
// the same session, and its replay gives the same estimates, byte for byte.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "inhand/sessions/session.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace inhand {
namespace {

// The scripts beside this file, and the official npm tools they run (installed by install-deps).
const std::string tools = test::SourceDir() + "/tests/ros";
bool HaveNodeTools() { return fs::is_directory(tools + "/node/node_modules/@mcap/core"); }

// The bytes of a session's camera images, each frame counted (a file used twice counts twice).
double ImageBytes(const Session& s) {
  double bytes = 0;
  for (const CameraFrame& f : s.camera_frames())
    bytes += static_cast<double>(fs::file_size(s.Resolve(f.image)));
  return bytes;
}

// The size an export of `s` may take: 1.15 x its image bytes + 2 MB per minute.
double McapSizeBound(const Session& s) {
  return 1.15 * ImageBytes(s) + 2e6 * (s.t(s.num_samples() - 1) - s.t(0)) / 60.0;
}

// replay --mcap of the session at `path` (loaded as s) with `sets` into `out`; the file within
// McapSizeBound.
void ExportWithinBound(const std::string& path, const Session& s, const std::string& sets,
                       const std::string& out) {
  ASSERT_EQ(test::RunInhand("replay " + path + " --no-video --mcap --modalities " + sets +
                            " --out " + out)
                .exit_code,
            0);
  const double size = static_cast<double>(fs::file_size(out + "/replay.mcap"));
  EXPECT_LE(size, McapSizeBound(s));
  std::printf("replay.mcap of %.0f s: %.1f MB for %.1f MB of images (bound %.1f MB)\n",
              s.t(s.num_samples() - 1) - s.t(0), size / 1e6, ImageBytes(s) / 1e6,
              McapSizeBound(s) / 1e6);
}

// A CSV file's last line, and a line's comma-separated cells (no quoted commas before the last
// cell used).
std::string LastLine(const std::string& text) {
  return text.substr(text.rfind('\n', text.size() - 2) + 1);
}
std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

int Shell(const std::string& cmd) { return std::system((cmd + " > /dev/null 2>&1").c_str()); }

// The simulated session made representable in a recording: times on whole nanoseconds (ROS
// time's resolution), the initial pose a fixed point of quaternion -> matrix -> quaternion (its
// text then survives any number of writes), models by absolute path.
void WriteRepresentable(const Session& sim, const std::string& out) {
  SessionInfo info = sim.info();
  info.hand_urdf = sim.Resolve(info.hand_urdf);
  info.object = sim.Resolve(info.object);
  for (auto& [name, path] : info.packages) path = sim.Resolve(path);
  Transform T = info.initial_T_PO;
  for (int i = 0; i < 20; ++i) {
    const Quat q(T.linear());
    T = MakeTransform(T.translation(), q);
    if (Quat(T.linear()).coeffs() == q.coeffs()) break;
  }
  info.initial_T_PO = T;
  const auto ns = [](double t) { return static_cast<double>(std::llround(t * 1e9)) / 1e9; };
  SessionWriter w(out, info, sim.joint_names());
  for (int k = 0; k < sim.num_samples(); ++k) w.AddJointSample(ns(sim.t(k)), sim.q(k), sim.tau(k));
  for (std::size_t i = 0; i < sim.camera_frames().size(); ++i)
    w.AddCameraFrame(ns(sim.camera_frames()[i].t), sim.LoadImage(static_cast<int>(i)),
                     sim.camera_frames()[i].T_PC);
  for (const GroundTruthSample& g : sim.groundtruth()) w.AddGroundTruth(ns(g.t), g.T_PO);
  w.Commit();
}

TEST(RoundTrip, SimulatedSessionThroughBagMcapAndDb3) {
  if (!HaveNodeTools())
    GTEST_SKIP()
        << "tests/ros/node/node_modules is absent: run scripts/install-deps.sh (npm ci there)";
  test::TempDir dir;
  ASSERT_EQ(
      test::RunInhand("simulate ketchup-power-grasp --noise paper --seed 3 --out " + (dir / "sim"))
          .exit_code,
      0);
  WriteRepresentable(Session::Load(dir / "sim"), dir / "orig");
  const Session orig = Session::Load(dir / "orig");
  const Transform& T0 = orig.info().initial_T_PO;
  const Quat q0(T0.linear());
  std::string pose, sigma;
  for (double v : {T0.translation().x(), T0.translation().y(), T0.translation().z(), q0.w(), q0.x(),
                   q0.y(), q0.z()})
    pose += (pose.empty() ? "" : ",") + FormatDouble(v);
  for (double v :
       {orig.info().sigma_position, orig.info().sigma_orientation, orig.info().sigma_joint_bias})
    sigma += (sigma.empty() ? "" : ",") + FormatDouble(v);

  ASSERT_EQ(Shell("/usr/bin/python3 " + tools + "/session_to_ros1.py " + (dir / "orig") + " " +
                  (dir / "rec.bag")),
            0);
  ASSERT_EQ(Shell("node " + tools + "/session_to_ros2.mjs " + (dir / "orig") + " " +
                  (dir / "rec.mcap") + " zstd"),
            0);
  ASSERT_EQ(
      Shell("node " + tools + "/session_to_ros2.mjs " + (dir / "orig") + " " + (dir / "rec.db3")),
      0);
  ASSERT_EQ(
      test::RunInhand("replay " + (dir / "orig") + " --no-video --out " + (dir / "replay_orig"))
          .exit_code,
      0);
  const std::string estimates = test::ReadFile(dir / "replay_orig/estimates.csv");
  ASSERT_GT(estimates.size(), 1000u);

  for (const std::string rec : {"rec.bag", "rec.mcap", "rec.db3"}) {
    SCOPED_TRACE(rec);
    const std::string out = dir / ("imported_" + rec);
    const test::CommandResult r = test::RunInhand(
        "import " + (dir / rec) + " --out " + out + " --hand " +
        orig.Resolve(orig.info().hand_urdf) + " --object " + orig.Resolve(orig.info().object) +
        " --time-origin 0 --effort-is external --object-pose /object_pose --initial-pose=" + pose +
        " --initial-sigma " + sigma);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // Joints, camera poses and truth to the last digit; every image byte for byte.
    for (const char* file : {"joints.csv", "camera.csv", "groundtruth.csv"})
      EXPECT_EQ(test::ReadFile(out + "/" + file),
                test::ReadFile(dir / ("orig/" + std::string(file))))
          << file;
    const Session imported = Session::Load(out);
    ASSERT_EQ(imported.camera_frames().size(), orig.camera_frames().size());
    for (std::size_t i = 0; i < orig.camera_frames().size(); ++i)
      ASSERT_EQ(test::ReadFile(imported.Resolve(imported.camera_frames()[i].image)),
                test::ReadFile(orig.Resolve(orig.camera_frames()[i].image)))
          << i;
    EXPECT_EQ(imported.info().initial_T_PO.matrix(), T0.matrix());
    EXPECT_EQ(imported.info().camera->fx, orig.info().camera->fx);
    // And so the same estimates, for all four sets.
    ASSERT_EQ(test::RunInhand("replay " + out + " --no-video --out " + out + "_replay").exit_code,
              0);
    EXPECT_EQ(test::ReadFile(out + "_replay/estimates.csv"), estimates);
  }
}

// replay --mcap: the official MCAP reader (@mcap/core, CRCs checked) reads the export back, with
// every topic, its foxglove schema, the expected message counts (the events: as many as events.csv
// has rows) and the session's time span.
TEST(Export, ReplayMcapReadsBackWithTheOfficialReader) {
  if (!HaveNodeTools())
    GTEST_SKIP()
        << "tests/ros/node/node_modules is absent: run scripts/install-deps.sh (npm ci there)";
  test::TempDir dir;
  ASSERT_EQ(
      test::RunInhand("simulate ketchup-power-grasp --noise paper --seed 2 --out " + (dir / "sim"))
          .exit_code,
      0);
  const Session s = Session::Load(dir / "sim");
  ASSERT_NO_FATAL_FAILURE(ExportWithinBound(dir / "sim", s, "j,jta", dir / "r"));
  const std::string json_path = dir / "check.json";
  ASSERT_EQ(std::system(
                ("node " + tools + "/check_mcap.mjs " + (dir / "r/replay.mcap") + " > " + json_path)
                    .c_str()),
            0);
  const nlohmann::json j = nlohmann::json::parse(test::ReadFile(json_path));
  const long n = s.num_samples(), frames = static_cast<long>(s.camera_frames().size());
  const auto count = [&](const std::string& topic) {
    return j.at("topics").at(topic).at("count").get<long>();
  };
  EXPECT_EQ(count("/inhand/pose/j"), n);
  EXPECT_EQ(count("/inhand/pose/jta"), n);
  EXPECT_EQ(count("/inhand/errors"), n);
  EXPECT_EQ(count("/tf"),
            3 * n + frames);  // two sets and the truth per sample, the camera per frame
  EXPECT_EQ(count("/camera/image"), frames);
  EXPECT_EQ(count("/camera/annotations"), frames);
  EXPECT_EQ(count("/inhand/contacts"), frames);
  EXPECT_EQ(j.at("topics").at("/inhand/pose/j").at("schema"), "foxglove_msgs/msg/PoseInFrame");
  EXPECT_EQ(j.at("topics").at("/camera/image").at("schema"), "foxglove_msgs/msg/CompressedImage");
  EXPECT_EQ(j.at("topics").at("/tf").at("schema"), "foxglove_msgs/msg/FrameTransform");
  EXPECT_EQ(j.at("topics").at("/inhand/contacts").at("schema"), "foxglove_msgs/msg/SceneUpdate");
  EXPECT_EQ(j.at("topics").at("/camera/annotations").at("schema"),
            "foxglove_msgs/msg/ImageAnnotations");
  EXPECT_EQ(j.at("topics").at("/inhand/errors").at("schema"), "inhand_msgs/msg/State");
  EXPECT_EQ(j.at("topics").at("/inhand/log").at("schema"), "foxglove_msgs/msg/Log");
  EXPECT_EQ(j.at("topics").at("/inhand/events").at("schema"), "inhand_msgs/msg/Event");
  // Every channel binary: ros2msg schemas, CDR messages, none JSON.
  for (const auto& [topic, entry] : j.at("topics").items()) {
    EXPECT_EQ(entry.at("message_encoding"), "cdr") << topic;
    EXPECT_EQ(entry.at("schema_encoding"), "ros2msg") << topic;
  }
  // Every CDR message decoded by @foxglove/rosmsg2-serialization; the first image is the
  // session's PNG byte for byte in length and signature, stamped at its capture time; the first
  // pose is estimates.csv's first row.
  EXPECT_EQ(j.at("cdr_errors"), 0);
  const nlohmann::json& image = j.at("first").at("/camera/image");
  const std::string png = test::ReadFile(s.Resolve(s.camera_frames()[0].image));
  EXPECT_EQ(image.at("data").at("length").get<std::size_t>(), png.size());
  EXPECT_EQ(image.at("data").at("head"), nlohmann::json::array({137, 80, 78, 71, 13, 10, 26, 10}));
  EXPECT_EQ(image.at("format"), "png");
  EXPECT_EQ(image.at("frame_id"), "camera");
  const long long frame_ns = std::llround(s.camera_frames()[0].t * 1e9);
  EXPECT_EQ(image.at("timestamp").at("sec").get<long long>(), frame_ns / 1000000000);
  EXPECT_EQ(image.at("timestamp").at("nanosec").get<long long>(), frame_ns % 1000000000);
  std::istringstream estimates(test::ReadFile(dir / "r/estimates.csv"));
  std::string header, row;
  std::getline(estimates, header);
  std::getline(estimates, row);  // t, set (j first), px, py, pz, ...
  std::vector<double> values;
  for (const std::string& cell : Cells(row))
    values.push_back(cell == "j" ? 0.0 : std::strtod(cell.c_str(), nullptr));
  ASSERT_GE(values.size(), 5u);
  const nlohmann::json& pose = j.at("first").at("/inhand/pose/j");
  EXPECT_EQ(pose.at("frame_id"), "palm");
  EXPECT_NEAR(pose.at("pose").at("position").at("x").get<double>(), values[2], 1e-15);
  EXPECT_NEAR(pose.at("pose").at("position").at("y").get<double>(), values[3], 1e-15);
  EXPECT_NEAR(pose.at("pose").at("position").at("z").get<double>(), values[4], 1e-15);
  EXPECT_EQ(j.at("start_ns"), std::to_string(std::llround(s.t(0) * 1e9)));
  EXPECT_EQ(j.at("end_ns"), std::to_string(std::llround(s.t(static_cast<int>(n) - 1) * 1e9)));
  EXPECT_EQ(j.at("json_errors"), 0);
  // The events, one log message per row of events.csv.
  const std::string events_csv = test::ReadFile(dir / "r/events.csv");
  const long events = std::count(events_csv.begin(), events_csv.end(), '\n') - 1;
  EXPECT_GT(events, 4);  // the fingers close on the bottle
  EXPECT_EQ(count("/inhand/events"), events);
  EXPECT_EQ(count("/inhand/log"), events);
  // The last event is events.csv's last row; the log line says the same.
  const std::string last_row = LastLine(events_csv);  // t,set,kind,subject,value,...
  const nlohmann::json& event = j.at("last").at("/inhand/events");
  const std::string event_prefix = event.at("set").get<std::string>() + "," +
                                   event.at("kind").get<std::string>() + "," +
                                   event.at("subject").get<std::string>() + ",";
  EXPECT_NE(last_row.find("," + event_prefix), std::string::npos) << last_row;
  EXPECT_NE(last_row.find(event.at("message").get<std::string>()), std::string::npos);
  EXPECT_EQ(j.at("last").at("/inhand/log").at("name"),
            "inhand/" + event.at("set").get<std::string>());
  // The last state per set is estimates.csv's last row of that set (jta, last in the file).
  const std::vector<std::string> cells_jta =
      Cells(LastLine(test::ReadFile(dir / "r/estimates.csv")));
  ASSERT_GT(cells_jta.size(), 21u);
  ASSERT_EQ(cells_jta[1], "jta");
  const nlohmann::json& state = j.at("last").at("/inhand/errors").at("sets");
  ASSERT_EQ(state.size(), 2u);
  EXPECT_EQ(state[0].at("set"), "j");
  const nlohmann::json& jta = state[1];
  EXPECT_EQ(jta.at("set"), "jta");
  EXPECT_NEAR(jta.at("sigma_position_mm").at("0").get<double>(), std::stod(cells_jta[9]) * 1000,
              1e-9);
  EXPECT_NEAR(jta.at("position_error_mm").get<double>(), std::stod(cells_jta[15]), 1e-9);
  EXPECT_NEAR(jta.at("penetration_mm").get<double>(), std::stod(cells_jta[17]), 1e-9);
  EXPECT_EQ(jta.at("health"), cells_jta[19]);
  EXPECT_EQ(jta.at("health_cause"), cells_jta[20]);
  // The last frame's overlays: a circle and a name per set, contact spheres per set.
  const nlohmann::json& annotations = j.at("last").at("/camera/annotations");
  ASSERT_EQ(annotations.at("texts").size(), 2u);
  EXPECT_EQ(annotations.at("texts")[1].at("text"), "jta");
  EXPECT_EQ(annotations.at("circles").size(), 2u);
  const nlohmann::json& entities = j.at("last").at("/inhand/contacts").at("entities");
  ASSERT_EQ(entities.size(), 2u);
  EXPECT_EQ(entities[1].at("id"), "contacts_jta");
  EXPECT_EQ(entities[1].at("frame_id"), "palm");
  EXPECT_GT(entities[1].at("spheres").size(), 0u);  // the fingers hold the bottle
  EXPECT_EQ(j.at("statistics").at("messages"), 6 * n + 4 * frames + 2 * events);
  EXPECT_TRUE(j.at("footer").get<bool>());
  // Read again as a viewer seeks: through the summary, the chunk and message indexes (every CRC
  // checked), zstd chunks; the same messages per topic, and one second read alone.
  const std::string indexed_path = dir / "indexed.json";
  ASSERT_EQ(std::system(("node " + tools + "/check_mcap_indexed.mjs " + (dir / "r/replay.mcap") +
                         " 7 > " + indexed_path)
                            .c_str()),
            0);
  const nlohmann::json x = nlohmann::json::parse(test::ReadFile(indexed_path));
  EXPECT_GT(x.at("chunks").get<int>(), 1);
  EXPECT_EQ(x.at("compressions"), nlohmann::json::array({"zstd"}));
  for (const auto& [topic, entry] : j.at("topics").items())
    EXPECT_EQ(x.at("topics").at(topic), entry.at("count")) << topic;
  EXPECT_EQ(x.at("messages"), j.at("statistics").at("messages"));
  EXPECT_EQ(x.at("statistics_messages"), x.at("messages"));
  // 500 Hz: one second holds at least the 500 samples' poses of each set.
  EXPECT_GT(x.at("window").at("messages").get<long>(), 2 * 500);
  std::printf("one second read through the index: %ld messages in %.1f ms\n",
              x.at("window").at("messages").get<long>(), x.at("window").at("ms").get<double>());
}

// A long recording (a simulated session played forward and backward for two minutes by
// scripts/long_session.py): the export stays within its size bound, and seconds drawn across it
// read through the index hold every sample of the second.
TEST(Export, LongRecordingStaysSmallAndSeeksThroughItsIndex) {
  if (!HaveNodeTools())
    GTEST_SKIP()
        << "tests/ros/node/node_modules is absent: run scripts/install-deps.sh (npm ci there)";
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("simulate brush-rotation --noise paper --seed 3 --out " + (dir / "sim"))
                .exit_code,
            0);
  ASSERT_EQ(Shell("python3 " + test::SourceDir() + "/scripts/long_session.py " + (dir / "sim") +
                  " " + (dir / "long") + " --minutes 2"),
            0);
  const Session s = Session::Load(dir / "long");
  EXPECT_NEAR(s.t(s.num_samples() - 1) - s.t(0), 120.0, 1e-6);
  ASSERT_NO_FATAL_FAILURE(ExportWithinBound(dir / "long", s, "jt", dir / "r"));
  const std::string indexed_path = dir / "indexed.json";
  ASSERT_EQ(std::system(("node " + tools + "/check_mcap_indexed.mjs " + (dir / "r/replay.mcap") +
                         " 11 5 > " + indexed_path)
                            .c_str()),
            0);
  const nlohmann::json x = nlohmann::json::parse(test::ReadFile(indexed_path));
  EXPECT_EQ(x.at("topics").at("/inhand/pose/jt").get<long>(), s.num_samples());
  EXPECT_EQ(x.at("topics").at("/camera/image").get<long>(),
            static_cast<long>(s.camera_frames().size()));
  ASSERT_EQ(x.at("windows").size(), 5u);
  double earliest = 1e30, latest = 0;
  for (const nlohmann::json& w : x.at("windows")) {
    const double from = std::stod(w.at("start_ns").get<std::string>()) / 1e9;
    earliest = std::min(earliest, from);
    latest = std::max(latest, from);
    // jt's pose, its errors and two transforms per 2 ms sample, an image per 0.1 s.
    EXPECT_GE(w.at("messages").get<long>(), 4 * 499 + 9) << from;
    std::printf("one second from %.2f s read through the index: %ld messages in %.1f ms\n", from,
                w.at("messages").get<long>(), w.at("ms").get<double>());
  }
  EXPECT_GT(latest - earliest, 30.0);  // the windows spread over the recording
}

}  // namespace
}  // namespace inhand
