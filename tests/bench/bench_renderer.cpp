// Renderer targets (issue 4): colour + depth + labels + read-back at 640x480 of the hand with an
// object, median <= 10 ms; H.264 encoding <= 5 ms per frame.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "bench_paths.hpp"
#include "inhand/features/extracted.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/printed_tags.hpp"
#include "inhand/renderer/video.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand {
namespace {

struct RenderScene {
  Renderer renderer;
  Scene scene;
  Aabb bounds;  // the object's
  RenderScene(const std::string& object_file) {
    const HandModel hand = LoadHandModel(kRoot + "/assets/hands/inhand_hand/inhand_hand.urdf");
    const ObjectModel object = LoadObjectModel(object_file);
    bounds = object.Bounds();
    KinematicsData kin(hand);
    kin.Update(hand, Eigen::VectorXd::Constant(hand.num_q(), 0.6));
    scene.K = IntrinsicsFromFov(640, 480, 45);
    scene.background = Vec3(0.8, 0.8, 0.8);
    scene.T_PC = LookAt(Vec3(0.15, -0.1, 0.3), Vec3(0, 0.05, 0.03), Vec3::UnitY());
    AddHand(scene, UploadHand(renderer, hand), kin.link_poses());
    AddObject(scene, UploadObject(renderer, object),
              MakeTransform(Vec3(0, 0.05, 0.045), ExpSO3(Vec3(0, M_PI / 2, 0))));
  }
  // The object's bounds in the image of `s` (as the tracker finds them).
  Eigen::AlignedBox2d ObjectBox(const Scene& s) const {
    Eigen::AlignedBox2d box;
    for (const SceneItem& item : s.items)
      if (item.label == kObjectLabel)
        for (int i = 0; i < 8; ++i)
          box.extend(s.K.Project(s.T_PC.inverse() * item.T_PM *
                                 Vec3(i & 1 ? bounds.max.x() : bounds.min.x(),
                                      i & 2 ? bounds.max.y() : bounds.min.y(),
                                      i & 4 ? bounds.max.z() : bounds.min.z())));
    return box;
  }
};

void Render(benchmark::State& state, const std::string& object, bool depth, bool region = false) {
  if (!std::filesystem::exists(object)) {
    state.SkipWithError("object absent");
    return;
  }
  RenderScene s(object);
  if (region) s.scene.region = DrawnRegion(s.ObjectBox(s.scene), FeatureParams(), 640, 480);
  RenderOutput out;
  s.renderer.Render(s.scene, out, depth);  // warm-up: shader compilation, textures
  for (auto _ : state) {
    s.renderer.Render(s.scene, out, depth);
    benchmark::DoNotOptimize(out.colour.data.data());
  }
}

void BM_Render640_HandKetchup_ColourDepthLabels(benchmark::State& s) {
  Render(s, kRoot + "/assets/objects/ketchup_bottle/object.json", true);
}
// The extracted-feature step's virtual view: only around the object (DrawnRegion).
void BM_Render640_HandKetchup_ColourDepthLabels_DrawnRegion(benchmark::State& s) {
  Render(s, kRoot + "/assets/objects/ketchup_bottle/object.json", true, true);
}
void BM_Render640_HandKetchup_ColourOnly(benchmark::State& s) {
  Render(s, kRoot + "/assets/objects/ketchup_bottle/object.json", false);
}
void BM_Render640_HandYcbMustard16k_ColourDepthLabels(benchmark::State& s) {
  Render(s, kRoot + "/../shared/assets/objects/ycb/mustard_bottle.urdf", true);
}
BENCHMARK(BM_Render640_HandKetchup_ColourDepthLabels)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Render640_HandKetchup_ColourDepthLabels_DrawnRegion)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Render640_HandKetchup_ColourOnly)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Render640_HandYcbMustard16k_ColourDepthLabels)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// `tiles` rendered 640x480 views side by side (the replay layout has three).
void VideoEncode(benchmark::State& state, int tiles) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "inhand_bench_video.mp4").string();
  RenderScene s(kRoot + "/assets/objects/ketchup_bottle/object.json");
  RenderOutput out;
  s.renderer.Render(s.scene, out, false);
  Image8 frame(640 * tiles, 480, 3);
  for (int y = 0; y < 480; ++y)
    for (int k = 0; k < tiles; ++k)
      std::copy_n(out.colour.pixel(0, y), 640 * 3, frame.pixel(640 * k, y));
  VideoWriter writer(path, 30.0, frame.width, frame.height);
  int i = 0;
  for (auto _ : state) {
    frame.pixel(i % frame.width, 10)[0] ^= 0xFF;  // frames differ a little, as in a video
    writer.Write(frame);
    ++i;
  }
  writer.Close();
  std::filesystem::remove(path);
}
void BM_VideoEncodeH264_640x480(benchmark::State& s) { VideoEncode(s, 1); }
void BM_VideoEncodeH264_1920x480(benchmark::State& s) { VideoEncode(s, 3); }
BENCHMARK(BM_VideoEncodeH264_640x480)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_VideoEncodeH264_1920x480)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace inhand

// The AprilTag step of jta at 640x480: detection on a rendered frame with a tagged bottle.
#include "inhand/features/tags.hpp"
#include "inhand/renderer/printed_tags.hpp"

namespace inhand {
namespace {

void BM_TagDetection640(benchmark::State& state) {
  Renderer renderer;
  const ObjectModel object = LoadObjectModel(kRoot + "/assets/objects/ketchup_bottle/object.json");
  Scene scene;
  scene.K = IntrinsicsFromFov(640, 480, 45);
  scene.background = Vec3(0.6, 0.6, 0.6);
  scene.T_PC = LookAt(Vec3(0.05, -0.35, 0.15), Vec3(0, 0, 0.1), Vec3::UnitZ());
  AddObject(scene, UploadObject(renderer, object, PrintedTagMeshes(object)), Transform::Identity());
  RenderOutput out;
  renderer.Render(scene, out, false);
  TagDetector detector;
  std::size_t found = 0;
  for (auto _ : state) found = detector.Detect(out.colour).size();
  state.counters["tags"] = static_cast<double>(found);
}
BENCHMARK(BM_TagDetection640)->Unit(benchmark::kMillisecond)->UseRealTime();

// A detector's construction (every tracker with tags makes two): the tag family's decode table is
// built once per process, so after the first this is the detector alone (was 134 ms each).
void BM_TagDetectorConstruction(benchmark::State& state) {
  for (auto _ : state) {
    TagDetector detector;
    benchmark::DoNotOptimize(&detector);
  }
}
BENCHMARK(BM_TagDetectorConstruction)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace inhand

// The extracted-feature step of jtf at 640x480: virtual render (colour, depth, labels) and the
// five matching steps against a camera image of the object 4 mm / 1.5 deg away.

namespace inhand {
namespace {

void FeatureStep(benchmark::State& state, bool region) {
  RenderScene s(kRoot + "/assets/objects/ketchup_bottle/object.json");
  RenderOutput real;
  s.renderer.Render(s.scene, real, false);
  Scene shifted = s.scene;
  for (SceneItem& item : shifted.items)
    if (item.label == kObjectLabel)
      item.T_PM =
          MakeTransform(Vec3(0.004, -0.002, 0.0), ExpSO3(Vec3(0.02, 0.0, 0.01))) * item.T_PM;
  RenderOutput virt;
  std::vector<std::uint8_t> mask;
  int inliers = 0;
  for (auto _ : state) {
    // As the tracker: drawn and matched only around the object's bounds (SearchRegion).
    PixelRect search;
    if (region) {
      const Eigen::AlignedBox2d box = s.ObjectBox(shifted);
      search = SearchRegion(box, FeatureParams(), 640, 480);
      shifted.region = DrawnRegion(box, FeatureParams(), 640, 480);
    }
    s.renderer.Render(shifted, virt, true);
    mask.resize(virt.label.size());
    for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = virt.label[i] == kObjectLabel;
    inliers = MatchFeatures(real.colour, virt.colour, &mask, FeatureParams(), nullptr, false,
                            search)
                  .num_inliers();  // as the tracker: no debug-only camera corners
  }
  state.counters["inliers"] = inliers;
  state.counters["drawn_px"] = region ? shifted.region.width() * shifted.region.height() : 0;
}
void BM_ExtractedFeatureStep640(benchmark::State& state) { FeatureStep(state, true); }
// The same over the whole images (before the region): for the ratio.
void BM_ExtractedFeatureStep640_WholeImage(benchmark::State& state) { FeatureStep(state, false); }
BENCHMARK(BM_ExtractedFeatureStep640)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ExtractedFeatureStep640_WholeImage)->Unit(benchmark::kMillisecond)->UseRealTime();

// The matching alone with step 0, the shift of the whole object searched within 90 px (the
// tracker's first frames, and a lost object's search): the virtual image about 25 px off.
void BM_MatchFeatures640_GlobalSearch90(benchmark::State& state) {
  RenderScene s(kRoot + "/assets/objects/ketchup_bottle/object.json");
  RenderOutput real, virt;
  s.renderer.Render(s.scene, real, false);
  Scene shifted = s.scene;
  for (SceneItem& item : shifted.items)
    if (item.label == kObjectLabel)
      item.T_PM = MakeTransform(Vec3(0.012, -0.006, 0.0), Mat3::Identity()) * item.T_PM;
  s.renderer.Render(shifted, virt, true);
  std::vector<std::uint8_t> mask(virt.label.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = virt.label[i] == kObjectLabel;
  FeatureParams p;
  p.global_search_radius = 90;
  MatchResult m;
  for (auto _ : state) m = MatchFeatures(real.colour, virt.colour, &mask, p, nullptr, false);
  state.counters["inliers"] = m.num_inliers();
  state.counters["shift_px"] = m.debug.global_shift.norm();
}
BENCHMARK(BM_MatchFeatures640_GlobalSearch90)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace inhand
