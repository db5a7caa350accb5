#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/features/extracted.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/renderer/views.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

struct Pair {
  ObjectModel object = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  Renderer renderer;
  std::vector<int> meshes = UploadObject(renderer, object);
  Intrinsics K = IntrinsicsFromFov(640, 480, 40);
  Transform T_PC = LookAt(Vec3(0.02, -0.32, 0.16), Vec3(0, 0, 0.09), Vec3::UnitZ());
  RenderOutput Render(const Transform& T_PO, const PixelRect& region = {}) {
    Scene s;
    s.K = K;
    s.T_PC = T_PC;
    s.background = Vec3(0.45, 0.5, 0.55);
    s.region = region;
    AddObject(s, meshes, T_PO);
    RenderOutput out;
    renderer.Render(s, out, true);
    return out;
  }
};

// The tracker draws the virtual view only around the object (DrawnRegion) and matches only as
// far around it as the search reaches (SearchRegion). On a plain background, where every edge
// lies well inside, the matches are those of the whole images, to the bit: the same pixels, the
// same inliers, the same similarity. The view drawn around the object has the whole view's
// pixels there and the background elsewhere.
TEST(ExtractedFeatures, ARegionAroundTheObjectMatchesAsTheWholeImages) {
  Pair p;
  const Transform T_true = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, 0.15)));
  const Transform T_est =
      MakeTransform(Vec3(0.004, -0.002, 0.003), ExpSO3(Vec3(0.01, -0.015, 0.02))) * T_true;
  const Aabb b = p.object.Bounds();
  Eigen::AlignedBox2d box;
  for (int i = 0; i < 8; ++i)
    box.extend(p.K.Project(p.T_PC.inverse() * T_est *
                           Vec3(i & 1 ? b.max.x() : b.min.x(), i & 2 ? b.max.y() : b.min.y(),
                                i & 4 ? b.max.z() : b.min.z())));
  const FeatureParams params;
  const PixelRect search = SearchRegion(box, params, 640, 480);
  const PixelRect drawn = DrawnRegion(box, params, 640, 480);
  ASSERT_FALSE(search.empty());
  EXPECT_LT(search.width() * search.height(), 640 * 480 / 2);
  EXPECT_TRUE(search.x0 <= drawn.x0 && search.y0 <= drawn.y0 && drawn.x1 <= search.x1 &&
              drawn.y1 <= search.y1);
  const RenderOutput real = p.Render(T_true);
  const RenderOutput whole = p.Render(T_est);
  const RenderOutput part = p.Render(T_est, drawn);
  const auto mask_of = [](const RenderOutput& v) {
    std::vector<std::uint8_t> mask(v.label.size());
    for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = v.label[i] == kObjectLabel;
    return mask;
  };
  const std::vector<std::uint8_t> mask_whole = mask_of(whole), mask_part = mask_of(part);
  EXPECT_EQ(mask_whole, mask_part);  // the object lies within the drawn region
  const MatchResult a = MatchFeatures(real.colour, whole.colour, &mask_whole, params);
  const MatchResult c =
      MatchFeatures(real.colour, part.colour, &mask_part, params, nullptr, true, search);
  ASSERT_GE(a.num_inliers(), 6);
  ASSERT_EQ(a.matches.size(), c.matches.size());
  for (std::size_t i = 0; i < a.matches.size(); ++i) {
    EXPECT_EQ(a.matches[i].virtual_px, c.matches[i].virtual_px) << i;
    EXPECT_EQ(a.matches[i].real_px, c.matches[i].real_px) << i;
    EXPECT_EQ(a.matches[i].inlier, c.matches[i].inlier) << i;
  }
  EXPECT_LT((a.debug.similarity - c.debug.similarity).norm(), 1e-9);
  EXPECT_EQ(a.debug.virtual_edges.data, c.debug.virtual_edges.data);
  // A region wholly outside the images reads nothing and finds nothing, with edge images of the
  // images' size (the matching views draw them).
  const MatchResult outside = MatchFeatures(real.colour, part.colour, &mask_part, params, nullptr,
                                            true, PixelRect{700, 0, 800, 100});
  EXPECT_TRUE(outside.matches.empty());
  EXPECT_TRUE(outside.debug.virtual_corners.empty());
  EXPECT_EQ(outside.debug.real_edges.width, 640);
  EXPECT_EQ(outside.debug.virtual_edges.height, 480);
  // The camera's edges are the whole image's within the region, zero outside it.
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      const bool inside = x >= search.x0 && x < search.x1 && y >= search.y0 && y < search.y1;
      ASSERT_EQ(c.debug.real_edges.pixel(x, y)[0], inside ? a.debug.real_edges.pixel(x, y)[0] : 0)
          << x << "," << y;
    }
}

TEST(ExtractedFeatures, MatchingRecoversAKnownPoseOffsetAndTheUpdateRemovesIt) {
  Pair p;
  const Transform T_true = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, 0.15)));
  const Transform T_est =
      MakeTransform(Vec3(0.004, -0.002, 0.003), ExpSO3(Vec3(0.01, -0.015, 0.02))) * T_true;
  const RenderOutput real = p.Render(T_true);
  const RenderOutput virt = p.Render(T_est);
  std::vector<std::uint8_t> mask(virt.label.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = virt.label[i] == kObjectLabel;
  const MatchResult r = MatchFeatures(real.colour, virt.colour, &mask, FeatureParams());
  ASSERT_GE(r.num_inliers(), 6) << r.matches.size() << " matches";
  // Every stage reported what it did.
  EXPECT_EQ(r.debug.real_edges.width, 640);
  EXPECT_FALSE(r.debug.virtual_corners.empty());
  EXPECT_EQ(r.debug.pieces.size(), r.debug.virtual_corners.size());

  // The matched pixel is where the object point seen at the virtual pixel really projects.
  std::vector<double> errors;
  std::vector<VisualFeature> features;
  const Transform T_CP = p.T_PC.inverse();
  for (const FeatureMatch& m : r.matches) {
    if (!m.inlier) continue;
    const int x = static_cast<int>(std::lround(m.virtual_px.x())),
              y = static_cast<int>(std::lround(m.virtual_px.y()));
    const float z = virt.depth_at(x, y);
    if (!std::isfinite(z)) continue;
    const Vec3 X_P = p.T_PC * p.K.Unproject(m.virtual_px, z);
    const Vec3 x_O = T_est.inverse() * X_P;
    const Vec2 truth = p.K.Project(T_CP * (T_true * x_O));
    errors.push_back((truth - m.real_px).norm());
    features.push_back({m.id, x_O, m.real_px});
  }
  ASSERT_GE(errors.size(), 6u);
  std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2),
                   errors.end());
  EXPECT_LT(errors[errors.size() / 2], 1.5) << "median pixel error of the matches";

  // The visual update removes most of the offset.
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  BulletContactQuery query(hand, p.object);
  FilterParams params;
  params.pixel_sigma = 1.5;
  Filter filter(hand, query, params, FilterOptions{false});
  filter.Reset(T_est, Eigen::VectorXd::Zero(hand.num_q()), StartSigmas{0.02, 0.087, 0.0, {}});
  const double before = (T_est.translation() - T_true.translation()).norm();
  const double rot_before = RotationDistance(T_est.linear(), T_true.linear());
  EXPECT_GE(filter.UpdateVisual(features, p.T_PC, p.K), 6);
  const double after = (filter.position() - T_true.translation()).norm();
  const double rot_after = RotationDistance(filter.rotation(), T_true.linear());
  std::cout << "  " << r.num_inliers() << " inliers of " << r.matches.size()
            << " matches, median error " << errors[errors.size() / 2] << " px; position error "
            << before * 1000 << " -> " << after * 1000 << " mm, orientation "
            << rot_before * 180 / M_PI << " -> " << rot_after * 180 / M_PI << " deg\n";
  EXPECT_LT(after, 0.5 * before) << before << " -> " << after;
  EXPECT_LT(rot_after, rot_before) << rot_before << " -> " << rot_after;
}

// Step 0: an estimate 30 mm off sideways puts the virtual object about 60 px from the camera's,
// twice the local search. One shift of the whole object finds it (the projected offset of the
// object's centre, within 5 px: the edges' best shift also absorbs the small rotation), and the
// local searches around it then match as near ones do;
// without step 0 the local searches find nothing true.
TEST(ExtractedFeatures, AGlobalShiftBridgesAnOffsetBeyondTheLocalSearch) {
  Pair p;
  const Transform T_true = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, 0.15)));
  const Vec3 side = p.T_PC.linear().col(0);  // the camera's x axis, in P
  const Transform T_est =
      MakeTransform(0.03 * side + Vec3(0, 0, 0.004), ExpSO3(Vec3(0.01, -0.01, 0.02))) * T_true;
  const RenderOutput real = p.Render(T_true), virt = p.Render(T_est);
  std::vector<std::uint8_t> mask(virt.label.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = virt.label[i] == kObjectLabel;
  const Vec3 centre_O = p.object.Bounds().Center();
  const Transform T_CP = p.T_PC.inverse();
  const Vec2 offset =
      p.K.Project(T_CP * (T_true * centre_O)) - p.K.Project(T_CP * (T_est * centre_O));
  ASSERT_GT(offset.norm(), 50.0) << "the offset must lie beyond the local search";
  // The median pixel error of the inliers against where their object points really project.
  const auto median_error = [&](const MatchResult& r) {
    std::vector<double> errors;
    for (const FeatureMatch& m : r.matches) {
      if (!m.inlier) continue;
      const float z = virt.depth_at(static_cast<int>(std::lround(m.virtual_px.x())),
                                    static_cast<int>(std::lround(m.virtual_px.y())));
      if (!std::isfinite(z)) continue;
      const Vec3 x_O = T_est.inverse() * (p.T_PC * p.K.Unproject(m.virtual_px, z));
      errors.push_back((p.K.Project(T_CP * (T_true * x_O)) - m.real_px).norm());
    }
    if (errors.empty()) return std::numeric_limits<double>::infinity();
    std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2),
                     errors.end());
    return errors[errors.size() / 2];
  };
  FeatureParams local;
  const MatchResult near = MatchFeatures(real.colour, virt.colour, &mask, local);
  EXPECT_FALSE(std::isfinite(near.debug.global_cost)) << "step 0 runs only when asked";
  EXPECT_TRUE(near.num_inliers() < 3 || median_error(near) > 5.0)
      << near.num_inliers() << " inliers, median error " << median_error(near);
  FeatureParams global;
  global.global_search_radius = 90;
  const MatchResult far = MatchFeatures(real.colour, virt.colour, &mask, global);
  std::cout << "  offset (" << offset.transpose() << ") px, step 0 shift ("
            << far.debug.global_shift.transpose() << "), chamfer " << far.debug.global_cost
            << " px (unshifted " << far.debug.global_cost_unshifted << "); " << far.num_inliers()
            << " inliers, median error " << median_error(far) << " px\n";
  EXPECT_LT((far.debug.global_shift - offset).norm(), 5.0);
  EXPECT_LT(far.debug.global_cost, 0.5 * far.debug.global_cost_unshifted);
  ASSERT_GE(far.num_inliers(), 6);
  EXPECT_LT(median_error(far), 1.5);
  FeatureParams bad = global;
  bad.global_truncation = 0.5;
  EXPECT_THROW(MatchFeatures(real.colour, virt.colour, &mask, bad), InputError);
}

// Step 0's chamfer cost, against a brute-force one: with one orientation bin (every edge agrees
// with every other), the mean over the virtual edge pixels (every stride-th of them in row order,
// at most 1500) of the distance to the nearest camera edge pixel, searched pixel by pixel within
// the truncation and cut there, and the truncation for a pixel shifted out of the image. At the
// shift step 0 found and unshifted, both agree to float precision (step 0 computes distance
// transforms only around the object; those must be the whole image's).
TEST(ExtractedFeatures, TheGlobalShiftsCostIsTheBruteForceChamfer) {
  Pair p;
  const Transform T_true = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, 0.15)));
  const Transform T_est =
      MakeTransform(0.03 * p.T_PC.linear().col(0), ExpSO3(Vec3(0.01, -0.01, 0.02))) * T_true;
  const RenderOutput real = p.Render(T_true), virt = p.Render(T_est);
  FeatureParams q;
  q.orientation_bins = 1;
  q.global_search_radius = 90;
  const MatchResult r = MatchFeatures(real.colour, virt.colour, nullptr, q);
  const Image8& re = r.debug.real_edges;
  const Image8& ve = r.debug.virtual_edges;
  const int W = re.width, H = re.height, T = static_cast<int>(q.global_truncation);
  std::vector<Eigen::Vector2i> all;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (ve.data[static_cast<std::size_t>(y * W + x)]) all.emplace_back(x, y);
  ASSERT_GT(all.size(), 200u);
  const std::size_t stride = (all.size() + 1499) / 1500;
  const auto chamfer = [&](int sx, int sy) {
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < all.size(); i += stride, ++n) {
      const int x = all[i].x() + sx, y = all[i].y() + sy;
      double d = q.global_truncation;
      if (x >= 0 && y >= 0 && x < W && y < H)
        for (int dy = -T; dy <= T; ++dy)
          for (int dx = -T; dx <= T; ++dx) {
            const int u = x + dx, v = y + dy;
            if (u >= 0 && v >= 0 && u < W && v < H && re.data[static_cast<std::size_t>(v * W + u)])
              d = std::min(d, std::hypot(dx, dy));
          }
      sum += d;
    }
    return sum / static_cast<double>(n);
  };
  const int sx = static_cast<int>(r.debug.global_shift.x()),
            sy = static_cast<int>(r.debug.global_shift.y());
  EXPECT_GT(std::hypot(sx, sy), 40.0);
  EXPECT_NEAR(r.debug.global_cost, chamfer(sx, sy), 1e-5);
  EXPECT_NEAR(r.debug.global_cost_unshifted, chamfer(0, 0), 1e-5);
  EXPECT_LT(r.debug.global_cost, 0.5 * r.debug.global_cost_unshifted);
}

// Corners near an occluder (a finger across the object) are junctions of its edges with the
// object's: none is kept within occluder_clearance of it; without the occluder some are.
TEST(ExtractedFeatures, CornersNearAnOccluderAreRejected) {
  Pair p;
  const RenderOutput a = p.Render(Transform::Identity());
  std::vector<std::uint8_t> mask(a.label.size()), band(a.label.size(), 0);
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = a.label[i] == kObjectLabel;
  // The band: the object's rows between a third and two thirds of its height in the image.
  int top = a.height, bottom = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      if (mask[std::size_t(y) * a.width + x]) top = std::min(top, y), bottom = std::max(bottom, y);
  const int y0 = top + (bottom - top) / 3, y1 = top + 2 * (bottom - top) / 3;
  for (int y = y0; y <= y1; ++y)
    for (int x = 0; x < a.width; ++x) band[std::size_t(y) * a.width + x] = 255;
  FeatureParams params;
  const auto near_band = [&](const Vec2& c) {
    return c.y() >= y0 - params.occluder_clearance && c.y() <= y1 + params.occluder_clearance;
  };
  const MatchResult free = MatchFeatures(a.colour, a.colour, &mask, params);
  EXPECT_TRUE(
      std::any_of(free.debug.virtual_corners.begin(), free.debug.virtual_corners.end(), near_band));
  const MatchResult occluded = MatchFeatures(a.colour, a.colour, &mask, params, &band);
  EXPECT_FALSE(occluded.debug.virtual_corners.empty());
  EXPECT_FALSE(std::any_of(occluded.debug.virtual_corners.begin(),
                           occluded.debug.virtual_corners.end(), near_band));
}

TEST(ExtractedFeatures, IdenticalImagesMatchInPlaceAndBadParametersAreRejected) {
  Pair p;
  const RenderOutput a = p.Render(Transform::Identity());
  std::vector<std::uint8_t> mask(a.label.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = a.label[i] == kObjectLabel;
  const MatchResult r = MatchFeatures(a.colour, a.colour, &mask, FeatureParams());
  ASSERT_GT(r.num_inliers(), 3);
  for (const FeatureMatch& m : r.matches)
    if (m.inlier) {
      EXPECT_LT((m.real_px - m.virtual_px).norm(), 0.5);
    }
  FeatureParams bad;
  bad.canny_high = 10;
  EXPECT_THROW(MatchFeatures(a.colour, a.colour, &mask, bad), InputError);
}

}  // namespace
}  // namespace inhand
