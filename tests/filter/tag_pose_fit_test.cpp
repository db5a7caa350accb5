#include "inhand/filter/tag_pose_fit.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "inhand/io/object_loader.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

// The tags' own fit of the object's pose, on corners projected exactly from a known pose (the
// ketchup bottle's two tags, a 640x480 camera 35 cm away): from a guess 120° and 40 mm off, one
// tag's corners or both tags' give that pose back (the best fit, squared error ~0), and its
// covariance is σ² (HᵀH)⁻¹ with H from central differences of the projection. No corners, or not
// four per tag: no fit.
TEST(TagPoseFit, TheFitOfTheCornersIsThePoseThatProjectedThem) {
  const ObjectModel object =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  ASSERT_EQ(object.tags.size(), 2u);
  Intrinsics K;
  K.width = 640;
  K.height = 480;
  K.fx = K.fy = 580.0;
  K.cx = 319.5;
  K.cy = 239.5;
  const Transform truth = MakeTransform(Vec3(0.02, 0.0, 0.08), ExpSO3(Vec3(0.1, 0.2, 0.3)));
  Mat3 R_PC;  // looking along +y, image rows along -z
  R_PC.col(0) = Vec3::UnitX();
  R_PC.col(1) = -Vec3::UnitZ();
  R_PC.col(2) = Vec3::UnitY();
  const Transform T_PC = MakeTransform(truth.translation() + Vec3(0.01, -0.35, 0.1), R_PC);
  Transform guess = truth;
  guess.linear() = ExpSO3(Vec3(0.0, 120.0 * M_PI / 180, 0.0)) * guess.linear();
  guess.translation() += Vec3(0.04, 0.0, 0.0);
  const auto pixels = [&](const Vec3& p, const Mat3& R, const std::vector<VisualFeature>& corners) {
    Eigen::VectorXd out(2 * corners.size());
    for (std::size_t i = 0; i < corners.size(); ++i)
      out.segment<2>(2 * static_cast<long>(i)) =
          K.Project(T_PC.inverse() * (p + R * corners[i].x_O));
    return out;
  };
  const double sigma = 4.0;
  for (const std::size_t count : {std::size_t{1}, std::size_t{2}}) {
    SCOPED_TRACE(std::to_string(count) + " tag(s)");
    std::vector<VisualFeature> corners;
    for (std::size_t t = 0; t < count; ++t) {
      const auto c = object.tags[t].CornersO();
      for (int i = 0; i < 4; ++i)
        corners.push_back({object.tags[t].id * 4 + i, c[static_cast<std::size_t>(i)],
                           K.Project(T_PC.inverse() * (truth * c[static_cast<std::size_t>(i)]))});
    }
    std::vector<TagPoseFit> fits;
    FitTagPoses(object, corners, T_PC, K, guess, sigma, fits);
    ASSERT_FALSE(fits.empty());
    const TagPoseFit& best = fits.front();
    EXPECT_LT(best.cost, 1e-12);
    EXPECT_LT((best.T_PO.translation() - truth.translation()).norm(), 1e-8);
    EXPECT_LT(RotationDistance(best.T_PO.linear(), truth.linear()), 1e-7);
    for (std::size_t i = 1; i < fits.size(); ++i) EXPECT_GE(fits[i].cost, fits[i - 1].cost);
    Eigen::MatrixXd H(2 * corners.size(), 6);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d[k] = h;
      const auto at = [&](const Vec6& e) {
        return pixels(truth.translation() + e.head<3>(), ExpSO3(e.tail<3>()) * truth.linear(),
                      corners);
      };
      H.col(k) = (at(d) - at(-d)) / (2 * h);
    }
    const Mat6 expected = (H.transpose() * H).inverse() * sigma * sigma;
    EXPECT_LT((best.covariance - expected).norm(), 1e-4 * expected.norm());
  }
  std::vector<TagPoseFit> fits;
  FitTagPoses(object, {}, T_PC, K, guess, sigma, fits);
  EXPECT_TRUE(fits.empty());
  const auto c = object.tags[0].CornersO();
  FitTagPoses(object,
              {{0, c[0], Vec2(300, 200)}, {1, c[1], Vec2(320, 200)}, {2, c[2], Vec2(320, 220)}},
              T_PC, K, guess, sigma, fits);
  EXPECT_TRUE(fits.empty());
}

}  // namespace
}  // namespace inhand
