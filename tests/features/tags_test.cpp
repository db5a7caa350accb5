#include <gtest/gtest.h>

#include <thread>

#include <fstream>
#include <regex>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/renderer/printed_tags.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/image_io.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

struct Expected {
  int id;
  std::array<Vec2, 4> corners;
};

std::vector<Expected> ReadExpected(const std::string& path) {
  std::ifstream in(path);
  std::vector<Expected> out;
  std::string line;
  const std::regex re(
      R"((\d+),\s*\(([-0-9.]+) ([-0-9.]+)\),\s*\(([-0-9.]+) ([-0-9.]+)\),\s*\(([-0-9.]+) ([-0-9.]+)\),\s*\(([-0-9.]+) ([-0-9.]+)\))");
  while (std::getline(in, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, re)) continue;
    Expected e;
    e.id = std::stoi(m[1]);
    for (int k = 0; k < 4; ++k)
      e.corners[static_cast<std::size_t>(k)] =
          Vec2(std::stod(m[2 + 2 * k]), std::stod(m[3 + 2 * k]));
    out.push_back(e);
  }
  return out;
}

// The upstream regression: decimate 1, no edge refinement, every corner coordinate within
// 0.1 px (the upstream test compares x and y separately). Expected
// values are in libapriltag's coordinates (pixel centres at +0.5).
TEST(Tags, UpstreamPhotographsGiveTheExpectedCorners) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string dir = test::SharedAssets() + "/apriltag/upstream_test_data/test/data/";
  TagDetectorParams params;
  params.decimate = 1.0;
  params.refine_edges = false;
  TagDetector detector(params);
  int matched = 0;
  for (const char* name :
       {"33369213973_9d9bb4cc96_c", "34085369442_304b6bafd9_c", "34139872896_defdb2f8d9_c"}) {
    const std::vector<Expected> expected = ReadExpected(dir + name + ".txt");
    ASSERT_FALSE(expected.empty()) << name;
    const std::vector<TagDetection> found = detector.Detect(ReadGreyImage(dir + name + ".jpg"));
    EXPECT_EQ(found.size(), expected.size()) << name;
    for (const Expected& e : expected) {
      double best = 1e9;
      for (const TagDetection& d : found) {
        if (d.id != e.id) continue;
        double worst = 0.0;
        for (int k = 0; k < 4; ++k)
          worst = std::max(worst, (d.corners[static_cast<std::size_t>(k)] + Vec2(0.5, 0.5) -
                                   e.corners[static_cast<std::size_t>(k)])
                                      .cwiseAbs()
                                      .maxCoeff());
        best = std::min(best, worst);
      }
      EXPECT_LT(best, 0.15) << name << " tag " << e.id << " at " << e.corners[0].transpose();
      matched += best < 0.1;
    }
  }
  EXPECT_GE(matched, 45);  // of 47 (the other two: 0.106 and 0.14 px, Debian's libapriltag 3.3.0)
}

// A 640x480 camera with focal length f [px].
Intrinsics Camera640(double f) {
  Intrinsics K;
  K.width = 640;
  K.height = 480;
  K.fx = K.fy = f;
  K.cx = 319.5;
  K.cy = 239.5;
  return K;
}

TagPlacement Tag(int id, double size) {
  TagPlacement tag;
  tag.id = id;
  tag.size = size;
  return tag;
}

// One tag (mesh) at T_PT on grey, seen by K.
Image8 RenderTag(Renderer& renderer, int mesh, const Intrinsics& K, const Transform& T_PT) {
  Scene scene;
  scene.K = K;
  scene.background = Vec3(0.5, 0.5, 0.5);
  scene.items.push_back({mesh, T_PT, 1, std::nullopt, 1.0, true});
  RenderOutput out;
  renderer.Render(scene, out, false);
  return out.colour;
}

// A tag rendered with the estimator's projection is detected where the projection puts it:
// this pins the pixel convention (pixel centres at integers) end to end.
TEST(Tags, RenderedTagCornersMatchTheProjection) {
  Renderer renderer;
  const TagPlacement tag = Tag(42, 0.04);
  const int mesh = renderer.AddMesh(MakeTagMesh(tag));
  const Intrinsics K = Camera640(600.0);
  TagDetector detector;  // default: decimate 2, edge refinement on
  int checked = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const Transform T_PT =
        MakeTransform(Vec3(0.01 * trial - 0.015, 0.005 * trial, 0.3 + 0.03 * trial),
                      ExpSO3(Vec3(M_PI + 0.3 - 0.15 * trial, 0.25, 0.2 * trial)));
    const std::vector<TagDetection> found = detector.Detect(RenderTag(renderer, mesh, K, T_PT));
    ASSERT_EQ(found.size(), 1u) << "trial " << trial;
    EXPECT_EQ(found[0].id, 42);
    const auto corners = tag.CornersO();
    for (int k = 0; k < 4; ++k) {
      const Vec2 expected = K.Project(T_PT * corners[static_cast<std::size_t>(k)]);
      EXPECT_LT((found[0].corners[static_cast<std::size_t>(k)] - expected).norm(), 0.35)
          << "trial " << trial << " corner " << k;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 16);
}

// Every detector of a family shares one decode table per process (building it took 134 ms per
// detector): a detector destroyed leaves it to the others, detectors with another number of
// corrected bits get their own, and detectors on two threads at once find the same corners.
TEST(Tags, DetectorsShareTheFamilysTableAndOutliveEachOther) {
  Renderer renderer;
  const TagPlacement tag = Tag(42, 0.04);
  const int mesh = renderer.AddMesh(MakeTagMesh(tag));
  const Image8 image =
      RenderTag(renderer, mesh, Camera640(600.0),
                MakeTransform(Vec3(0.0, 0.0, 0.3), ExpSO3(Vec3(M_PI + 0.2, 0.1, 0.3))));
  std::vector<TagDetection> first;
  {
    TagDetector a;
    first = a.Detect(image);
  }
  ASSERT_EQ(first.size(), 1u);
  TagDetectorParams exact;
  exact.max_hamming = 0;
  TagDetector b, c, d(exact);
  std::vector<TagDetection> on_b, on_c;
  std::thread tb([&] { on_b = b.Detect(image); });
  std::thread tc([&] { on_c = c.Detect(image); });
  tb.join();
  tc.join();
  std::vector<TagDetection> on_d = d.Detect(image);
  for (const auto* found : {&on_b, &on_c, &on_d}) {
    ASSERT_EQ(found->size(), 1u);
    EXPECT_EQ(found->front().id, 42);
    for (std::size_t k = 0; k < 4; ++k)
      EXPECT_EQ(found->front().corners[k], first[0].corners[k]) << k;
  }
}

// A small tag (about 25 px wide, as on an object in the hand): a search of a region around it
// gives the same corners as the whole frame at the same resolution, in the whole image's pixel
// coordinates; a region without it finds nothing; regions beyond the border are clipped.
TEST(Tags, RegionSearchAgreesWithTheWholeFrame) {
  Renderer renderer;
  const TagPlacement tag = Tag(7, 0.018);
  const int mesh = renderer.AddMesh(MakeTagMesh(tag));
  const Intrinsics K = Camera640(580.0);
  const Transform T_PT = MakeTransform(Vec3(0.09, -0.05, 0.42), ExpSO3(Vec3(M_PI + 0.4, 0.2, 0.3)));
  const Image8 image = RenderTag(renderer, mesh, K, T_PT);
  TagDetectorParams full_resolution;
  full_resolution.decimate = 1.0;
  TagDetector detector(full_resolution);
  const std::vector<TagDetection> whole = detector.Detect(image);
  ASSERT_EQ(whole.size(), 1u);
  const Vec2 c = whole[0].center;
  const std::vector<TagDetection> region = detector.Detect(
      image, PixelRect{int(c.x()) - 40, int(c.y()) - 40, int(c.x()) + 40, int(c.y()) + 40});
  ASSERT_EQ(region.size(), 1u);
  EXPECT_EQ(region[0].id, 7);
  const auto corners = tag.CornersO();
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_LT((region[0].corners[k] - whole[0].corners[k]).norm(), 1e-3)
        << k;  // libapriltag computes in float
    EXPECT_LT((region[0].corners[k] - K.Project(T_PT * corners[k])).norm(), 0.35) << k;
  }
  EXPECT_TRUE(detector.Detect(image, PixelRect{0, 0, 100, 100}).empty());
  EXPECT_EQ(detector.Detect(image, PixelRect{-500, -500, 5000, 5000}).size(), 1u);
  EXPECT_TRUE(detector.Detect(image, PixelRect{700, 10, 800, 50}).empty());
}

// libapriltag crashed (SIGSEGV) on images a few pixels high; replay reached it through a region
// search cut by the frame's border (a 115 x 3 strip). Every tiny image, every strip and every
// region at every border gives no tag, never a crash, at every decimation.
TEST(Tags, TinyImagesAndRegionsAtEveryBorderNeverCrash) {
  for (const double decimate : {1.0, 1.5, 2.0, 4.0}) {
    TagDetectorParams p;
    p.decimate = decimate;
    TagDetector detector(p);
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{
             {1, 1}, {4, 4}, {100, 1}, {1, 100}, {115, 3}, {3, 115}, {8, 8}, {9, 20}, {640, 4}}) {
      Image8 image(w, h, 3);
      for (std::size_t i = 0; i < image.data.size(); ++i)
        image.data[i] = static_cast<std::uint8_t>((i * 37) & 255);
      EXPECT_TRUE(detector.Detect(image).empty()) << w << "x" << h << " at decimate " << decimate;
    }
    Image8 frame(640, 480, 3);
    for (std::size_t i = 0; i < frame.data.size(); ++i)
      frame.data[i] = static_cast<std::uint8_t>((i * 131) & 255);
    for (int inside = -2; inside <= 12; ++inside) {  // regions reaching `inside` px into the frame
      const int x = 300, y = 200;
      for (const PixelRect& r :
           {PixelRect{x, -100, x + 115, inside}, PixelRect{x, 480 - inside, x + 115, 580},
            PixelRect{-100, y, inside, y + 115}, PixelRect{640 - inside, y, 740, y + 115},
            PixelRect{-50, -50, inside, inside}, PixelRect{640 - inside, 480 - inside, 700, 540}})
        EXPECT_TRUE(detector.Detect(frame, r).empty())
            << r.x0 << "," << r.y0 << "," << r.x1 << "," << r.y1;
    }
  }
}

TEST(Tags, BadParametersAndIds) {
  TagDetectorParams p;
  p.family = "tag99h1";
  EXPECT_THROW(TagDetector{p}, InputError);
  p = TagDetectorParams();
  p.decimate = 0.5;
  EXPECT_THROW(TagDetector{p}, InputError);
}

}  // namespace
}  // namespace inhand
