// Python target (issue 39): feeding 500 Hz joint samples from Python costs at most 20 µs per
// sample above the C++ step. One session (ketchup, seed 1, no images) is tracked with jt by the
// C++ Tracker and by the `inhand` module driven from an embedded interpreter, alternately, three
// passes each; every call is timed by its caller (steady_clock in C++, perf_counter_ns in
// Python, the loop's row indexing included), and the counters are the medians over all calls:
// cpp_us, python_us, their difference overhead_us and ratio.
#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <vector>

#include "inhand/sessions/session.hpp"
#include "inhand/sessions/simulator.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;
namespace py = pybind11;

const std::string& SessionDir() {
  static const std::string dir = [] {
    const fs::path d = fs::temp_directory_path() / "inhand_bench_python_session";
    fs::remove_all(d);
    SimulateOptions o;
    o.scenario = "ketchup-power-grasp";
    o.out_dir = d.string();
    o.images = false;
    Simulate(o);
    return d.string();
  }();
  return dir;
}

// One pass of the C++ Tracker over the session: each AddJointSample's time [µs].
void CppPass(const Session& s, const SessionModels& m, std::vector<double>& us) {
  Tracker tracker(m.hand, m.object, Modalities::Parse("jt", "set"), TrackerParams());
  tracker.Start(s.t(0), s.info().initial_T_PO);
  Eigen::VectorXd q(m.hand.num_q()), tau(m.hand.num_q());
  for (int k = 0; k < s.num_samples(); ++k) {
    for (std::size_t j = 0; j < m.joint_columns.size(); ++j) {
      q[static_cast<long>(j)] = s.q(k)[m.joint_columns[j]];
      tau[static_cast<long>(j)] = s.tau(k)[m.joint_columns[j]];
    }
    const auto start = std::chrono::steady_clock::now();
    tracker.AddJointSample(s.t(k), q, tau);
    if (k > 0)  // the first sample sizes the history once
      us.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
              .count());
  }
}

// The same pass written as a user would in Python (the README's loop).
constexpr const char* kPythonPass = R"(
def python_pass(session_dir, us):
    import time
    import inhand
    s = inhand.Session(session_dir)
    hand, obj, columns = s.models()
    tracker = inhand.Tracker(hand, obj, "jt")
    tracker.start(s.t[0], s.initial_pose, s.sigma_position, s.sigma_orientation,
                  s.sigma_joint_bias)
    q, tau, t = s.q[:, columns], s.tau[:, columns], s.t
    clock = time.perf_counter_ns
    for k in range(len(t)):
        start = clock()
        tracker.add_joint_sample(t[k], q[k], tau[k])
        if k > 0:
            us.append((clock() - start) / 1000.0)
)";

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

void BM_Python_JointSample_Jt_OverCpp(benchmark::State& state) {
  static py::scoped_interpreter interpreter;
  py::module_::import("sys").attr("path").attr("insert")(0, INHAND_PYTHON_DIR);
  py::dict scope;
  scope["__builtins__"] = py::module_::import("builtins");
  py::exec(kPythonPass, scope);
  const py::object python_pass = scope["python_pass"];
  const Session session = Session::Load(SessionDir());
  const SessionModels models = LoadSessionModels(session, false);
  std::vector<double> cpp_us, python_us;
  for (auto _ : state) {
    for (int pass = 0; pass < 3; ++pass) {
      CppPass(session, models, cpp_us);
      py::list us;
      python_pass(SessionDir(), us);
      for (const py::handle h : us) python_us.push_back(h.cast<double>());
    }
  }
  const double cpp = Median(cpp_us), python = Median(python_us);
  state.counters["cpp_us"] = cpp;
  state.counters["python_us"] = python;
  state.counters["overhead_us"] = python - cpp;
  state.counters["ratio"] = python / cpp;
  state.counters["samples"] = static_cast<double>(python_us.size());
}
BENCHMARK(BM_Python_JointSample_Jt_OverCpp)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace inhand
