// Simulator target (issue 5): every scenario, with its camera images, simulates in less than 3x
// its own duration; with the realistic camera too (issue 16: its own light, shadows, motion blur
// sub-frames, lens, sensor and JPEG). One full simulation per iteration; the counter `x_real_time`
// is wall time over simulated time (read its median from `make bench`).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "inhand/sessions/simulator.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;

void Simulation(benchmark::State& state, const std::string& scenario,
                NoiseProfile noise = NoiseProfile::kPaper) {
  const fs::path dir = fs::temp_directory_path() / ("inhand_bench_sim_" + scenario);
  double wall = 0.0, simulated = 0.0;
  for (auto _ : state) {
    fs::remove_all(dir);
    SimulateOptions o;
    o.scenario = scenario;
    o.out_dir = dir.string();
    o.noise = noise;
    const SimulationSummary s = Simulate(o);
    wall += s.wall_time;
    simulated += s.duration;
  }
  fs::remove_all(dir);
  state.counters["x_real_time"] = wall / simulated;
}

void BM_Simulate_Ketchup(benchmark::State& s) { Simulation(s, "ketchup-power-grasp"); }
void BM_Simulate_Brush(benchmark::State& s) { Simulation(s, "brush-rotation"); }
void BM_Simulate_Water(benchmark::State& s) { Simulation(s, "water-push-grasp"); }
void BM_Simulate_Shampoo(benchmark::State& s) { Simulation(s, "shampoo-grasp"); }
void BM_Simulate_Pen(benchmark::State& s) { Simulation(s, "pen-fingertip"); }
void BM_SimulateRealistic_Ketchup(benchmark::State& s) {
  Simulation(s, "ketchup-power-grasp", NoiseProfile::kRealistic);
}
void BM_SimulateRealistic_Brush(benchmark::State& s) {
  Simulation(s, "brush-rotation", NoiseProfile::kRealistic);
}
void BM_SimulateRealistic_Water(benchmark::State& s) {
  Simulation(s, "water-push-grasp", NoiseProfile::kRealistic);
}
void BM_SimulateRealistic_Shampoo(benchmark::State& s) {
  Simulation(s, "shampoo-grasp", NoiseProfile::kRealistic);
}
void BM_SimulateRealistic_Pen(benchmark::State& s) {
  Simulation(s, "pen-fingertip", NoiseProfile::kRealistic);
}
BENCHMARK(BM_Simulate_Ketchup)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Simulate_Brush)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Simulate_Water)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Simulate_Shampoo)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Simulate_Pen)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_SimulateRealistic_Ketchup)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_SimulateRealistic_Brush)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_SimulateRealistic_Water)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_SimulateRealistic_Shampoo)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_SimulateRealistic_Pen)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace inhand
