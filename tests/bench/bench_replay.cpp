// Replay targets (issue 18), on the demo session (ketchup-power-grasp, seed 1, paper noise:
// 5.0 s of 500 Hz joints, 51 camera frames at 10 Hz). The replays report `x_real_time`: the
// session's duration over the wall time of one whole `inhand replay` (read the median):
//   all four sets + video        >= 3x     all four sets, no video   >= 5x
//   j,jt, no video               >= 10x
// and the pictures of one frame (overlays + virtual view + 3-D view + H.264 encoding, 1920x480)
// <= 15 ms. Each replay runs with --jobs 1 and with every core (`jobs` in the name).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "inhand/app/commands.hpp"
#include "inhand/app/frame_composer.hpp"
#include "inhand/app/player.hpp"
#include "inhand/renderer/video.hpp"
#include "inhand/sessions/simulator.hpp"

namespace inhand {
namespace {

namespace fs = std::filesystem;

const std::string& DemoSession() {
  static const std::string dir = [] {
    const fs::path d = fs::temp_directory_path() / "inhand_bench_replay_session";
    fs::remove_all(d);
    SimulateOptions o;
    o.scenario = "ketchup-power-grasp";
    o.out_dir = d.string();
    o.seed = 1;
    o.noise = NoiseProfile::kPaper;
    Simulate(o);
    return d.string();
  }();
  return dir;
}

void Replay(benchmark::State& state, const std::string& modalities, bool video, int jobs) {
  const std::string session = DemoSession();
  const Session s = Session::Load(session);
  const double duration = s.t(s.num_samples() - 1) - s.t(0);
  app::ReplayCommand cmd;
  cmd.session = session;
  cmd.out = (fs::temp_directory_path() / "inhand_bench_replay_out").string();
  cmd.modalities = modalities;
  cmd.no_video = !video;
  cmd.jobs = jobs;
  std::vector<double> factors;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    std::streambuf* cout = std::cout.rdbuf(nullptr);  // the replay's summary lines
    app::RunReplay(cmd);
    std::cout.rdbuf(cout);
    factors.push_back(
        duration / std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  fs::remove_all(cmd.out);
  std::sort(factors.begin(), factors.end());
  state.counters["x_real_time"] = factors[factors.size() / 2];
}

int Cores() { return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 16u)); }

void BM_Replay_AllSets_Video_Jobs1(benchmark::State& s) { Replay(s, "", true, 1); }
void BM_Replay_AllSets_Video_JobsCores(benchmark::State& s) { Replay(s, "", true, Cores()); }
void BM_Replay_AllSets_NoVideo_Jobs1(benchmark::State& s) { Replay(s, "", false, 1); }
void BM_Replay_AllSets_NoVideo_JobsCores(benchmark::State& s) { Replay(s, "", false, Cores()); }
void BM_Replay_JJt_NoVideo_Jobs1(benchmark::State& s) { Replay(s, "j,jt", false, 1); }
void BM_Replay_JJt_NoVideo_JobsCores(benchmark::State& s) { Replay(s, "j,jt", false, Cores()); }
BENCHMARK(BM_Replay_AllSets_Video_Jobs1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Replay_AllSets_Video_JobsCores)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Replay_AllSets_NoVideo_Jobs1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Replay_AllSets_NoVideo_JobsCores)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Replay_JJt_NoVideo_Jobs1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Replay_JJt_NoVideo_JobsCores)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// One frame's pictures as the replay makes them: the player at camera frame 30 (all four sets),
// its state captured, overlays painted, virtual and 3-D views rendered, placed side by side and
// encoded (H.264, 1920x480). The encoder gets the 51 frames of the session in turn, so that it
// codes real motion.
// The player after the whole demo session, with the pictures' state at each camera frame.
struct Played {
  Session session = Session::Load(DemoSession());
  app::SessionPlayer player{session, TrackerParams()};
  std::vector<app::PictureState> pictures;
  Played() {
    for (int k = 0; k < session.num_samples(); ++k) {
      player.Step(k);
      if (player.last_frame() >= 0)
        pictures.push_back(app::FrameComposer::Capture(player, player.last_frame(), session.t(k)));
    }
  }
};

void BM_ComposeAndEncodeFrame1920x480(benchmark::State& state) {
  const Played played;
  const std::vector<app::PictureState>& pictures = played.pictures;
  app::FrameComposer composer(played.player);
  const std::string path = (fs::temp_directory_path() / "inhand_bench_compose.mp4").string();
  std::unique_ptr<VideoWriter> video;
  std::size_t i = 0;
  for (auto _ : state) {
    const Image8 picture = composer.Compose(pictures[i++ % pictures.size()]);
    if (!video) video = std::make_unique<VideoWriter>(path, 10.0, picture.width, picture.height);
    video->Write(picture);
  }
  if (video) video->Close();
  fs::remove(path);
}
BENCHMARK(BM_ComposeAndEncodeFrame1920x480)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ComposeFrame1920x480_NoEncoding(benchmark::State& state) {
  const Played played;
  const std::vector<app::PictureState>& pictures = played.pictures;
  app::FrameComposer composer(played.player);
  std::size_t i = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(composer.Compose(pictures[i++ % pictures.size()]).data.data());
}
BENCHMARK(BM_ComposeFrame1920x480_NoEncoding)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace inhand
