// What fuzzing and a hostile user found (issue 17), each case made here, small, by the test.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A noise-free ketchup session for this binary's tests (simulated once).
const std::string& Session() {
  static const std::string path = fs::temp_directory_path().string() +
                                  "/inhand-robustness-session-" + std::to_string(::getpid());
  static const bool made = [] {
    const test::CommandResult r =
        test::RunInhand("simulate ketchup-power-grasp --noise none --seed 3 --out " + path);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(path, ec);
    });
    return true;
  }();
  (void)made;
  return path;
}

// --- 1. --out never destroys what inhand did not write, the input, or the current folder.
TEST(Robustness, OutputFoldersReplaceOnlyWhatInhandWrote) {
  test::TempDir dir;
  fs::copy(Session(), dir / "session", fs::copy_options::recursive);
  const std::string before = Read(dir / "session/joints.csv");
  // The input itself, and a folder that contains it.
  test::CommandResult r = test::RunInhand("replay " + (dir / "session") +
                                          " --no-video --modalities j --out " + (dir / "session"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is the input"), std::string::npos) << r.output;
  r = test::RunInhand("replay " + (dir / "session") + " --no-video --modalities j --out " +
                      dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(Read(dir / "session/joints.csv"), before);
  // The current folder ("." and "./"), from inside it.
  fs::create_directories(dir / "work");
  dir.Write("work/notes.txt", "mine");
  for (const char* out : {".", "./", "../work"}) {
    r = test::RunInhand("replay " + (dir / "session") + " --no-video --modalities j --out " + out,
                        "cd " + (dir / "work") + " &&");
    EXPECT_EQ(r.exit_code, 2) << out << ": " << r.output;
    EXPECT_NE(r.output.find("current folder"), std::string::npos) << r.output;
  }
  EXPECT_EQ(Read(dir / "work/notes.txt"), "mine");
  // A folder of someone else's files: refused; an empty one: used; inhand's own: replaced.
  dir.Write("theirs/thesis.tex", "years of work");
  r = test::RunInhand("replay " + (dir / "session") + " --no-video --modalities j --out " +
                      (dir / "theirs"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("not written by inhand"), std::string::npos) << r.output;
  EXPECT_EQ(Read(dir / "theirs/thesis.tex"), "years of work");
  fs::create_directories(dir / "empty");
  EXPECT_EQ(test::RunInhand("replay " + (dir / "session") + " --no-video --modalities j --out " +
                            (dir / "empty"))
                .exit_code,
            0);
  EXPECT_TRUE(fs::exists(dir / "empty/.inhand-output"));
  EXPECT_EQ(test::RunInhand("replay " + (dir / "session") + " --no-video --modalities j --out " +
                            (dir / "empty"))
                .exit_code,
            0);
  // simulate --overwrite and match follow the same rule.
  r = test::RunInhand("simulate ketchup-power-grasp --no-images --overwrite --out " +
                      (dir / "theirs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(Read(dir / "theirs/thesis.tex"), "years of work");
  r = test::RunInhand("match " + (dir / "session") + " --frame 0 --out " + (dir / "theirs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = test::RunInhand("evaluate --scenarios pen-fingertip --seeds 1 --plan --out " +
                      (dir / "theirs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(Read(dir / "theirs/thesis.tex"), "years of work");
}

// A crash leaves `.NAME.tmp-PID`; the next run removes it when that process is gone.
TEST(Robustness, StaleStagingFoldersAreRemoved) {
  test::TempDir dir;
  fs::create_directories(dir / ".out.tmp-999999999");
  dir.Write(".out.tmp-999999999/estimates.csv", "half");
  fs::create_directories(dir / (".out.tmp-" + std::to_string(::getpid())));  // a live process's
  ASSERT_EQ(
      test::RunInhand("replay " + Session() + " --no-video --modalities j --out " + (dir / "out"))
          .exit_code,
      0);
  EXPECT_FALSE(fs::exists(dir / ".out.tmp-999999999"));
  EXPECT_TRUE(fs::exists(dir / (".out.tmp-" + std::to_string(::getpid()))));
}

// A copy of the session whose joints.csv has `value` in column `column` of sample `sample`.
constexpr int kEverySample = -2;  // WithJoint's `sample`: every one
std::string WithJoint(const test::TempDir& dir, const std::string& name, int sample, int column,
                      const std::string& value) {
  fs::copy(Session(), dir / name, fs::copy_options::recursive);
  std::stringstream in(Read(dir / (name + "/joints.csv")));
  std::string out, line;
  for (int k = -1; std::getline(in, line); ++k) {
    if (k == sample || (sample == kEverySample && k >= 0)) {
      std::size_t start = 0;
      for (int c = 0; c < column; ++c) start = line.find(',', start) + 1;
      const std::size_t end = line.find(',', start);
      line = line.substr(0, start) + value + (end == std::string::npos ? "" : line.substr(end));
    }
    out += line + "\n";
  }
  std::ofstream(dir / (name + "/joints.csv")) << out;
  return dir / name;
}

Json Summary(const std::string& replay) { return Json::parse(Read(replay + "/summary.json")); }

// --- 2. One bad sample does not poison the rest: dropped, reported with its line, estimates
// finite, and the result is the clean run's but for that sample.
TEST(Robustness, AnAbsurdJointSampleIsDroppedAndReported) {
  test::TempDir dir;
  ASSERT_EQ(test::RunInhand("replay " + Session() + " --no-video --modalities j,jt --out " +
                            (dir / "clean"))
                .exit_code,
            0);
  const Json clean = Summary(dir / "clean");
  for (const std::string value : {"1e300", "1000", "-nan"}) {
    const std::string session = WithJoint(dir, "s" + value, 1500, 3, value);
    const test::CommandResult r = test::RunInhand(
        "replay " + session + " --no-video --modalities j,jt --out " + (dir / ("r" + value)));
    if (value == "-nan") {  // not a number in the file: the reader rejects it with the line
      EXPECT_EQ(r.exit_code, 2) << r.output;
      EXPECT_NE(r.output.find("joints.csv:1502"), std::string::npos) << r.output;
      continue;
    }
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("warning: " + session + "/joints.csv:1502: q:"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("sample dropped"), std::string::npos) << r.output;
    const Json s = Summary(dir / ("r" + value));
    EXPECT_EQ(s.at("joint_samples_rejected"), 1);
    for (const char* set : {"j", "jt"}) {
      const double e = s.at("modalities").at(set).at("terminal_position_error_mm").get<double>();
      EXPECT_TRUE(std::isfinite(e));
      EXPECT_EQ(s.at("modalities").at(set).at("joint_samples_dropped"), 1) << set;
      EXPECT_NEAR(e, clean.at("modalities").at(set).at("terminal_position_error_mm").get<double>(),
                  1.0)
          << set << " " << value;
    }
    EXPECT_EQ(Read(dir / ("r" + value) + "/estimates.csv").find("nan"), std::string::npos);
    EXPECT_EQ(Read(dir / ("r" + value) + "/estimates.csv").find("inf"), std::string::npos);
  }
}

// A session none of whose joint samples can be fused is refused, by name, with no output: not
// replayed into an estimate that is the start's and nothing else.
TEST(Robustness, ASessionWithoutAFusableJointSampleIsRefused) {
  test::TempDir dir;
  const std::string session = WithJoint(dir, "s", kEverySample, 3, "1000");
  const test::CommandResult r =
      test::RunInhand("replay " + session + " --no-video --modalities j --out " + (dir / "r"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(session + "/joints.csv: none of its "), std::string::npos) << r.output;
  EXPECT_NE(
      r.output.find("joint samples can be fused; the first: " + session + "/joints.csv:2: q:"),
      std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "r"));
}

// Encoders overshoot their URDF's limits (19 of 20 recorded Allegro grasps pass joint_12.0's
// upper limit): such samples are reported once per joint with the worst value and the limit, and
// kept or clamped as joints.clamp_to_limits says.
TEST(Robustness, JointSamplesBeyondTheirLimitsAreReportedOncePerJoint) {
  test::TempDir dir;
  fs::copy(Session(), dir / "s", fs::copy_options::recursive);
  std::stringstream in(Read(dir / "s/joints.csv"));
  std::string out, line;
  // Column 3 is q:index_flex2 (limits [0, 1.75]), column 1 q:index_abduction ([-0.35, 0.35]).
  auto set = [](std::string& row, int column, const std::string& value) {
    std::size_t start = 0;
    for (int c = 0; c < column; ++c) start = row.find(',', start) + 1;
    const std::size_t end = row.find(',', start);
    row = row.substr(0, start) + value + (end == std::string::npos ? "" : row.substr(end));
  };
  for (int k = -1; std::getline(in, line); ++k) {
    if (k >= 100) set(line, 3, k == 105 ? "2.05" : "1.95");  // the index finger curled further
    if (k == 200) set(line, 1, "-0.5");  // by 0.15 rad, beyond the session's 5° bias σ
    out += line + "\n";
  }
  std::ofstream(dir / "s/joints.csv") << out;
  const test::CommandResult kept = test::RunInhand(
      "replay " + (dir / "s") + " --no-video --modalities j --out " + (dir / "kept"));
  ASSERT_EQ(kept.exit_code, 0) << kept.output;
  const std::string flex2 = "q:index_flex2 beyond its upper limit 1.75 in ";
  EXPECT_NE(kept.output.find(flex2), std::string::npos) << kept.output;
  EXPECT_NE(kept.output.find("(worst 2.05, by 0.3)"), std::string::npos) << kept.output;
  EXPECT_EQ(kept.output.find(flex2), kept.output.rfind(flex2)) << "one line per joint";
  EXPECT_NE(kept.output.find("q:index_abduction beyond its lower limit -0.35 in 1 of "),
            std::string::npos)
      << kept.output;
  EXPECT_NE(kept.output.find("kept as measured"), std::string::npos) << kept.output;
  // index_flex2 rests on its lower limit early on: the encoder reads up to 0.038 rad below it,
  // within the session's joint-bias σ, and no warning says so.
  EXPECT_EQ(kept.output.find("q:index_flex2 beyond its lower limit"), std::string::npos)
      << kept.output;

  dir.Write("clamp.json", R"({"joints": {"clamp_to_limits": true}})");
  const test::CommandResult clamped =
      test::RunInhand("replay " + (dir / "s") + " --no-video --modalities j --params " +
                      (dir / "clamp.json") + " --out " + (dir / "clamped"));
  ASSERT_EQ(clamped.exit_code, 0) << clamped.output;
  EXPECT_NE(clamped.output.find("clamped to the limit"), std::string::npos) << clamped.output;
  EXPECT_NE(Read(dir / "clamped/params.json").find("\"clamp_to_limits\": true"), std::string::npos);
  EXPECT_TRUE(Read(dir / "kept/estimates.csv") != Read(dir / "clamped/estimates.csv"))
      << "clamping changed nothing";
  dir.Write("bad.json", R"({"joints": {"clamp_to_limits": 1}})");
  const test::CommandResult bad =
      test::RunInhand("replay " + (dir / "s") + " --no-video --params " + (dir / "bad.json") +
                      " --out " + (dir / "bad"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("'joints.clamp_to_limits' must be true or false"), std::string::npos)
      << bad.output;
}

// Parameters at the edge of what they were documented to accept broke the covariance; the
// ranges now keep the arithmetic finite, and what is outside them is refused by name.
TEST(Robustness, ParametersThatBreakTheArithmeticAreRefused) {
  test::TempDir dir;
  for (const auto& [json, field] : std::vector<std::pair<std::string, std::string>>{
           {R"({"contact_sigma": 1e-300, "contact_iterations": 20})", "contact_sigma"},
           {R"({"pixel_sigma": 1e-300})", "pixel_sigma"},
           {R"({"contact_iterations": 4294967297})", "contact_iterations"},
           {R"({"features": {"max_corners": 4294967336}})", "max_corners"}}) {
    dir.Write("p.json", json);
    const test::CommandResult r = test::RunInhand("replay " + Session() + " --no-video --params " +
                                                  (dir / "p.json") + " --out " + (dir / "out"));
    EXPECT_EQ(r.exit_code, 2) << json << ": " << r.output;
    EXPECT_NE(r.output.find(field), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  // The smallest accepted values run to a finite end with the most iterations.
  dir.Write("edge.json",
            R"({"contact_sigma": 1e-5, "contact_iterations": 20, "pixel_sigma": 0.01})");
  const test::CommandResult r =
      test::RunInhand("replay " + Session() + " --no-video --modalities j,jt,jta --params " +
                      (dir / "edge.json") + " --out " + (dir / "edge"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json edge = Summary(dir / "edge");
  for (const auto& [set, m] : edge.at("modalities").items()) {
    EXPECT_TRUE(std::isfinite(m.at("terminal_position_error_mm").get<double>())) << set;
    EXPECT_TRUE(std::isfinite(m.at("nees_mean").get<double>())) << set;
    EXPECT_GE(m.at("nees_mean").get<double>(), 0.0) << set;
  }
  // A session's initial sigma of 1e300.
  fs::copy(Session(), dir / "wide", fs::copy_options::recursive);
  std::string text = Read(dir / "wide/session.json");
  const std::size_t at = text.find("\"sigma_position\": ") + 18;
  text.replace(at, text.find_first_of(",\n}", at) - at, "1e300");
  std::ofstream(dir / "wide/session.json") << text;
  const test::CommandResult wide =
      test::RunInhand("replay " + (dir / "wide") + " --no-video --out " + (dir / "w"));
  EXPECT_EQ(wide.exit_code, 2) << wide.output;
  EXPECT_NE(wide.output.find("sigma_position"), std::string::npos) << wide.output;
}

// --- 3. Crashes on reachable input.
TEST(Robustness, DeepJsonAndLongUrdfChainsAreErrorsNotCrashes) {
  test::TempDir dir;
  fs::copy(Session(), dir / "deep", fs::copy_options::recursive);
  std::string text = Read(dir / "deep/session.json");
  const std::size_t at = text.find("\"version\": ") + 11;
  text.replace(at, 1, std::string(100000, '[') + "1" + std::string(100000, ']'));
  std::ofstream(dir / "deep/session.json") << text;
  test::CommandResult r =
      test::RunInhand("replay " + (dir / "deep") + " --no-video --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output.substr(0, 300);
  EXPECT_NE(r.output.find("nested deeper than 64"), std::string::npos) << r.output.substr(0, 300);
  dir.Write(
      "o/object.json",
      R"({"format": "inhand-object", "version": 1, "name": "b", "visual": [], "collision": [{"box": [0.05, 0.02, 0.1]}], "mass": )" +
          std::string(100000, '[') + "0.1" + std::string(100000, ']') + "}");
  r = test::RunInhand("model " + (dir / "o/object.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output.substr(0, 300);
  EXPECT_NE(r.output.find("nested deeper than 64"), std::string::npos) << r.output.substr(0, 300);
  dir.Write("deep.json", std::string(70000, '[') + std::string(70000, ']'));
  r = test::RunInhand("replay " + Session() + " --no-video --params " + (dir / "deep.json") +
                      " --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output.substr(0, 300);
  // A URDF chain of 100,000 links: refused at once, no stack overflow.
  std::string urdf = "<robot name='chain'>\n<link name='l0'/>\n";
  for (int i = 1; i <= 100000; ++i)
    urdf += "<link name='l" + std::to_string(i) + "'/><joint name='j" + std::to_string(i) +
            "' type='fixed'><parent link='l" + std::to_string(i - 1) + "'/><child link='l" +
            std::to_string(i) + "'/></joint>\n";
  dir.Write("chain.urdf", urdf + "</robot>\n");
  r = test::RunInhand("model " + (dir / "chain.urdf"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("more than 1000 links"), std::string::npos) << r.output;
  // 900 links in a chain load (the traversal is iterative).
  urdf = "<robot name='chain'>\n<link name='l0'/>\n";
  for (int i = 1; i < 900; ++i)
    urdf += "<link name='l" + std::to_string(i) + "'/><joint name='j" + std::to_string(i) +
            "' type='fixed'><parent link='l" + std::to_string(i - 1) + "'/><child link='l" +
            std::to_string(i) + "'/></joint>\n";
  dir.Write("ok.urdf", urdf + "</robot>\n");
  r = test::RunInhand("model " + (dir / "ok.urdf") + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output.substr(0, 300);
}

TEST(Robustness, TinyImagesGiveNoTagsNotACrash) {
  test::TempDir dir;
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {4, 4}, {100, 1}}) {
    const std::string file = dir / (std::to_string(w) + "x" + std::to_string(h) + ".png");
    ASSERT_EQ(std::system(("convert -size " + std::to_string(w) + "x" + std::to_string(h) +
                           " xc:gray " + file)
                              .c_str()),
              0);
    const test::CommandResult r = test::RunInhand("tags " + file + " --json");
    EXPECT_EQ(r.exit_code, 0) << file << ": " << r.output;
  }
}

// --- 4. Validation gaps.
TEST(Robustness, BadGeometryAndDuplicatesAreRefusedByName) {
  test::TempDir dir;
  const auto urdf = [&](const std::string& geometry, const std::string& extra = "") {
    dir.Write("g.urdf",
              "<robot name='g'>\n<link name='base'/>\n<link name='a'><collision><geometry>" +
                  geometry +
                  "</geometry></collision></link>\n<joint name='j' type='revolute'><parent "
                  "link='base'/><child link='a'/>"
                  "<limit lower='0' upper='1' effort='1' velocity='1'/></joint>\n" +
                  extra + "</robot>\n");
    return test::RunInhand("model " + (dir / "g.urdf"));
  };
  for (const auto& [geometry, message] : std::vector<std::pair<std::string, std::string>>{
           {"<sphere radius='-0.01'/>", "sphere radius"},
           {"<cylinder radius='0.01' length='-0.022'/>", "cylinder length"},
           {"<box size='0 0 0'/>", "box size"}}) {
    const test::CommandResult r = urdf(geometry);
    EXPECT_EQ(r.exit_code, 2) << geometry << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  }
  const test::CommandResult two = urdf(
      "<sphere radius='0.01'/>",
      "<link name='c'/><joint name='k' type='fixed'><parent link='c'/><child link='a'/></joint>\n");
  EXPECT_EQ(two.exit_code, 2) << two.output;
  EXPECT_NE(two.output.find("second joint"), std::string::npos) << two.output;
  // An object box with a negative size, a tag of an unknown family: named in object.json.
  dir.Write(
      "o/object.json",
      R"({"format": "inhand-object", "version": 1, "name": "b", "visual": [], "collision": [{"box": [0.05, -0.02, 0.1]}], "mass": 0.1})");
  test::CommandResult r = test::RunInhand("model " + (dir / "o/object.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("object.json: field 'collision[0].box'"), std::string::npos) << r.output;
  dir.Write(
      "t/object.json",
      R"({"format": "inhand-object", "version": 1, "name": "b", "visual": [], "collision": [{"box": [0.05, 0.02, 0.1]}], "mass": 0.1,
    "tags": [{"family": "tag99h9", "id": 0, "size": 0.02, "pose": {"xyz": [0, 0, 0.05]}}]})");
  r = test::RunInhand("model " + (dir / "t/object.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("object.json: field 'tags[0].family'"), std::string::npos) << r.output;
  // A set named twice.
  r = test::RunInhand("replay " + Session() + " --modalities j,j --no-video --out " +
                      (dir / "out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("'j' is listed twice"), std::string::npos) << r.output;
  // A session version of 4294967297 does not read as 1.
  fs::copy(Session(), dir / "v", fs::copy_options::recursive);
  std::string text = Read(dir / "v/session.json");
  const std::size_t at = text.find("\"version\": ") + 11;
  text.replace(at, 1, "4294967297");
  std::ofstream(dir / "v/session.json") << text;
  r = test::RunInhand("replay " + (dir / "v") + " --no-video --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("version"), std::string::npos) << r.output;
  // A camera width of 4294967936 does not read as 640.
  fs::copy(Session(), dir / "w", fs::copy_options::recursive);
  text = Read(dir / "w/session.json");
  const std::size_t width = text.find("\"width\": 640");
  ASSERT_NE(width, std::string::npos);
  text.replace(width, 13, "\"width\": 4294967936");
  std::ofstream(dir / "w/session.json") << text;
  r = test::RunInhand("replay " + (dir / "w") + " --no-video --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("width"), std::string::npos) << r.output;
}

// Frames stamped before the first joint sample are not fused at it; ground truth that does not
// cover the joint samples gives no errors where it is missing. Both are said, with the times.
TEST(Robustness, TimeMisalignmentIsReported) {
  test::TempDir dir;
  fs::copy(Session(), dir / "s", fs::copy_options::recursive);
  // Drop the first 0.5 s of joint samples (250 rows) and the last 0.5 s of ground truth.
  const auto keep = [&](const std::string& file, int skip_front, int skip_back) {
    std::stringstream in(Read(dir / file));
    std::vector<std::string> lines;
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    std::string out = lines[0] + "\n";
    for (std::size_t i = 1 + static_cast<std::size_t>(skip_front);
         i + static_cast<std::size_t>(skip_back) < lines.size(); ++i)
      out += lines[i] + "\n";
    std::ofstream(dir / file) << out;
  };
  keep("s/joints.csv", 250, 0);
  keep("s/groundtruth.csv", 0, 250);
  const test::CommandResult r = test::RunInhand(
      "replay " + (dir / "s") + " --modalities j,jta --no-video --out " + (dir / "r"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frames captured before the first joint sample"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("groundtruth.csv: covers"), std::string::npos) << r.output;
  const Json s = Summary(dir / "r");
  EXPECT_GE(s.at("frames_before_first_sample").get<int>(), 4);
  EXPECT_GE(s.at("samples_without_truth").get<int>(), 200);
  EXPECT_TRUE(
      std::isfinite(s.at("modalities").at("j").at("terminal_position_error_mm").get<double>()));
}

// Clear messages that name the file.
TEST(Robustness, ImageErrorsNameTheFile) {
  test::TempDir dir;
  fs::copy(Session(), dir / "s", fs::copy_options::recursive);
  const std::string frame = dir / "s/images/frame_000000.png";
  std::string png = Read(frame);
  std::ofstream(frame, std::ios::binary) << png.substr(0, png.size() / 2);  // truncated
  test::CommandResult r = test::RunInhand("replay " + (dir / "s") +
                                          " --no-video --modalities jta --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output.find("libpng"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.rfind("inhand: error: " + frame, 0), 0u) << r.output;
  // A header claiming 60000 x 60000.
  png[16] = 0, png[17] = 0, png[18] = static_cast<char>(0xea), png[19] = 0x60;
  png[20] = 0, png[21] = 0, png[22] = static_cast<char>(0xea), png[23] = 0x60;
  std::ofstream(frame, std::ios::binary) << png;
  r = test::RunInhand("replay " + (dir / "s") + " --no-video --modalities jta --out " +
                      (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(frame + ": the PNG header says 60000x60000"), std::string::npos)
      << r.output;
  // compare names both images and their sizes.
  ASSERT_EQ(std::system(("convert -size 4x3 xc:gray " + (dir / "a.png") +
                         " && convert -size 5x3 xc:gray " + (dir / "b.png"))
                            .c_str()),
            0);
  r = test::RunInhand("compare " + (dir / "a.png") + " " + (dir / "b.png"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(dir / "a.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(dir / "b.png"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace inhand
