#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/image_compare.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/video.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/image_io.hpp"
#include "test_support.hpp"
#include "video_probe.hpp"

namespace inhand {
namespace {

Renderer& SharedRenderer() {
  static Renderer r;  // one OSMesa context for the whole binary
  return r;
}

Intrinsics Camera(int w = 320, int h = 240) {
  Intrinsics K;
  K.width = w;
  K.height = h;
  K.fx = 300.3;
  K.fy = 297.9;
  K.cx = 161.37;
  K.cy = 118.71;
  return K;
}

// Signed distance of a pixel centre to a convex polygon (counter-clockwise or clockwise).
double SignedDistance(const std::vector<Vec2>& poly, const Vec2& p) {
  double inside = std::numeric_limits<double>::infinity();
  const double orientation = [&] {
    double a = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vec2& u = poly[i];
      const Vec2& v = poly[(i + 1) % poly.size()];
      a += u.x() * v.y() - v.x() * u.y();
    }
    return a > 0 ? 1.0 : -1.0;
  }();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    const Vec2 e = (b - a).normalized();
    const double cross = e.x() * (p - a).y() - e.y() * (p - a).x();
    inside = std::min(inside, orientation * cross);
  }
  return inside;  // > 0 inside
}

std::vector<Vec2> ConvexHull2d(std::vector<Vec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Vec2> hull;
  const auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = hull.size();
    for (const Vec2& p : pts) {
      while (hull.size() >= start + 2 && cross(hull[hull.size() - 2], hull.back(), p) <= 0)
        hull.pop_back();
      hull.push_back(p);
    }
    hull.pop_back();
    std::reverse(pts.begin(), pts.end());
  }
  return hull;
}

TEST(Renderer, SilhouetteAgreesWithTheEstimatorsProjection) {
  Renderer& r = SharedRenderer();
  const Vec3 h(0.03, 0.02, 0.05);
  const TriangleMesh box = ConvexPiece::Box(h, Transform::Identity()).ToMesh();
  const int id = r.AddMesh(box);
  const Intrinsics K = Camera();
  for (int trial = 0; trial < 5; ++trial) {
    const Transform T_PO = MakeTransform(Vec3(0.01 * trial - 0.02, 0.005 * trial, 0.02),
                                         ExpSO3(Vec3(0.3 + trial, -0.7, 0.2 * trial)));
    const Transform T_PC = MakeTransform(Vec3(0.0, 0.0, -0.4), Mat3::Identity());
    Scene scene;
    scene.K = K;
    scene.T_PC = T_PC;
    scene.items.push_back({id, T_PO, kObjectLabel, std::nullopt, 1.0, true});
    RenderOutput out;
    r.Render(scene, out);
    std::vector<Vec2> projected;
    for (const Vec3& v : box.vertices) projected.push_back(K.Project(T_PC.inverse() * (T_PO * v)));
    const std::vector<Vec2> silhouette = ConvexHull2d(projected);
    int checked = 0;
    for (int y = 0; y < K.height; ++y)
      for (int x = 0; x < K.width; ++x) {
        const double d = SignedDistance(silhouette, Vec2(x, y));
        const bool in_mask = out.label_at(x, y) == kObjectLabel;
        if (d > 0.5) {
          ASSERT_TRUE(in_mask) << "pixel (" << x << ", " << y << ") is " << d
                               << " px inside, not drawn";
          ++checked;
        } else if (d < -0.5) {
          ASSERT_FALSE(in_mask) << "pixel (" << x << ", " << y << ") is " << -d
                                << " px outside, drawn";
        }
      }
    EXPECT_GT(checked, 500);
  }
}

// A finely tessellated sphere (the renderer's accuracy, not the tessellation's, is under test).
TriangleMesh FineSphere(double radius, int rings, int segments) {
  TriangleMesh m;
  for (int i = 0; i <= rings; ++i) {
    const double phi = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double th = 2 * M_PI * j / segments;
      m.vertices.emplace_back(radius * std::sin(phi) * std::cos(th),
                              radius * std::sin(phi) * std::sin(th), radius * std::cos(phi));
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      m.triangles.emplace_back(a, a + segments, b + segments);
      m.triangles.emplace_back(a, b + segments, b);
    }
  m.ComputeNormals();
  return m;
}

TEST(Renderer, DepthIsMetricAlongTheOpticalAxis) {
  Renderer& r = SharedRenderer();
  const double radius = 0.05;
  const int sphere = r.AddMesh(FineSphere(radius, 120, 240));
  const Intrinsics K = Camera();
  const Vec3 centre_C(0.02, -0.01, 0.6);
  Scene scene;
  scene.K = K;
  scene.T_PC = MakeTransform(Vec3(0.1, 0.2, 0.3), ExpSO3(Vec3(0.2, 0.1, -0.3)));
  scene.items.push_back({sphere, MakeTransform(scene.T_PC * centre_C, Mat3::Identity()),
                         kObjectLabel, std::nullopt, 1.0, false});
  RenderOutput out;
  r.Render(scene, out);
  int checked = 0;
  double worst = 0.0;
  for (int y = 0; y < K.height; y += 3)
    for (int x = 0; x < K.width; x += 3) {
      // Analytic ray-sphere intersection through the pixel centre.
      const Vec3 ray = K.Unproject(Vec2(x, y), 1.0);
      const double a = ray.squaredNorm(), b = -2 * ray.dot(centre_C),
                   c = centre_C.squaredNorm() - radius * radius;
      const double disc = b * b - 4 * a * c;
      if (disc < 4 * a * 0.3 * radius * radius)
        continue;  // skip grazing rays at the rim (tessellation)
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      const double z = t * ray.z();
      ASSERT_EQ(out.label_at(x, y), kObjectLabel);
      worst = std::max(worst, std::abs(out.depth_at(x, y) - z));
      ++checked;
    }
  EXPECT_GT(checked, 100);
  EXPECT_LT(worst, 0.001);  // 1 mm
  EXPECT_TRUE(std::isinf(out.depth_at(0, 0)));
  EXPECT_EQ(out.label_at(0, 0), 0);

  // A box face-on: its front face at exactly 0.5 m - 20 mm.
  const int box =
      r.AddMesh(ConvexPiece::Box(Vec3(0.04, 0.03, 0.02), Transform::Identity()).ToMesh());
  Scene face_on;
  face_on.K = K;
  face_on.items.push_back({box, MakeTransform(Vec3(0.01, 0.0, 0.5), Mat3::Identity()), kObjectLabel,
                           std::nullopt, 1.0, false});
  r.Render(face_on, out);
  const Vec2 centre = K.Project(Vec3(0.01, 0.0, 0.48));
  EXPECT_NEAR(out.depth_at(static_cast<int>(centre.x()), static_cast<int>(centre.y())), 0.48, 1e-5);
}

// Our hand, its joints at zero, seen by a camera 0.35 m away facing the palm.
struct FacingThePalm {
  Renderer& r = SharedRenderer();
  HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  KinematicsData kin{hand};
  Scene scene;
  FacingThePalm(int width, int height) {
    kin.Update(hand, Eigen::VectorXd::Zero(hand.num_q()));
    scene.K = Camera(width, height);
    scene.T_PC = LookAt(Vec3(0, 0.07, 0.35), Vec3(0, 0.07, 0), Vec3::UnitY());
    AddHand(scene, UploadHand(r, hand), kin.link_poses());
  }
};

TEST(Renderer, LabelImageIdentifiesTheLinks) {
  FacingThePalm f(320, 320);
  Renderer& r = f.r;
  const HandModel& hand = f.hand;
  const KinematicsData& kin = f.kin;
  const Scene& scene = f.scene;
  RenderOutput out;
  r.Render(scene, out);
  const Transform T_CP = scene.T_PC.inverse();
  const auto label_at = [&](const Vec3& X) {
    const Vec2 uv = scene.K.Project(T_CP * X);
    return out.label_at(static_cast<int>(std::lround(uv.x())),
                        static_cast<int>(std::lround(uv.y())));
  };
  EXPECT_EQ(label_at(Vec3(0, 0.048, 0)), kHandLabelBase + hand.LinkIndex("palm"));
  for (const char* link : {"index_middle", "middle_distal", "ring_proximal", "thumb_middle"}) {
    const int l = hand.LinkIndex(link);
    const Vec3 centre = kin.T_PL(l) * Vec3(0, 0.012, 0.0);
    EXPECT_EQ(label_at(centre), kHandLabelBase + l) << link;
  }
  EXPECT_EQ(out.label_at(2, 2), 0);
}

// A region renders its pixels as the whole image does, to the bit (colour, depth, labels), and
// nothing else: every pixel outside is the background (the colour GL stores for it, depth +inf,
// label 0), also when the same output held a whole render before. A region partly outside the
// image is clipped; one wholly outside leaves the background everywhere.
TEST(Renderer, ARegionIsTheWholeRendersPixelsAndTheBackgroundElsewhere) {
  FacingThePalm f(320, 240);
  Renderer& r = f.r;
  Scene& scene = f.scene;
  scene.background = Vec3(0.5, 0.25, 0.75);
  RenderOutput whole, part;
  r.Render(scene, whole);
  r.Render(scene, part);  // the output held a whole render: the region must clear the rest
  // The background as GL stores it: a corner the hand does not reach.
  const std::uint8_t* bg = whole.colour.pixel(0, 0);
  ASSERT_EQ(whole.label_at(0, 0), 0);
  for (const PixelRect& region :
       {PixelRect{90, 40, 250, 200}, PixelRect{-30, 100, 170, 400}, PixelRect{400, 10, 500, 50}}) {
    scene.region = region;
    r.Render(scene, part);
    const PixelRect in = region.ClippedTo(320, 240);
    int drawn = 0;
    for (int y = 0; y < 240; ++y)
      for (int x = 0; x < 320; ++x) {
        const bool inside = x >= in.x0 && x < in.x1 && y >= in.y0 && y < in.y1;
        const std::size_t i = std::size_t(y) * 320 + x;
        if (inside) {
          ASSERT_TRUE(std::equal(whole.colour.pixel(x, y), whole.colour.pixel(x, y) + 3,
                                 part.colour.pixel(x, y)))
              << x << "," << y;
          ASSERT_EQ(whole.label[i], part.label[i]) << x << "," << y;
          ASSERT_EQ(whole.depth[i], part.depth[i]) << x << "," << y;
          drawn += part.label[i] != 0;
        } else {
          ASSERT_TRUE(std::equal(bg, bg + 3, part.colour.pixel(x, y))) << x << "," << y;
          ASSERT_EQ(part.label[i], 0) << x << "," << y;
          ASSERT_EQ(part.depth[i], std::numeric_limits<float>::infinity()) << x << "," << y;
        }
      }
    EXPECT_EQ(drawn > 0, !in.empty());  // the palm is in the middle of the image: in both
  }
}

// A hand as dark as the Allegro's black anodised links (Kd 0.004) is a flat black silhouette in
// the external 3-D view: its fingers cannot be told from the palm behind them. The explanatory
// views draw it in its LegibleColour, which shows the shading: across the hand's pixels the
// brightness varies (5th to 95th percentile), where it stayed within a few levels of black. Our
// own hand's colours stay.
TEST(Renderer, VeryDarkHandsAreDrawnLegiblyInTheExplanatoryViews) {
  Renderer& r = SharedRenderer();
  HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  {
    const HandMeshes own = UploadHand(r, hand);
    for (const auto& link : own.legible_rgba)
      for (const auto& rgba : link) EXPECT_FALSE(rgba.has_value());
  }
  for (Link& link : hand.links)
    for (TriangleMesh& m : link.visual)
      m.material.rgba = Eigen::Vector4d(0.004025, 0.004025, 0.004025, 1.0);
  Material black;
  black.rgba = Eigen::Vector4d(0.004, 0.002, 0.0, 0.5);
  const std::optional<Eigen::Vector4d> lifted = LegibleColour(black);
  ASSERT_TRUE(lifted.has_value());
  EXPECT_NEAR(0.2126 * (*lifted)[0] + 0.7152 * (*lifted)[1] + 0.0722 * (*lifted)[2],
              kLegibleLuminance, 1e-12);
  EXPECT_NEAR((*lifted)[0] - (*lifted)[2], 0.004, 1e-12);  // the hue's differences kept
  EXPECT_EQ((*lifted)[3], 0.5);
  black.texture_file = "/some/texture.png";
  EXPECT_FALSE(LegibleColour(black).has_value());

  const HandMeshes meshes = UploadHand(r, hand);
  KinematicsData kin(hand);
  kin.Update(hand, Eigen::VectorXd::Constant(hand.num_q(), 0.3));
  const auto brightness_spread = [&](bool legible, double* mean) {
    Scene scene;
    scene.K = Camera(320, 320);
    scene.T_PC = LookAt(Vec3(0.12, 0.2, 0.3), Vec3(0, 0.07, 0), Vec3::UnitY());
    scene.background = Vec3(0.9, 0.9, 0.9);
    AddHand(scene, meshes, kin.link_poses(), 1.0, legible);
    RenderOutput out;
    r.Render(scene, out);
    std::vector<int> values;
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x)
        if (out.label_at(x, y) >= kHandLabelBase) values.push_back(out.colour.pixel(x, y)[1]);
    EXPECT_GT(values.size(), 5000u);
    std::sort(values.begin(), values.end());
    double sum = 0.0;
    for (int v : values) sum += v;
    *mean = sum / static_cast<double>(values.size());
    return values[values.size() * 95 / 100] - values[values.size() * 5 / 100];
  };
  double mean_black = 0.0, mean_legible = 0.0;
  const int black_spread = brightness_spread(false, &mean_black);
  const int legible_spread = brightness_spread(true, &mean_legible);
  // Measured: black 1 level of spread around a mean of 1.1; legible 18 around 29.
  EXPECT_LE(black_spread, 4);
  EXPECT_LT(mean_black, 5.0);
  EXPECT_GT(legible_spread, 10);
  EXPECT_GT(mean_legible, 20.0);
}

// One pass for many silhouettes (the overlays' estimates): each object's bit of the OR-ed mask
// is exactly its own silhouette rendered alone, also where the objects overlap and occlude each
// other; pixels no object covers are 0.
TEST(Renderer, MasksOfOverlappingObjectsInOnePassAreTheirSilhouettes) {
  Renderer& r = SharedRenderer();
  const ObjectModel ketchup =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  const std::vector<int> meshes = UploadObject(r, ketchup);
  OverlayPainter painter(r, meshes);
  Scene scene;
  scene.K = Camera(320, 240);
  scene.T_PC = LookAt(Vec3(0.0, 0.0, 0.4), Vec3(0, 0, 0), Vec3::UnitY());
  std::vector<Transform> poses;
  for (int i = 0; i < 5; ++i)  // 8 mm and 6 deg apart: they overlap
    poses.push_back(
        MakeTransform(Vec3(0.008 * i, 0.003 * i, -0.01 * i), ExpSO3(Vec3(0.1 * i, 0.0, 0.05 * i))));
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const std::size_t first = scene.items.size();
    AddObject(scene, meshes, poses[i]);
    for (std::size_t k = first; k < scene.items.size(); ++k)
      scene.items[k].label = static_cast<std::uint16_t>(1u << i);
  }
  std::vector<std::uint16_t> bits;
  r.RenderMasks(scene, bits);
  ASSERT_EQ(bits.size(), 320u * 240u);
  long overlap = 0, covered = 0;
  std::vector<long> own(poses.size(), 0);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const std::vector<std::uint8_t> alone = painter.Silhouette(poses[i], scene.T_PC, scene.K);
    long differ = 0;
    for (std::size_t p = 0; p < bits.size(); ++p) {
      differ += ((bits[p] >> i) & 1u) != alone[p];
      own[i] += alone[p];
    }
    EXPECT_EQ(differ, 0) << "object " << i;
    EXPECT_GT(own[i], 2000) << "object " << i;
  }
  for (const std::uint16_t b : bits) overlap += __builtin_popcount(b) >= 2, covered += b != 0;
  EXPECT_GT(overlap, own[0] / 2);  // the test is about overlapping objects
  EXPECT_LT(covered, 320 * 240 / 2);
  EXPECT_EQ(bits[0], 0);
}

TEST(Renderer, TransparentBodyLetsTheBackgroundThrough) {
  Renderer& r = SharedRenderer();
  const ObjectModel water = LoadObjectModel(test::ProjectAsset("objects/water_bottle/object.json"));
  const std::vector<int> bottle = UploadObject(r, water);
  TriangleMesh wall = ConvexPiece::Box(Vec3(0.2, 0.2, 0.005), Transform::Identity()).ToMesh();
  wall.material.rgba = Eigen::Vector4d(0.9, 0.1, 0.1, 1.0);
  const int wall_id = r.AddMesh(wall);
  Scene scene;
  scene.K = Camera();
  scene.T_PC = LookAt(Vec3(0, -0.5, 0.1), Vec3(0, 0, 0.1), Vec3::UnitZ());
  scene.background = Vec3(0.1, 0.1, 0.9);
  scene.items.push_back({wall_id, MakeTransform(Vec3(0, 0.15, 0.1), ExpSO3(Vec3(M_PI / 2, 0, 0))),
                         7, std::nullopt, 1.0, false});
  AddObject(scene, bottle, Transform::Identity());
  RenderOutput out;
  r.Render(scene, out);
  // The body's middle (z = 0.1 m): red wall behind, seen through clear plastic.
  const Vec2 body = scene.K.Project(scene.T_PC.inverse() * Vec3(0.0, -0.02, 0.1));
  const std::uint8_t* px = out.colour.pixel(static_cast<int>(body.x()), static_cast<int>(body.y()));
  EXPECT_GT(px[0], 120);
  EXPECT_GT(px[0], px[1] + 60);
  EXPECT_GT(px[0], px[2] + 40);
  // Depth and label belong to the wall, not the transparent body.
  EXPECT_EQ(out.label_at(static_cast<int>(body.x()), static_cast<int>(body.y())), 7);
  EXPECT_NEAR(out.depth_at(static_cast<int>(body.x()), static_cast<int>(body.y())),
              0.5 + 0.15 - 0.005, 0.01);
  // The opaque cap is drawn in its own blue and owns its pixels.
  const Vec2 cap = scene.K.Project(scene.T_PC.inverse() * Vec3(0.0, -0.016, 0.222));
  EXPECT_EQ(out.label_at(static_cast<int>(cap.x()), static_cast<int>(cap.y())), kObjectLabel);
}

// The scene of the golden images: the project's hand around the ketchup bottle.
struct GoldenScene {
  HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  ObjectModel ketchup = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  HandMeshes hand_meshes;
  std::vector<int> object_meshes;
  KinematicsData kin{hand};
  Transform T_PO = MakeTransform(Vec3(-0.02, 0.05, 0.045),
                                 ExpSO3(Vec3(0, M_PI / 2, 0)) * ExpSO3(Vec3(0, 0, -0.4)));
  Scene scene;
  explicit GoldenScene(Renderer& r) {
    hand_meshes = UploadHand(r, hand);
    object_meshes = UploadObject(r, ketchup);
    Eigen::VectorXd q = Eigen::VectorXd::Constant(hand.num_q(), 0.7);
    for (const char* a : {"index_abduction", "middle_abduction", "ring_abduction"})
      q[hand.joints[hand.JointIndex(a)].q_index] = 0.0;
    q[hand.joints[hand.JointIndex("thumb_abduction")].q_index] = 0.3;
    kin.Update(hand, q);
    scene.K = Camera();
    scene.background = Vec3(0.85, 0.87, 0.9);
    scene.T_PC = LookAt(Vec3(0.12, -0.06, 0.24), Vec3(0, 0.05, 0.03), Vec3::UnitY());
    AddHand(scene, hand_meshes, kin.link_poses());
    AddObject(scene, object_meshes, T_PO);
  }
};

// Compares with tests/golden/NAME; INHAND_REGENERATE_GOLDEN=1 rewrites it. On failure the
// actual image and the difference heat map are written next to the build's test output.
void ExpectGolden(const Image8& actual, const std::string& name) {
  const std::string golden = test::SourceDir() + "/tests/golden/" + name;
  if (const char* regen = std::getenv("INHAND_REGENERATE_GOLDEN");
      regen && std::string(regen) == "1") {
    WriteImage(golden, actual);
    GTEST_SKIP() << "regenerated " << golden;
  }
  ASSERT_TRUE(std::filesystem::exists(golden))
      << golden << " missing: run with INHAND_REGENERATE_GOLDEN=1";
  const Image8 expected = ReadImage(golden);
  const ImageDiff diff = CompareImages(actual, expected, 12);
  if (diff.bad_fraction > 0.003 || diff.max_channel_delta > 96) {
    const std::string dir =
        std::filesystem::temp_directory_path().string() + "/inhand-golden-failures";
    std::filesystem::create_directories(dir);
    WriteImage(dir + "/actual_" + name, actual);
    WriteImage(dir + "/diff_" + name, diff.heatmap);
    FAIL() << name << ": " << diff.bad_fraction * 100
           << " % of pixels differ by more than 12, max delta " << diff.max_channel_delta
           << "; actual and diff written to " << dir;
  }
}

TEST(Golden, HandHoldingKetchup) {
  Renderer& r = SharedRenderer();
  GoldenScene g(r);
  RenderOutput a, b;
  r.Render(g.scene, a);
  r.Render(g.scene, b);
  EXPECT_EQ(a.colour.data, b.colour.data);  // bit-stable within a run
  ExpectGolden(a.colour, "hand_ketchup.png");
}

TEST(Golden, Fig1StyleOverlay) {
  Renderer& r = SharedRenderer();
  GoldenScene g(r);
  RenderOutput background;
  r.Render(g.scene, background);
  OverlayPainter painter(r, g.object_meshes);
  OverlayFrame frame;
  frame.camera = background.colour;
  frame.T_PC = g.scene.T_PC;
  frame.K = g.scene.K;
  OverlayEstimate truth{"truth", kColourTruth, g.T_PO, Mat3::Zero(), true, {}, {}};
  OverlayEstimate joints{"j",
                         kColourJoints,
                         MakeTransform(Vec3(0.012, -0.008, 0.01), Mat3::Identity()) * g.T_PO,
                         Mat3::Identity() * 1e-4,
                         false,
                         {},
                         {}};
  joints.contacts.push_back({OverlayContact::Kind::kKinematic, Vec3(0.0, 0.08, 0.07),
                             Vec3(0.0, 0.08, 0.07), Vec3(0, -1, 0), Vec3::Zero()});
  joints.contacts.push_back({OverlayContact::Kind::kTorque, Vec3(0.02, 0.06, 0.02),
                             Vec3(0.02, 0.06, 0.02), Vec3(0, 0, 1), Vec3(0, 0, 5)});
  OverlayEstimate features{"jtf",
                           kColourFeatures,
                           MakeTransform(Vec3(0.002, 0.001, 0.0), Mat3::Identity()) * g.T_PO,
                           Mat3::Identity() * 4e-6,
                           false,
                           {},
                           {}};
  features.features.push_back({Vec2(120, 140), Vec2(126, 137), true});
  features.features.push_back({Vec2(200, 90), Vec2(180, 100), false});
  frame.estimates = {truth, joints, features};
  frame.hud = {"t = 1.250 s   frame 37", "j: 14.2 mm / 6.1 deg"};
  const Image8 painted = painter.Paint(frame);
  // Every estimate is visible: its colour appears in the picture.
  for (const Rgb& c : {kColourJoints, kColourFeatures}) {
    long n = 0;
    for (int y = 0; y < painted.height; ++y)
      for (int x = 0; x < painted.width; ++x) {
        const std::uint8_t* p = painted.pixel(x, y);
        n += std::abs(p[0] - c.r) + std::abs(p[1] - c.g) + std::abs(p[2] - c.b) < 30;
      }
    EXPECT_GT(n, 100) << int(c.r) << "," << int(c.g) << "," << int(c.b);
  }
  ExpectGolden(painted, "overlay_fig1.png");
}

// A HUD line longer than the picture is wide (a set's error, σ, constraints and what its tracker
// says) breaks into lines that stay inside it: between clauses where it can, between words inside
// a clause too wide for a line of its own, never inside a word. Nothing is lost or reordered.
TEST(Overlay, LongHudLinesWrapInsideThePicture) {
  const std::string line =
      "jtf: 63.5 mm / 117.8 deg, sigma 10.1 mm / 9.3 deg, 1 constraint, object not matched in 14 "
      "frames";
  const auto joined = [](const std::vector<std::string>& pieces) {
    std::string all;
    for (const std::string& p : pieces)
      all += (all.empty() ? "" : " ") + p.substr(p.find_first_not_of(' '));
    return all;
  };
  EXPECT_EQ(WrapHudLine(line, 10000), std::vector<std::string>{line});
  EXPECT_EQ(WrapHudLine("", 100), std::vector<std::string>{""});
  const std::vector<std::string> clauses = WrapHudLine(line, 330);
  ASSERT_GE(clauses.size(), 2u);
  EXPECT_EQ(joined(clauses), line);
  for (std::size_t i = 0; i + 1 < clauses.size(); ++i)
    EXPECT_EQ(clauses[i].back(), ',') << clauses[i];
  for (std::size_t i = 1; i < clauses.size(); ++i)
    EXPECT_EQ(clauses[i].rfind("  ", 0), 0u) << clauses[i];
  const std::vector<std::string> words = WrapHudLine(line, 120);  // narrower than most clauses
  EXPECT_GT(words.size(), clauses.size());
  EXPECT_EQ(joined(words), line);
  EXPECT_EQ(WrapHudLine("unbreakable_word_wider_than_the_line", 20),
            std::vector<std::string>{"unbreakable_word_wider_than_the_line"});
  // Odd spacing and commas: no character but spaces is lost, added or moved.
  const auto squeezed = [](const std::string& text) {
    std::string out;
    for (const char c : text)
      if (c != ' ') out += c;
    return out;
  };
  for (const std::string odd :
       {"  ,  , x   y ,", " ", ", , ,", "a,b, c ,d", "  wide_word  wide_word_two , x"}) {
    std::string all;
    for (const std::string& piece : WrapHudLine(odd, 5)) all += piece;
    EXPECT_EQ(squeezed(all), squeezed(odd)) << "'" << odd << "'";
  }

  // Painted on a 320-pixel-wide picture: the HUD darkens its boxes, but not the right margin.
  Renderer& r = SharedRenderer();
  OverlayPainter painter(r, {});
  OverlayFrame frame;
  frame.K = Camera();
  frame.camera = Image8(frame.K.width, frame.K.height, 3);
  std::fill(frame.camera.data.begin(), frame.camera.data.end(), std::uint8_t{200});
  frame.hud = {"t = 1.250 s   frame 37", line};
  const Image8 painted = painter.Paint(frame);
  long darkened = 0, margin = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < painted.width; ++x) {
      const bool dark = painted.pixel(x, y)[0] < 200;
      darkened += dark;
      margin += dark && x >= painted.width - 4;
    }
  EXPECT_GT(darkened, 4000);
  EXPECT_EQ(margin, 0);
}

TEST(Video, H264FramesRoundTrip) {
  test::TempDir dir;
  const std::string path = dir / "v.mp4";
  {
    VideoWriter w(path, 30.0, 320, 240);
    for (int i = 0; i < 12; ++i) {
      Image8 frame(320, 240, 3);
      for (int y = 0; y < 240; ++y)
        for (int x = 0; x < 320; ++x)
          frame.pixel(x, y)[0] = static_cast<std::uint8_t>((x + 10 * i) % 256);
      w.Write(frame);
    }
    EXPECT_EQ(w.frames(), 12);
  }
  const test::VideoInfo info = test::ProbeVideo(path);
  EXPECT_EQ(info.frames, 12);
  EXPECT_EQ(info.width, 320);
  EXPECT_EQ(info.height, 240);
  EXPECT_TRUE(info.codec == "avc1" || info.codec == "h264") << info.codec;
  const Image8 f = test::ReadVideoFrame(path, 5);
  ASSERT_EQ(f.width, 320);
  EXPECT_NEAR(f.pixel(100, 100)[0], (100 + 50) % 256, 12);  // lossy, but close
  EXPECT_THROW(VideoWriter(dir / "odd.mp4", 30.0, 321, 240), InputError);
}

TEST(ImageCompare, CountsDifferencesAndRejectsSizeMismatch) {
  Image8 a(10, 10, 3), b(10, 10, 3);
  EXPECT_EQ(CompareImages(a, b, 0).max_channel_delta, 0);
  b.pixel(3, 4)[1] = 40;
  b.pixel(5, 5)[2] = 5;
  const ImageDiff d = CompareImages(a, b, 10);
  EXPECT_EQ(d.max_channel_delta, 40);
  EXPECT_EQ(d.bad_pixels, 1);
  EXPECT_DOUBLE_EQ(d.bad_fraction, 0.01);
  EXPECT_GT(d.heatmap.pixel(3, 4)[0], 100);
  EXPECT_THROW(CompareImages(a, Image8(10, 11, 3), 0), InputError);
}

// The GUI's layout: the main image untouched at its size, the column's two images at half its
// height on its right (uniform colours keep their value through the resize), a caption too long
// for a column panel broken onto a second line inside it.
TEST(Overlay, MainAndColumnKeepsTheMainImageAndStacksTheOthers) {
  Image8 main(64, 48, 3), top(64, 48, 3), bottom(32, 24, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) main.pixel(x, y)[c] = static_cast<std::uint8_t>(x + y + 10 * c);
  std::fill(top.data.begin(), top.data.end(), 200);
  std::fill(bottom.data.begin(), bottom.data.end(), 90);
  const Image8 all = MainAndColumn(main, {&top, &bottom});
  ASSERT_EQ(all.width, 96);
  ASSERT_EQ(all.height, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      ASSERT_EQ(all.pixel(x, y)[1], main.pixel(x, y)[1]) << x << " " << y;
  EXPECT_EQ(all.pixel(80, 12)[0], 200);
  EXPECT_EQ(all.pixel(80, 36)[0], 90);
  // Captions: one bar over the main image, two lines over the narrow top panel.
  const Image8 captioned = MainAndColumn(Image8(400, 300, 3), {&top, &bottom},
                                         {"main", "a caption far too long for one line", ""});
  const auto dark_rows = [&](int x) {
    int rows = 0;
    while (rows < captioned.height && captioned.pixel(x, rows)[0] == 30) ++rows;
    return rows;
  };
  EXPECT_EQ(dark_rows(399), 20);
  EXPECT_GE(dark_rows(598), 36);
  EXPECT_EQ(captioned.pixel(598, 200)[0], 90);
}

}  // namespace
}  // namespace inhand
