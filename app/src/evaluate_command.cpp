#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "inhand/app/commands.hpp"
#include "inhand/app/modalities.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/sessions/install_dirs.hpp"
#include "inhand/sessions/output_folder.hpp"
#include "inhand/sessions/session.hpp"
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

// Fig. 7's data from one run: the change of x, y, z [mm] and roll, pitch, yaw [deg] from the
// truth's start over time, of the truth and of each set, as fig7_SCENARIO.csv (t, series, the six
// changes; angles wrapped to ±180°). inhand_plots draws it.
void WriteFig7Data(const std::string& run_dir, const std::string& path) {
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
  const Vec6 start = series["truth"].empty() ? Vec6::Zero() : series["truth"].front().second;
  std::ofstream out(path);
  out << "t,series,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n";
  for (const auto& [name, samples] : series)
    for (const auto& [t, v] : samples) {
      out << FormatDouble(t) << "," << name;
      for (int a = 0; a < 6; ++a) {
        double d = v[a] - start[a];
        if (a >= 3) d = std::remainder(d, 360.0);
        out << "," << FormatDouble(d);
      }
      out << "\n";
    }
}

// Draws the plots with matplotlib (python3 -m inhand_plots OUT): the module beside the running
// code (build/python from build/bin; PREFIX/lib/python3.X/dist-packages from PREFIX/bin; the
// Python module's own folder). The tables stand without them: a missing plotter is a warning.
void DrawPlots(const std::string& out) {
  const std::string python = INHAND_PYTHON_EXECUTABLE;
  std::string dir;
  if (const fs::path here = RunningCodeDir(); !here.empty() && !python.empty())
    for (const fs::path& d : {here / "../python", here / ".." / INHAND_PYTHON_INSTALL_DIR, here})
      if (fs::is_regular_file(d / "inhand_plots.py")) {
        dir = fs::canonical(d).string();
        break;
      }
  if (dir.empty()) {
    std::cerr << "evaluate: no plots: this build has no Python module (inhand_plots)\n";
    return;
  }
  const std::string command = "PYTHONPATH=" + Quote(dir) + " PYTHONDONTWRITEBYTECODE=1 " +
                              Quote(python) + " -m inhand_plots " + Quote(out);
  const int status = std::system(command.c_str());
  if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0))
    std::cerr << "evaluate: the plots were not drawn (" << command
              << " failed; the tables are written)\n";
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

// Every run's summary.json that exists, per scenario in the evaluation's order: (seed, its
// contents), read once for Table I and the trust table.
using SeedSummaries = std::vector<std::pair<int, Json>>;
using Summaries = std::vector<std::pair<std::string, SeedSummaries>>;
Summaries ReadSummaries(const EvaluateCommand& cmd, const std::vector<std::string>& scenarios,
                        int last_seed) {
  Summaries out;
  for (const std::string& s : scenarios) {
    SeedSummaries& runs = out.emplace_back(s, SeedSummaries()).second;
    for (int seed = cmd.first_seed; seed <= last_seed; ++seed) {
      const fs::path summary = fs::path(RunDir(cmd.out, s, seed)) / "replay/summary.json";
      if (fs::exists(summary)) runs.emplace_back(seed, jsonf::ReadFile(summary.string()));
    }
  }
  return out;
}

// One scenario's rows of Table I (into `table` and `md`) from its runs' summaries, and its
// Fig. 7-style plot from the first seed's run.
void MergeScenario(const EvaluateCommand& cmd, const std::string& s, const SeedSummaries& summaries,
                   Json& table, std::ostream& md) {
  std::map<std::string, std::vector<double>> pos, ori, nees, pen_mean, pen_max;
  for (const auto& [seed, j] : summaries) {
    for (auto it = j.at("modalities").begin(); it != j.at("modalities").end(); ++it) {
      if (!it.value().contains("terminal_position_error_mm")) continue;
      pos[it.key()].push_back(it.value().at("terminal_position_error_mm").get<double>());
      ori[it.key()].push_back(it.value().at("terminal_orientation_error_deg").get<double>());
      nees[it.key()].push_back(it.value().value("nees_mean", 0.0));
      pen_mean[it.key()].push_back(it.value().value("penetration_mm_mean", 0.0));
      pen_max[it.key()].push_back(it.value().value("penetration_mm_max", 0.0));
    }
  }
  for (const ModalitySet& m : ParseModalities(cmd.modalities)) {
    const std::string& set = m.name;
    if (!pos.count(set)) continue;
    const Stat p = Stats(pos[set]), o = Stats(ori[set]), n = Stats(nees[set]);
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
    WriteFig7Data(first, (fs::path(cmd.out) / ("fig7_" + s + ".csv")).string());
}

// Does each set say when it is wrong? Over every scenario and seed of the evaluation, per set
// (docs/evaluation.md, "Health"): a run is *bad* when it ends more than twice its scenario's
// median position error for that set, or more than 15 mm off, and *good* within 1.5× that median;
// it *alarmed* when it said `inconsistent` or `lost` at some time. Written as trust.json and as a
// section of table1.md.
Json MergeTrust(const EvaluateCommand& cmd, const Summaries& summaries, std::ostream& md) {
  struct Run {
    std::string scenario;
    int seed = 0;
    double mm = 0, deg = 0, alarmed_share = 0;
    bool alarmed = false, silent = false;
  };
  std::map<std::string, std::vector<Run>> by_set;
  for (const auto& [s, runs] : summaries)
    for (const auto& [seed, j] : runs) {
      for (auto it = j.at("modalities").begin(); it != j.at("modalities").end(); ++it) {
        const Json& v = it.value();
        if (!v.contains("terminal_position_error_mm")) continue;
        Run r;
        r.scenario = s;
        r.seed = seed;
        r.mm = v.at("terminal_position_error_mm").get<double>();
        r.deg = v.at("terminal_orientation_error_deg").get<double>();
        r.alarmed = v.value("health_alarms", 0) > 0;
        r.silent = !r.alarmed && v.value("health_final", std::string()) == "ok";
        if (v.contains("health_time_share"))
          r.alarmed_share = v.at("health_time_share").value("inconsistent", 0.0) +
                            v.at("health_time_share").value("lost", 0.0);
        by_set[it.key()].push_back(r);
      }
    }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  };
  // jt's run of the same scenario and seed, for "worse than jt".
  const auto jt_of = [&](const Run& r) -> const Run* {
    const auto jt = by_set.find("jt");
    if (jt == by_set.end()) return nullptr;
    for (const Run& x : jt->second)
      if (x.scenario == r.scenario && x.seed == r.seed) return &x;
    return nullptr;
  };
  Json out = Json::object();
  md << "\n## Trust: does each set say when it is wrong?\n\n"
     << "Over every scenario and seed above. Bad: a run that ends more than twice its scenario's "
        "median position error for the set, or more than 15 mm off; good: within 1.5x that "
        "median. Alarmed: said `inconsistent` or `lost` at some time. Silent: a bad run that "
        "never alarmed and ended `ok`. Worse than jt: more than 5 mm or 10 deg worse than jt's run "
        "of the same scenario and seed.\n\n"
     << "| set | runs | bad | bad that alarmed | silent bad | good runs' time alarmed | worse "
        "than jt | of them alarmed | worst run [mm] |\n"
     << "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const ModalitySet& m : ParseModalities(cmd.modalities)) {
    const auto found = by_set.find(m.name);
    if (found == by_set.end()) continue;
    const std::vector<Run>& runs = found->second;
    std::map<std::string, std::vector<double>> per_scenario;
    for (const Run& r : runs) per_scenario[r.scenario].push_back(r.mm);
    std::map<std::string, double> med;
    for (const auto& [s, v] : per_scenario) med[s] = median(v);
    int bad = 0, bad_alarmed = 0, silent = 0, good = 0, worse = 0, worse_alarmed = 0;
    double good_share = 0.0;
    const Run* worst = &runs.front();
    for (const Run& r : runs) {
      if (r.mm > worst->mm) worst = &r;
      const double md_s = med[r.scenario];
      if (r.mm > 2.0 * md_s || r.mm > 15.0) {
        ++bad;
        bad_alarmed += r.alarmed;
        silent += r.silent;
      } else if (r.mm <= 1.5 * md_s) {
        ++good;
        good_share += r.alarmed_share;
      }
      if (m.name != "jt")
        if (const Run* jt = jt_of(r); jt && (r.mm > jt->mm + 5.0 || r.deg > jt->deg + 10.0)) {
          ++worse;
          worse_alarmed += r.alarmed;
        }
    }
    const bool compared = m.name != "jt" && by_set.count("jt");
    Json cell = {{"runs", runs.size()},
                 {"bad", bad},
                 {"bad_alarmed", bad_alarmed},
                 {"silent_bad", silent},
                 {"good", good},
                 {"good_time_alarmed", good > 0 ? good_share / good : 0.0},
                 {"worst_scenario", worst->scenario},
                 {"worst_seed", worst->seed},
                 {"worst_position_mm", worst->mm}};
    if (compared) cell["worse_than_jt"] = worse, cell["worse_than_jt_alarmed"] = worse_alarmed;
    out[m.name] = cell;
    md << "| " << m.name << " | " << runs.size() << " | " << bad << " | " << bad_alarmed << " | "
       << silent << " | " << std::fixed << std::setprecision(1)
       << (good > 0 ? 100.0 * good_share / good : 0.0) << " % of " << good << " | "
       << (compared ? std::to_string(worse) : "-") << " | "
       << (compared ? std::to_string(worse_alarmed) : "-") << " | " << worst->mm << " ("
       << worst->scenario << " " << worst->seed << ") |\n";
  }
  return out;
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
  const Summaries summaries = ReadSummaries(cmd, scenarios, last_seed);
  for (const auto& [s, of_scenario] : summaries) MergeScenario(cmd, s, of_scenario, table, md);
  const Json trust = MergeTrust(cmd, summaries, md);
  std::ofstream(fs::path(cmd.out) / "trust.json") << trust.dump(2) << "\n";
  std::ofstream(fs::path(cmd.out) / "table1.md") << md.str();
  std::ofstream(fs::path(cmd.out) / "table1.json") << table.dump(2) << "\n";
  std::cout << md.str();
  DrawPlots(cmd.out);
  return 0;
}

}  // namespace inhand::app
