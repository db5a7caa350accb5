#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "inhand/app/commands.hpp"
#include "inhand/app/modalities.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "inhand/sessions/simulator.hpp"
#include "inhand/tracker/tracker_params.hpp"

namespace fs = std::filesystem;

namespace inhand::app {

namespace {

using jsonf::Json;

// The paper's Table I: terminal position [mm] / orientation [deg] errors per modality set.
struct PaperCell {
  double mm, deg;
};
const std::map<std::string, std::map<std::string, PaperCell>>& PaperTable() {
  static const std::map<std::string, std::map<std::string, PaperCell>> table = {
      {"ketchup-power-grasp",
       {{"j", {29.3, 22.9}}, {"jt", {26.6, 9.0}}, {"jta", {20.2, 7.0}}, {"jtf", {11.1, 11.2}}}},
      {"brush-rotation",
       {{"j", {37.6, 26.5}}, {"jt", {22.7, 10.8}}, {"jta", {13.5, 10.1}}, {"jtf", {13.7, 11.1}}}},
      {"water-push-grasp",
       {{"j", {28.6, 19.9}}, {"jt", {22.4, 9.5}}, {"jta", {16.0, 11.2}}, {"jtf", {17.4, 26.9}}}},
      {"shampoo-grasp",
       {{"j", {34.4, 22.1}}, {"jt", {15.9, 14.7}}, {"jta", {8.4, 6.8}}, {"jtf", {8.5, 10.4}}}},
  };
  return table;
}

std::string Quote(const std::string& s) { return "'" + s + "'"; }

std::string RunDir(const std::string& out, const std::string& scenario, int seed) {
  return (fs::path(out) / "runs" / (scenario + "-seed" + std::to_string(seed))).string();
}

std::string RunCommand(const std::string& self, const std::string& out, const std::string& scenario,
                       int seed, const std::string& noise, const std::string& modalities, bool keep,
                       const std::string& params) {
  const std::string dir = RunDir(out, scenario, seed);
  std::string c =
      Quote(self) + " simulate " + scenario + " --seed " + std::to_string(seed) + " --noise " +
      noise + " --overwrite --out " + Quote(dir + "/session") + " > " + Quote(dir + "/log.txt") +
      " 2>&1 && " + Quote(self) + " replay " + Quote(dir + "/session") + " --modalities " +
      Quote(modalities) + (params.empty() ? std::string() : " --params " + Quote(params)) +
      " --no-video --out " + Quote(dir + "/replay") + " >> " + Quote(dir + "/log.txt") + " 2>&1";
  if (!keep) c += " && rm -rf " + Quote(dir + "/session/images");
  return "mkdir -p " + Quote(dir) + " && " + c;
}

struct Stat {
  double mean = 0, std = 0;
  int n = 0;
};
Stat Stats(const std::vector<double>& v) {
  Stat s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  for (double x : v) s.mean += x;
  s.mean /= s.n;
  for (double x : v) s.std += (x - s.mean) * (x - s.mean);
  s.std = s.n > 1 ? std::sqrt(s.std / (s.n - 1)) : 0.0;
  return s;
}

// Fig. 7: change of x, y, z [mm] and roll, pitch, yaw [deg] over time (truth dashed black,
// each set in its colour), from one run; and the terminal errors of all runs as bars.
void PlotScenario(const std::string& scenario, const std::string& run_dir,
                  const std::map<std::string, std::pair<Stat, Stat>>& bars,
                  const std::string& path) {
  // Truth and estimates of the first seed.
  std::map<std::string, std::vector<std::pair<double, Vec6>>> series;  // set -> (t, pose6)
  const auto pose6 = [](const Transform& T) {
    Vec6 v;
    v.head<3>() = T.translation() * 1000.0;
    v.tail<3>() = RpyFromRotation(T.linear()) * 180.0 / M_PI;
    return v;
  };
  // The truth straight from groundtruth.csv (the run's images may have been deleted).
  std::ifstream gt(run_dir + "/session/groundtruth.csv");
  std::string line;
  std::getline(gt, line);
  while (std::getline(gt, line)) {
    double v[8];
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3],
                    &v[4], &v[5], &v[6], &v[7]) != 8)
      continue;
    series["truth"].emplace_back(
        v[0], pose6(MakeTransform(Vec3(v[1], v[2], v[3]), Quat(v[4], v[5], v[6], v[7]))));
  }
  std::ifstream in(run_dir + "/replay/estimates.csv");
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> f;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    if (f.size() < 9) continue;
    const Transform T =
        MakeTransform(Vec3(std::stod(f[2]), std::stod(f[3]), std::stod(f[4])),
                      Quat(std::stod(f[5]), std::stod(f[6]), std::stod(f[7]), std::stod(f[8])));
    series[f[1]].emplace_back(std::stod(f[0]), pose6(T));
  }
  const int W = 1500, H = 900, cols = 3;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const char* names[6] = {"x [mm]", "y [mm]", "z [mm]", "roll [deg]", "pitch [deg]", "yaw [deg]"};
  const Vec6 start = series["truth"].empty() ? Vec6::Zero() : series["truth"].front().second;
  for (int a = 0; a < 6; ++a) {
    const cv::Rect box(60 + (a % cols) * 480, 40 + (a / cols) * 280, 420, 220);
    double lo = 1e9, hi = -1e9, t0 = 1e9, t1 = -1e9;
    for (const auto& [set, s] : series)
      for (const auto& [t, v] : s) {
        double d = v[a] - start[a];
        if (a >= 3) d = std::remainder(d, 360.0);
        lo = std::min(lo, d), hi = std::max(hi, d), t0 = std::min(t0, t), t1 = std::max(t1, t);
      }
    if (hi - lo < 1e-6) hi = lo + 1;
    const double pad = 0.08 * (hi - lo);
    lo -= pad, hi += pad;
    cv::rectangle(img, box, cv::Scalar(120, 120, 120), 1);
    cv::putText(img, std::string("change in ") + names[a], cv::Point(box.x, box.y - 8),
                cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    std::ostringstream lo_s, hi_s;
    lo_s << std::fixed << std::setprecision(1) << lo;
    hi_s << std::fixed << std::setprecision(1) << hi;
    cv::putText(img, hi_s.str(), cv::Point(box.x - 55, box.y + 10), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
    cv::putText(img, lo_s.str(), cv::Point(box.x - 55, box.y + box.height),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
    const auto to_px = [&](double t, double v) {
      return cv::Point(box.x + static_cast<int>((t - t0) / (t1 - t0) * box.width),
                       box.y + box.height - static_cast<int>((v - lo) / (hi - lo) * box.height));
    };
    std::vector<std::string> order;  // every set, then the truth on top
    for (const auto& entry : series)
      if (entry.first != "truth") order.push_back(entry.first);
    order.push_back("truth");
    for (const std::string& set : order) {
      auto it = series.find(set);
      if (it == series.end()) continue;
      const Rgb c = ModalityColour(set);
      const cv::Scalar col(c.r, c.g, c.b);
      cv::Point prev(-1, -1);
      int k = 0;
      for (const auto& [t, v] : it->second) {
        double d = v[a] - start[a];
        if (a >= 3) d = std::remainder(d, 360.0);
        const cv::Point q = to_px(t, d);
        if (prev.x >= 0 && (set != "truth" || (k / 6) % 2 == 0))
          cv::line(img, prev, q, col, set == "truth" ? 2 : 1, cv::LINE_AA);
        prev = q;
        ++k;
      }
    }
    cv::putText(img, "t [s]", cv::Point(box.x + box.width - 30, box.y + box.height + 16),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
  // Bars: mean ± std terminal errors of all seeds.
  int x = 60;
  const int base = 880, scale_mm = 4, scale_deg = 4;
  cv::putText(
      img, scenario + ": terminal errors over all seeds (left mm, right deg; paper colours)",
      cv::Point(60, 615), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  for (const auto& [set, st] : bars) {
    const Rgb c = ModalityColour(set);
    const cv::Scalar col(c.r, c.g, c.b);
    const int hp = std::min(240, static_cast<int>(st.first.mean * scale_mm)),
              ho = std::min(240, static_cast<int>(st.second.mean * scale_deg));
    cv::rectangle(img, cv::Rect(x, base - hp, 30, hp), col, cv::FILLED);
    cv::rectangle(img, cv::Rect(x + 34, base - ho, 30, ho), col, 1);
    std::ostringstream label;
    label << set << ": " << std::fixed << std::setprecision(1) << st.first.mean << " mm, "
          << st.second.mean << " deg";
    cv::putText(img, label.str(), cv::Point(x, base + 14), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    x += 300;
  }
  Image8 out(W, H, 3);
  for (int y = 0; y < H; ++y) std::copy_n(img.ptr<std::uint8_t>(y), W * 3, out.pixel(0, y));
  WriteImage(path, out);
}

}  // namespace

// The scenarios --scenarios names (all when empty), each checked to exist.
std::vector<std::string> ScenariosOf(const EvaluateCommand& cmd) {
  std::vector<std::string> scenarios;
  if (cmd.scenarios.empty()) {
    for (const ScenarioInfo& s : ListScenarios()) scenarios.push_back(s.name);
  } else {
    std::stringstream ss(cmd.scenarios);
    std::string s;
    std::vector<std::string> known;
    for (const ScenarioInfo& i : ListScenarios()) known.push_back(i.name);
    while (std::getline(ss, s, ','))
      if (std::find(known.begin(), known.end(), s) == known.end())
        throw InputError("--scenarios: unknown scenario '" + s + "'");
      else
        scenarios.push_back(s);
  }
  return scenarios;
}

// Per scenario, the sets it runs, comma-separated: those with tags (a) only where the scenario's
// object carries tags (the pen has none).
std::map<std::string, std::string> SetsPerScenario(const EvaluateCommand& cmd,
                                                   const std::vector<std::string>& scenarios) {
  std::map<std::string, std::string> sets_of;
  for (const ScenarioInfo& info : ListScenarios()) {
    if (std::find(scenarios.begin(), scenarios.end(), info.name) == scenarios.end()) continue;
    ContactFieldOptions no_field;
    no_field.source = "none";
    const bool tags = !LoadObjectModel(info.object_file, {}, no_field).tags.empty();
    std::string list, dropped;
    for (const ModalitySet& m : ParseModalities(cmd.modalities)) {
      std::string& to = (m.tags && !tags) ? dropped : list;
      to += (to.empty() ? "" : ",") + m.name;
    }
    if (!dropped.empty())
      std::cerr << "evaluate: " << info.name << ": " << dropped
                << " left out (the object has no AprilTags)\n";
    if (list.empty())
      throw InputError("--modalities: no set can run on " + info.name +
                       " (its object has no AprilTags)");
    sets_of[info.name] = list;
  }
  return sets_of;
}

// Runs the commands as child processes, `jobs` at a time; the number that failed.
int RunAll(const std::vector<std::pair<std::string, std::pair<std::string, int>>>& runs, int jobs) {
  std::size_t next = 0;
  int running = 0, failed = 0;
  while (next < runs.size() || running > 0) {
    while (running < jobs && next < runs.size()) {
      const pid_t pid = ::fork();
      if (pid == 0) {
        ::execl("/bin/sh", "sh", "-c", runs[next].first.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
      }
      if (pid < 0) throw InputError("evaluate: cannot start a run");
      ++running, ++next;
    }
    int status = 0;
    if (::wait(&status) > 0) {
      --running;
      failed += !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
      std::cerr << "\revaluate: " << (next - static_cast<std::size_t>(running)) << "/"
                << runs.size() << " runs done" << std::flush;
    }
  }
  std::cerr << "\n";
  if (failed) std::cerr << "evaluate: " << failed << " runs failed (see runs/*/log.txt)\n";
  return failed;
}

// One scenario's rows of Table I (into `table` and `md`) from its runs' summaries, and its
// Fig. 7-style plot from the first seed's run.
void MergeScenario(const EvaluateCommand& cmd, const std::string& s, int last_seed, Json& table,
                   std::ostream& md) {
  std::map<std::string, std::vector<double>> pos, ori, nees, pen_mean, pen_max;
  for (int seed = cmd.first_seed; seed <= last_seed; ++seed) {
    const fs::path summary = fs::path(RunDir(cmd.out, s, seed)) / "replay/summary.json";
    if (!fs::exists(summary)) continue;
    const Json j = jsonf::ReadFile(summary.string());
    for (auto it = j.at("modalities").begin(); it != j.at("modalities").end(); ++it) {
      if (!it.value().contains("terminal_position_error_mm")) continue;
      pos[it.key()].push_back(it.value().at("terminal_position_error_mm").get<double>());
      ori[it.key()].push_back(it.value().at("terminal_orientation_error_deg").get<double>());
      nees[it.key()].push_back(it.value().value("nees_mean", 0.0));
      pen_mean[it.key()].push_back(it.value().value("penetration_mm_mean", 0.0));
      pen_max[it.key()].push_back(it.value().value("penetration_mm_max", 0.0));
    }
  }
  std::map<std::string, std::pair<Stat, Stat>> bars;
  for (const ModalitySet& m : ParseModalities(cmd.modalities)) {
    const std::string& set = m.name;
    if (!pos.count(set)) continue;
    const Stat p = Stats(pos[set]), o = Stats(ori[set]), n = Stats(nees[set]);
    bars[set] = {p, o};
    // The tail beside the mean: the worst run, and the deepest link inside the estimate (the
    // runs' time-averages averaged; the deepest of any sample of any run).
    const double worst_mm = *std::max_element(pos[set].begin(), pos[set].end());
    const double worst_deg = *std::max_element(ori[set].begin(), ori[set].end());
    const double pen = Stats(pen_mean[set]).mean;
    const double pen_worst = *std::max_element(pen_max[set].begin(), pen_max[set].end());
    Json cell = {{"runs", p.n},
                 {"position_mm_mean", p.mean},
                 {"position_mm_std", p.std},
                 {"position_mm_worst", worst_mm},
                 {"orientation_deg_mean", o.mean},
                 {"orientation_deg_std", o.std},
                 {"orientation_deg_worst", worst_deg},
                 {"nees_mean", n.mean},
                 {"penetration_mm_mean", pen},
                 {"penetration_mm_max", pen_worst}};
    std::ostringstream ps, os;
    ps << std::fixed << std::setprecision(1) << p.mean << " ± " << p.std;
    os << std::fixed << std::setprecision(1) << o.mean << " ± " << o.std;
    const auto paper = PaperTable().find(s);
    if (paper != PaperTable().end() && paper->second.count(set)) {
      const PaperCell& pc = paper->second.at(set);
      cell["paper_position_mm"] = pc.mm;
      cell["paper_orientation_deg"] = pc.deg;
      cell["at_or_below_paper"] = p.mean <= pc.mm && o.mean <= pc.deg;
      ps << " (" << pc.mm << ")";
      os << " (" << pc.deg << ")";
    }
    table[s][set] = cell;
    md << "| " << s << " | " << set << " | " << p.n << " | " << ps.str() << " | " << os.str()
       << " | " << std::fixed << std::setprecision(1) << worst_mm << " / " << worst_deg << " | "
       << std::setprecision(0) << n.mean << " | " << std::setprecision(1) << pen << " / "
       << pen_worst << " |\n";
  }
  const std::string first = RunDir(cmd.out, s, cmd.first_seed);
  if (fs::exists(fs::path(first) / "replay/estimates.csv") &&
      fs::exists(fs::path(first) / "session/groundtruth.csv"))
    PlotScenario(s, first, bars, (fs::path(cmd.out) / ("fig7_" + s + ".png")).string());
}

int RunEvaluate(const EvaluateCommand& cmd, const std::string& self) {
  if (cmd.out.empty()) throw InputError("evaluate: --out DIR is required");
  if (cmd.seeds < 1 || cmd.seeds > 1000)
    throw InputError("--seeds is " + std::to_string(cmd.seeds) + ", expected 1..1000");
  if (cmd.first_seed < 1 || cmd.first_seed > 1000000)
    throw InputError("--first-seed is " + std::to_string(cmd.first_seed) + ", expected 1..1000000");
  const int last_seed = cmd.first_seed + cmd.seeds - 1;
  if (cmd.jobs < 1 || cmd.jobs > 64)
    throw InputError("--jobs is " + std::to_string(cmd.jobs) + ", expected 1..64");
  ParseNoiseProfile(cmd.noise);
  const std::vector<std::string> scenarios = ScenariosOf(cmd);
  ParseModalities(cmd.modalities);  // an unknown set is an error before anything is written
  std::string params;
  if (!cmd.params.empty()) {
    ReadTrackerParams(cmd.params);  // a bad file is an error before any run
    params = fs::absolute(cmd.params).string();
  }
  // The evaluation folder collects runs (kept across --plan and --merge): it must be new, empty
  // or an evaluation folder already.
  const fs::path out_dir = CheckOutputFolder(cmd.out);
  fs::create_directories(out_dir);
  std::ofstream(out_dir / kOutputMarker) << "written by inhand evaluate\n";
  std::vector<std::pair<std::string, std::pair<std::string, int>>>
      runs;  // command, (scenario, seed)
  const std::map<std::string, std::string> sets_of = SetsPerScenario(cmd, scenarios);
  for (const std::string& s : scenarios)
    for (int seed = cmd.first_seed; seed <= last_seed; ++seed)
      runs.push_back(
          {RunCommand(self, cmd.out, s, seed, cmd.noise, sets_of.at(s), cmd.keep_sessions, params),
           {s, seed}});
  if (cmd.plan) {
    std::ofstream plan(fs::path(cmd.out) / "plan.txt");
    for (const auto& r : runs) plan << r.first << "\n";
    std::cout << runs.size() << " runs written to " << (fs::path(cmd.out) / "plan.txt").string()
              << "; run them (e.g. parallel < plan.txt), then: inhand evaluate --out " << cmd.out
              << " --merge\n";
    return 0;
  }
  if (!cmd.merge) RunAll(runs, cmd.jobs);
  // Merge: Table I with the paper's values beside ours.
  Json table = Json::object();
  std::ostringstream md;
  md << "# Table I: terminal errors, mean ± std over seeds " << cmd.first_seed << "-" << last_seed
     << " (" << cmd.noise << " noise)\n\n"
     << "Position [mm] and orientation [deg] at the end of each run; the paper's values in "
        "brackets.\n"
     << "Worst: the run that ended farthest off, in position / in orientation.\n"
     << "NEES: mean normalised estimation error squared of the 6-D pose (consistent filter: 6).\n"
     << "Penetration: how deep the deepest hand link lies inside the estimated object, averaged "
        "over each run's samples and then over the runs / the deepest of any sample [mm].\n\n"
     << "| scenario | set | runs | position [mm] | orientation [deg] | worst [mm / deg] | NEES "
        "mean "
        "| penetration mean / max [mm] |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const std::string& s : scenarios) MergeScenario(cmd, s, last_seed, table, md);
  std::ofstream(fs::path(cmd.out) / "table1.md") << md.str();
  std::ofstream(fs::path(cmd.out) / "table1.json") << table.dump(2) << "\n";
  std::cout << md.str();
  return 0;
}

}  // namespace inhand::app
