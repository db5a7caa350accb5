// A deterministic mutation fuzzer for every parser of user input: session.json, joints.csv,
// camera.csv, groundtruth.csv, the parameter file, object.json, URDF and ROS 2 recordings (MCAP,
// CDR, .db3). Each starts from a
// valid file and mutates it (bytes: flips, insertions, deletions, duplications, truncation;
// tokens: numbers replaced by extremes, strings emptied, values nested deeply, lines swapped,
// duplicated or dropped). Every input must either load, and then hold only finite, valid
// values, or be refused with an InputError; anything else (another exception, a crash, a hang,
// a non-finite value accepted) is a finding. INHAND_FUZZ_RUNS inputs per parser (1,000 in
// make test; make fuzz runs 20,000), seeded: a finding reproduces from its run number.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/ros/recording.hpp"
#include "inhand/sessions/session.hpp"
#include "inhand/tracker/tracker_params.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;

int Runs() {
  const char* env = std::getenv("INHAND_FUZZ_RUNS");
  return env ? std::max(1, std::atoi(env)) : 1000;
}

class Mutator {
 public:
  explicit Mutator(unsigned seed) : rng_(seed) {}
  std::string operator()(std::string s) {
    const int n = 1 + Pick(3);
    for (int i = 0; i < n; ++i) s = Once(std::move(s));
    return s;
  }

 private:
  int Pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  std::size_t At(const std::string& s) {
    return s.empty() ? 0 : std::uniform_int_distribution<std::size_t>(0, s.size() - 1)(rng_);
  }
  std::string Once(std::string s) {
    static const std::vector<std::string> kNumbers = {"1e308",
                                                      "-1e308",
                                                      "nan",
                                                      "inf",
                                                      "-inf",
                                                      "-0",
                                                      "4294967297",
                                                      "-2147483649",
                                                      "1e-320",
                                                      "0",
                                                      "99999999999999999999",
                                                      "-1",
                                                      "0.5e",
                                                      "1e300",
                                                      "-1e-300",
                                                      "18446744073709551616",
                                                      "2147483648"};
    switch (Pick(12)) {
      case 0:
        if (!s.empty()) s[At(s)] ^= static_cast<char>(1 << Pick(8));
        return s;
      case 1:
        s.insert(At(s), 1, static_cast<char>(Pick(256)));
        return s;
      case 2: {
        const std::size_t a = At(s);
        return s.erase(a, static_cast<std::size_t>(Pick(16)));
      }
      case 3: {
        const std::size_t a = At(s);
        return s.insert(a, s.substr(a, static_cast<std::size_t>(Pick(64))));
      }
      case 4:
        return s.substr(0, At(s));
      case 5:
      case 6:
      case 7: {  // a number token replaced by an extreme
        std::vector<std::pair<std::size_t, std::size_t>> numbers;
        for (std::size_t i = 0; i < s.size();) {
          if (std::isdigit(static_cast<unsigned char>(s[i])) ||
              (s[i] == '-' && i + 1 < s.size() &&
               std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
            std::size_t j = i + 1;
            while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' ||
                                    s[j] == 'e' || s[j] == 'E' || s[j] == '-' || s[j] == '+'))
              ++j;
            numbers.push_back({i, j - i});
            i = j;
          } else {
            ++i;
          }
        }
        if (numbers.empty()) return s;
        const auto [a, len] =
            numbers[static_cast<std::size_t>(Pick(static_cast<int>(numbers.size())))];
        return s.replace(
            a, len, kNumbers[static_cast<std::size_t>(Pick(static_cast<int>(kNumbers.size())))]);
      }
      case 8: {  // a string emptied
        const std::size_t a = s.find('"', At(s));
        if (a == std::string::npos) return s;
        const std::size_t b = s.find('"', a + 1);
        return b == std::string::npos ? s : s.replace(a + 1, b - a - 1, "");
      }
      case 9: {  // a value nested deeply
        const std::size_t a = s.find(':', At(s));
        if (a == std::string::npos) return s;
        const int depth = Pick(2) ? 100 : 5000;
        s.insert(a + 1, std::string(static_cast<std::size_t>(depth), '['));
        const std::size_t b = s.find_first_of(",}\n", a + 1 + static_cast<std::size_t>(depth));
        return s.insert(b == std::string::npos ? s.size() : b,
                        std::string(static_cast<std::size_t>(depth), ']'));
      }
      default: {  // lines swapped, duplicated or dropped
        std::vector<std::string> lines;
        std::stringstream in(s);
        for (std::string l; std::getline(in, l);) lines.push_back(l);
        if (lines.size() < 2) return s;
        const std::size_t i = static_cast<std::size_t>(Pick(static_cast<int>(lines.size()))),
                          j = static_cast<std::size_t>(Pick(static_cast<int>(lines.size())));
        if (Pick(3) == 0)
          std::swap(lines[i], lines[j]);
        else if (Pick(2))
          lines.insert(lines.begin() + static_cast<long>(i), lines[j]);
        else
          lines.erase(lines.begin() + static_cast<long>(i));
        std::string out;
        for (const std::string& l : lines) out += l + "\n";
        return out;
      }
    }
  }
  std::mt19937 rng_;
};

struct Tally {
  int accepted = 0, refused = 0;
  std::vector<std::string> findings;
};

// Runs `parse` on mutations of `valid`; `parse` throws InputError to refuse, returns "" when it
// accepted valid values, or a description of what it accepted wrongly.
Tally Fuzz(const std::string& name, const std::string& valid,
           const std::function<std::string(const std::string&)>& parse) {
  Tally tally;
  EXPECT_EQ(parse(valid), "") << name << ": the valid seed must load";
  for (int run = 0; run < Runs(); ++run) {
    const std::string input = Mutator(static_cast<unsigned>(run) * 2654435761u + 1u)(valid);
    // INHAND_FUZZ_DUMP=NAME:RUN runs only that input and writes it to $TMPDIR/inhand-fuzz-NAME-RUN.
    if (const char* dump = std::getenv("INHAND_FUZZ_DUMP")) {
      if (std::string(dump) != name + ":" + std::to_string(run)) continue;
      std::ofstream(fs::temp_directory_path() / ("inhand-fuzz-" + name + "-" + std::to_string(run)),
                    std::ios::binary)
          << input;
    }
    const auto start = std::chrono::steady_clock::now();
    try {
      const std::string wrong = parse(input);
      if (wrong.empty())
        ++tally.accepted;
      else
        tally.findings.push_back(name + " run " + std::to_string(run) + ": accepted " + wrong);
    } catch (const InputError&) {
      ++tally.refused;
    } catch (const std::exception& e) {
      tally.findings.push_back(name + " run " + std::to_string(run) + ": " + typeid(e).name() +
                               ": " + e.what());
    }
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (s > 10.0)
      tally.findings.push_back(name + " run " + std::to_string(run) + ": took " +
                               std::to_string(s) + " s");
  }
  std::printf("fuzz %-16s %6d inputs: %6d refused with a message, %6d accepted, %zu findings\n",
              name.c_str(), Runs(), tally.refused, tally.accepted, tally.findings.size());
  for (const std::string& f : tally.findings) ADD_FAILURE() << f;
  return tally;
}

// A small valid session: the project's hand and ketchup bottle, 20 joint samples, 2 frames,
// ground truth. Each fuzzed file replaces one of its files.
struct SmallSession {
  test::TempDir dir;
  SmallSession() {
    const std::vector<std::string> names =
        LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false})
            .QNames();
    std::string joints = "t";
    for (const auto& n : names) joints += ",q:" + n;
    for (const auto& n : names) joints += ",tau:" + n;
    joints += "\n";
    for (int k = 0; k < 20; ++k) {
      joints += std::to_string(0.002 * k);
      for (std::size_t j = 0; j < names.size(); ++j) joints += "," + std::to_string(0.3 + 0.01 * k);
      for (std::size_t j = 0; j < names.size(); ++j) joints += "," + std::to_string(0.1);
      joints += "\n";
    }
    dir.Write("joints.csv", joints);
    dir.Write("camera.csv",
              "t,image,px,py,pz,qw,qx,qy,qz\n0,images/a.png,0.1,0.2,0.3,1,0,0,0\n0.02,images/"
              "b.png,0.1,0.2,0.3,1,0,0,0\n");
    dir.Write("images/a.png", "x");
    dir.Write("images/b.png", "x");
    dir.Write("groundtruth.csv",
              "t,px,py,pz,qw,qx,qy,qz\n0,0,0.06,0.05,1,0,0,0\n0.04,0,0.06,0.05,0.7071068,0.7071068,"
              "0,0\n");
    dir.Write("session.json", R"({
  "format": "inhand-session",
  "version": 1,
  "name": "fuzz",
  "hand": {"urdf": ")" + test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf") +
                                  R"("},
  "object": {"model": ")" + test::ProjectAsset("objects/ketchup_bottle/object.json") +
                                  R"("},
  "camera": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 32, "cy": 24, "distortion": [0, 0, 0, 0, 0]},
  "initial_estimate": {"T_PO": {"xyz": [0, 0.06, 0.05], "quat_wxyz": [1, 0, 0, 0]}, "sigma_position": 0.02,
                       "sigma_orientation": 0.087, "sigma_joint_bias": 0.087},
  "provenance": {"by": "fuzz_test"}
}
)");
  }
};

// What a loaded session must hold.
std::string CheckSession(const Session& s) {
  for (int k = 0; k < s.num_samples(); ++k)
    if (!std::isfinite(s.t(k)) || (k > 0 && !(s.t(k) > s.t(k - 1))) || !s.q(k).allFinite() ||
        !s.tau(k).allFinite())
      return "joint sample " + std::to_string(k) + " not finite or not increasing";
  for (const CameraFrame& f : s.camera_frames())
    if (!std::isfinite(f.t) || !f.T_PC.matrix().allFinite()) return "a camera frame not finite";
  for (const GroundTruthSample& g : s.groundtruth())
    if (!std::isfinite(g.t) || !g.T_PO.matrix().allFinite())
      return "a ground-truth pose not finite";
  const SessionInfo& i = s.info();
  if (!i.initial_T_PO.matrix().allFinite() || !(i.sigma_position > 0 && i.sigma_position <= 10) ||
      !(i.sigma_orientation > 0) || !(i.sigma_joint_bias >= 0))
    return "an initial estimate out of range";
  if (i.camera && !(i.camera->width > 0 && i.camera->width <= 16384 && i.camera->fx > 0))
    return "bad intrinsics";
  return "";
}

TEST(Fuzz, SessionFiles) {
  SmallSession base;
  for (const std::string file : {"session.json", "joints.csv", "camera.csv", "groundtruth.csv"}) {
    const std::string valid = test::ReadFile(base.dir / file);
    test::TempDir work;
    fs::copy(base.dir.path(), work / "s", fs::copy_options::recursive);
    Fuzz(file, valid, [&](const std::string& text) {
      std::ofstream(work / ("s/" + file), std::ios::binary) << text;
      const Session s = Session::Load(work / "s");
      if (std::string wrong = CheckSession(s); !wrong.empty()) return wrong;
      if (file != "session.json") return std::string();
      const SessionModels m = LoadSessionModels(s, false);  // joints matched to the hand
      return m.joint_columns.size() == 16 ? std::string()
                                          : std::string("a joint mapping of the wrong size");
    });
  }
}

TEST(Fuzz, ParameterFile) {
  TrackerParams p;
  Fuzz("params.json", TrackerParamsToJson(p), [](const std::string& text) {
    const TrackerParams q = TrackerParamsFromJson(text, "params.json");
    q.Validate("again");  // what was accepted is valid
    const TrackerParams back = TrackerParamsFromJson(TrackerParamsToJson(q), "round trip");
    return TrackerParamsToJson(back) == TrackerParamsToJson(q)
               ? std::string()
               : std::string("a value that does not round-trip");
  });
}

TEST(Fuzz, ObjectFile) {
  const std::string src = test::ProjectAsset("objects/brush");
  test::TempDir work;
  fs::copy(src, work / "o", fs::copy_options::recursive);
  Fuzz("object.json", test::ReadFile(src + "/object.json"), [&](const std::string& text) {
    std::ofstream(work / "o/object.json", std::ios::binary) << text;
    // The description's contact_field is parsed and validated; building the field (a second
    // per new geometry, tested in contacts/field_test.cpp) is left out of the mutation loop.
    ContactFieldOptions no_field;
    no_field.source = "none";
    const ObjectModel o = LoadObjectModel(work / "o/object.json", {}, no_field);
    if (!(o.mass > 0) || !std::isfinite(o.mass) || o.pieces.empty())
      return std::string("a mass or pieces out of range");
    for (const TagPlacement& t : o.tags)
      if (!(t.size > 0) || !t.T_OT.matrix().allFinite()) return std::string("a tag out of range");
    return std::string();
  });
}

TEST(Fuzz, Urdf) {
  const std::string path = test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf");
  const std::string dir = fs::path(path).parent_path().string();
  Fuzz("urdf", test::ReadFile(path), [&](const std::string& text) {
    const HandModel h = ParseHandModel(text, dir, "hand.urdf", {{}, false});
    for (const Joint& j : h.joints)
      if (!j.T_LJ.matrix().allFinite() || !j.axis.allFinite() ||
          (j.has_limits && !(j.lower <= j.upper)))
        return std::string("joint '" + j.name + "' not finite or with limits upside down");
    return std::string();
  });
}

// ROS recordings: our MCAP reader (plain and zstd chunks), CDR decoder and .db3 reader, on
// mutations of the fixtures the official tools wrote. Every topic is read and decoded.
void FuzzRecording(const std::string& fixture) {
  const std::string valid = test::ReadFile(test::SourceDir() + "/tests/ros/fixtures/" + fixture);
  test::TempDir work;
  const std::string path = work / ("r" + fs::path(fixture).extension().string());
  Fuzz(fixture, valid, [&](const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    std::unique_ptr<ros::Recording> rec = ros::OpenRecording(path);
    std::vector<std::string> topics;
    for (const ros::TopicInfo& t : rec->Topics()) topics.push_back(t.name);
    std::size_t messages = 0;
    rec->Read(topics, true, [&](ros::Message&) { ++messages; });
    return std::string();
  });
}

TEST(Fuzz, McapRecording) { FuzzRecording("synthetic.mcap"); }
TEST(Fuzz, McapZstdRecording) { FuzzRecording("synthetic_zstd.mcap"); }
TEST(Fuzz, McapLz4Recording) { FuzzRecording("synthetic_lz4.mcap"); }
TEST(Fuzz, Db3Recording) { FuzzRecording("synthetic.db3"); }
TEST(Fuzz, Ros1Bag) { FuzzRecording("synthetic.bag"); }

}  // namespace
}  // namespace inhand
