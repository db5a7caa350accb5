// The camera is not our renderer: CameraSimulator on the real renderer (lens distortion, cast
// shadows, vignetting, exposure and sensor noise, motion blur).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "inhand/core/error.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/camera_sim.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

Intrinsics SmallCamera() {
  Intrinsics K;
  K.width = 320;
  K.height = 240;
  K.fx = K.fy = 290.0;
  K.cx = 159.5;
  K.cy = 119.5;
  return K;
}

int FlatBox(Renderer& r, const Vec3& half, const Eigen::Vector4d& rgba) {
  TriangleMesh m = ConvexPiece::Box(half, Transform::Identity()).ToMesh();
  m.material.rgba = rgba;
  return r.AddMesh(m);
}

double Linear(std::uint8_t v) { return std::pow(v / 255.0, 2.2); }

TEST(CameraSimulator, LensDistortionMovesPointsWhereItsCoefficientsSay) {
  Renderer renderer;
  Intrinsics K = SmallCamera();
  RealismParams p;
  K.distortion = p.distortion;
  CameraSimulator camera(renderer, K, p, Effects::Parse("camera.distortion", "test"), LightRig(),
                         1);
  EXPECT_GT(camera.margin(), 5);
  Scene scene;
  scene.K = SmallCamera();
  scene.T_PC = Transform::Identity();
  const int square = FlatBox(renderer, Vec3(0.003, 0.003, 0.0005), Eigen::Vector4d(1, 1, 1, 1));
  const std::vector<Vec2> ideal = {{30, 25},   {290, 25},  {30, 215},
                                   {290, 215}, {160, 120}, {100, 60}};
  for (const Vec2& u : ideal)
    scene.items.push_back({square, MakeTransform(scene.K.Unproject(u, 0.5), Mat3::Identity()), 1,
                           std::nullopt, 1.0, true});
  Image8 out;
  camera.Capture({scene}, out);
  for (const Vec2& u : ideal) {
    const Vec2 expected = K.Distort(u);
    double w = 0.0;
    Vec2 c = Vec2::Zero();
    for (int y = static_cast<int>(expected.y()) - 10; y <= static_cast<int>(expected.y()) + 10; ++y)
      for (int x = static_cast<int>(expected.x()) - 10; x <= static_cast<int>(expected.x()) + 10;
           ++x) {
        if (x < 0 || y < 0 || x >= K.width || y >= K.height) continue;
        const double v = Linear(out.pixel(x, y)[1]);
        w += v;
        c += v * Vec2(x, y);
      }
    ASSERT_GT(w, 1.0) << "nothing seen near " << expected.transpose();
    c /= w;
    EXPECT_LT((c - expected).norm(), 0.3) << "ideal " << u.transpose() << " expected "
                                          << expected.transpose() << " seen " << c.transpose();
    if ((u - Vec2(160, 120)).norm() > 150) {
      EXPECT_GT((expected - u).norm(), 5.0);  // the lens moves the corners
    }
  }
}

// Where the segment a-b meets the axis-aligned box [lo, hi] (slab test).
bool SegmentHitsBox(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double d = b[i] - a[i];
    if (std::abs(d) < 1e-12) {
      if (a[i] < lo[i] || a[i] > hi[i]) return false;
      continue;
    }
    double u = (lo[i] - a[i]) / d, v = (hi[i] - a[i]) / d;
    if (u > v) std::swap(u, v);
    t0 = std::max(t0, u);
    t1 = std::min(t1, v);
    if (t0 > t1) return false;
  }
  return true;
}

TEST(CameraSimulator, CastShadowsWhereTheLampIsOccluded) {
  Renderer renderer;
  const Intrinsics K = SmallCamera();
  LightRig light;
  light.lamp = Vec3(0, 0, 1.0);
  light.lamp_target = Vec3(0, 0, 0);
  CameraSimulator camera(renderer, K, RealismParams(), Effects::Parse("camera.light", "test"),
                         light, 1);
  Scene scene;
  scene.K = K;
  scene.T_PC = LookAt(Vec3(0.5, 0.05, 0.9), Vec3(0, 0, 0), Vec3::UnitZ());
  const Vec3 half(0.05, 0.05, 0.01), centre(0, 0, 0.3);
  scene.items.push_back({FlatBox(renderer, Vec3(0.5, 0.5, 0.01), Eigen::Vector4d(0.7, 0.7, 0.7, 1)),
                         MakeTransform(Vec3(0, 0, -0.01), Mat3::Identity()), 1, std::nullopt, 1.0,
                         false});
  scene.items.push_back({FlatBox(renderer, half, Eigen::Vector4d(0.3, 0.3, 0.8, 1)),
                         MakeTransform(centre, Mat3::Identity()), 2, std::nullopt, 1.0, false});
  const std::vector<float> rgb = camera.Radiance(scene);
  const int m = camera.margin(), W = K.width + 2 * m;
  double shadow = 0.0, lit = 0.0;
  int n_shadow = 0, n_lit = 0;
  for (int y = 0; y < K.height; ++y)
    for (int x = 0; x < K.width; ++x) {
      // The table point this pixel sees (skipping pixels whose ray meets the box first).
      const Vec3 eye = scene.T_PC.translation();
      const Vec3 dir = scene.T_PC.linear() * K.Unproject(Vec2(x, y), 1.0);
      if (dir.z() >= 0) continue;
      const Vec3 P = eye + dir * (-eye.z() / dir.z());
      if (std::abs(P.x()) > 0.45 || std::abs(P.y()) > 0.45) continue;
      const Vec3 grow(0.01, 0.01, 0.01);
      if (SegmentHitsBox(eye, P, centre - half - grow, centre + half + grow)) continue;
      const double g = rgb[3 * (std::size_t(y + m) * W + x + m) + 1];
      if (SegmentHitsBox(P, light.lamp, centre - half + grow, centre + half - grow)) {
        shadow += g;
        ++n_shadow;
      } else if (!SegmentHitsBox(P, light.lamp, centre - half - 2 * grow,
                                 centre + half + 2 * grow) &&
                 P.norm() < 0.2) {
        lit += g;
        ++n_lit;
      }
    }
  ASSERT_GT(n_shadow, 200);
  ASSERT_GT(n_lit, 200);
  shadow /= n_shadow;
  lit /= n_lit;
  EXPECT_LT(shadow, 0.35 * lit) << "shadow " << shadow << " lit " << lit;
  EXPECT_GT(shadow, 0.0);  // ambient and fill light remain
}

Scene GreyWall(Renderer& renderer, const Intrinsics& K, double grey) {
  Scene scene;
  scene.K = K;
  scene.items.push_back({FlatBox(renderer, Vec3(2, 2, 0.01), Eigen::Vector4d(grey, grey, grey, 1)),
                         MakeTransform(Vec3(0, 0, 1.0), Mat3::Identity()), 1, std::nullopt, 1.0,
                         true});
  return scene;
}

double MeanLinear(const Image8& img, int x0, int y0, int size, int channel,
                  double* stddev = nullptr) {
  double s = 0.0, s2 = 0.0;
  for (int y = y0; y < y0 + size; ++y)
    for (int x = x0; x < x0 + size; ++x) {
      const double v = Linear(img.pixel(x, y)[channel]);
      s += v;
      s2 += v * v;
    }
  const double n = double(size) * size, mean = s / n;
  if (stddev) *stddev = std::sqrt(std::max(0.0, s2 / n - mean * mean));
  return mean;
}

TEST(CameraSimulator, VignettingDarkensTheCornersByItsAmount) {
  Renderer renderer;
  const Intrinsics K = SmallCamera();
  RealismParams p;
  CameraSimulator camera(renderer, K, p, Effects::Parse("camera.vignetting", "test"), LightRig(),
                         1);
  Image8 out;
  camera.Capture({GreyWall(renderer, K, 0.8)}, out);
  const double centre = MeanLinear(out, 155, 115, 10, 1), corner = MeanLinear(out, 0, 0, 3, 1);
  const double r2 =
      (Vec2(1, 1) - Vec2(K.cx, K.cy)).squaredNorm() / (0.25 * (320.0 * 320 + 240.0 * 240));
  EXPECT_NEAR(corner / centre, 1.0 - p.vignetting * r2, 0.02);
}

TEST(CameraSimulator, ExposureDriftsFromFrameToFrameAndSensorNoiseFollowsTheSignal) {
  Renderer renderer;
  const Intrinsics K = SmallCamera();
  RealismParams p;
  CameraSimulator camera(
      renderer, K, p, Effects::Parse("camera.exposure,camera.sensor_noise", "test"), LightRig(), 4);
  const Scene wall = GreyWall(renderer, K, 0.7);
  std::vector<double> log_means;
  double noise_ratio = 0.0;
  for (int f = 0; f < 40; ++f) {
    Image8 out;
    camera.Capture({wall}, out);
    double sd = 0.0;
    const double mean = MeanLinear(out, 100, 80, 60, 1, &sd);
    log_means.push_back(std::log(mean));
    // Shot noise sqrt(e) and read noise in electrons, at this frame's signal (quantisation adds a
    // little).
    const double e = mean * p.full_well;
    noise_ratio += sd / (std::sqrt(e + p.read_noise * p.read_noise) / p.full_well) / 40.0;
  }
  double m = 0.0, v = 0.0;
  for (double l : log_means) m += l / log_means.size();
  for (double l : log_means) v += (l - m) * (l - m) / (log_means.size() - 1);
  EXPECT_GT(std::sqrt(v), 0.03);
  EXPECT_LT(std::sqrt(v), 0.16);  // exposure 0.08 and the green channel's white balance 0.03
  EXPECT_NEAR(noise_ratio, 1.0, 0.15);
}

TEST(CameraSimulator, MotionBlurAveragesTheSubFrames) {
  Renderer renderer;
  const Intrinsics K = SmallCamera();
  CameraSimulator camera(renderer, K, RealismParams(), Effects::Parse("camera.motion_blur", "test"),
                         LightRig(), 1);
  const int square = FlatBox(renderer, Vec3(0.02, 0.02, 0.001), Eigen::Vector4d(1, 1, 1, 1));
  std::vector<Scene> frames;
  for (int i = 0; i < 3; ++i) {  // 10 px apart at 0.5 m
    Scene s;
    s.K = K;
    s.items.push_back({square, MakeTransform(Vec3(i * 10 * 0.5 / K.fx, 0, 0.5), Mat3::Identity()),
                       1, std::nullopt, 1.0, true});
    frames.push_back(s);
  }
  const auto partial = [&](const Image8& img) {
    int n = 0;
    for (int x = 0; x < K.width; ++x) {
      const double v = Linear(img.pixel(x, 120)[1]);
      n += v > 0.2 && v < 0.8;
    }
    return n;
  };
  Image8 blurred, sharp;
  camera.Capture(frames, blurred);
  camera.Capture({frames.back()}, sharp);
  EXPECT_LE(partial(sharp), 2);
  EXPECT_GE(partial(blurred), 18);  // two steps of 10 px at 1/3 and 2/3 on both edges
}

}  // namespace
}  // namespace inhand
