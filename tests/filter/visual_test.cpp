// The filter's visual update: features of one frame sharing the camera's error, the model floor,
// the camera error kept across frames, widening and relocating the pose.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "fixtures.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/contact_model.hpp"

namespace inhand {
namespace {

using namespace filter_test;  // NOLINT: the fixtures of this folder

// Forty object points seen by a camera whose recorded pose is 1.5 mm off along its x axis: the
// pixels say the object is 1.5 mm off the other way. Fused as independent features, the filter
// believes them to 0.2 mm; with the camera's σ (2 mm per axis) shared by the frame's features
// it keeps ~2 mm of doubt along that axis, and with a negligible camera σ (the camera error in
// the state) it equals the paper's independent features.
TEST(Filter, FeaturesOfOneFrameShareTheCameraError) {
  FingerScene s;
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  const Transform T_PC_true = T_PC * MakeTransform(Vec3(0.0015, 0, 0), Mat3::Identity());
  const std::vector<VisualFeature> features = FeaturesSeenFrom(T_PC_true, K, p);
  const auto fused = [&](double camera_sigma) {
    FilterParams params;
    params.pixel_sigma = 2.0;
    params.visual_gate_chi2 = 0.0;
    params.camera_position_sigma = camera_sigma;
    params.camera_orientation_sigma = 0.0;
    params.visual_model_sigma = 0.0;  // the paper's independent features
    Filter f = s.Started(At(p), params, false);
    EXPECT_EQ(f.UpdateVisual(features, T_PC, K), 40);
    return f;
  };
  const Vec3 axis = T_PC.linear().col(0);
  const auto sigma_along = [&](const Filter& f) {
    return std::sqrt(axis.dot(f.covariance().topLeftCorner<3, 3>() * axis));
  };
  const Filter independent = fused(0.0), shared = fused(0.002), nearly = fused(1e-9);
  EXPECT_LT(sigma_along(independent), 0.0003);
  EXPECT_GT(sigma_along(shared), 0.0015);
  EXPECT_LT(sigma_along(shared), 0.0021);
  EXPECT_LT((nearly.position() - independent.position()).norm(), 1e-9);
  EXPECT_LT((nearly.covariance() - independent.covariance()).cwiseAbs().maxCoeff(), 1e-12);
  // Both move the object by the 1.5 mm the pixels show (against the camera's shift; the prior's
  // 20 mm leaves no reason not to), the shared one a little less far.
  const double moved_independent = -axis.dot(independent.position() - p),
               moved_shared = -axis.dot(shared.position() - p);
  EXPECT_NEAR(moved_independent, 0.0015, 0.0001);
  EXPECT_GT(moved_shared, 0.0012);
  EXPECT_LT(moved_shared, moved_independent);
}

// visual_model_sigma: 40 features a frame over 10 frames cannot make a feature's pixel known
// better than the floor (the independent features of the paper would claim 0.3 mm after one),
// and the floor gives back no more than needed to reach it.
TEST(Filter, VisualModelSigmaBoundsWhatFramesOfFeaturesCanKnow) {
  FingerScene s;
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  const std::vector<VisualFeature> features = FeaturesSeenFrom(T_PC, K, p);
  FilterParams params;
  params.pixel_sigma = 2.0;
  params.visual_gate_chi2 = 0.0;
  params.visual_model_sigma = 4.0;
  Filter f = s.Started(At(p), params, false);
  for (int frame = 0; frame < 10; ++frame) EXPECT_EQ(f.UpdateVisual(features, T_PC, K), 40);
  // Along the camera's x axis a position error moves every pixel alike: its σ in pixels is the
  // floor's, up to the share the orientation takes of each feature's variance.
  const Vec3 axis = T_PC.linear().col(0);
  const double z = (T_PC.inverse() * p).z();
  const double sigma_px =
      K.fx / z * std::sqrt(axis.dot(f.covariance().topLeftCorner<3, 3>() * axis));
  EXPECT_GT(sigma_px, 0.5 * params.visual_model_sigma);
  EXPECT_LT(sigma_px, 1.5 * params.visual_model_sigma);
  EXPECT_NEAR(f.position().x(), p.x(), 1e-9);  // exact pixels: no bias from the floor
}

// The camera's error is a state of its own, constant over frames: with the object pose known
// (σ 1 µm), the pixels of a camera 1.5 mm off are explained by the camera, which the filter
// keeps for the next frame (its pixels need no correction); the object does not move.
TEST(Filter, TheCameraErrorIsEstimatedAndKeptAcrossFrames) {
  FingerScene s;
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  const Vec3 offset(0.0015, 0, 0);
  const Transform T_PC_true = T_PC * MakeTransform(offset, Mat3::Identity());
  const std::vector<VisualFeature> features = FeaturesSeenFrom(T_PC_true, K, p);
  FilterParams params;
  params.pixel_sigma = 1.0;
  params.camera_position_sigma = 0.002;
  params.camera_orientation_sigma = 0.5 * M_PI / 180;
  Filter f(s.hand, s.query, params, FilterOptions{false});
  f.Reset(At(p), s.q0, StartSigmas{1e-6, 1e-6, 1e-9, {}});
  EXPECT_EQ(f.UpdateVisual(features, T_PC, K), 40);
  // At 0.4 m a 1.5 mm shift and a 0.2 deg turn of the camera look alike: ξ is some mix of both.
  EXPECT_GT(f.camera_error().head<3>().dot(offset) / offset.norm() +
                0.4 * f.camera_error().tail<3>().norm(),
            0.001);
  EXPECT_LT((f.position() - p).norm(), 1e-5);
  // The next frame's pixels are already explained: nothing left to correct.
  f.Predict(s.q0, 0.1);
  f.UpdateVisual(features, T_PC, K);
  for (const auto& v : f.trace().visual) EXPECT_LT((v.measured - v.predicted).norm(), 0.2);
}

// The trace keeps each point's depth at the prior beside its measured and predicted pixels, so a
// caller can tell how far the image puts the object: with the camera 3 mm off across its axis,
// every residual × depth / fx is 3 mm (to the pinhole's second order), and the depth is the
// point's z in the camera.
TEST(Filter, TheTraceGivesEachPointsDepthForTheDisplacement) {
  FingerScene s;
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  const Transform T_PC_true = T_PC * MakeTransform(Vec3(0.003, 0, 0), Mat3::Identity());
  const std::vector<VisualFeature> features = FeaturesSeenFrom(T_PC_true, K, p);
  Filter f = s.Started(At(p), FilterParams(), false);
  f.UpdateVisual(features, T_PC, K);
  ASSERT_EQ(f.trace().visual.size(), features.size());
  for (std::size_t i = 0; i < features.size(); ++i) {
    const FilterTrace::Visual& v = f.trace().visual[i];
    const Vec3 X_C = T_PC.inverse() * (p + features[i].x_O);
    EXPECT_NEAR(v.depth, X_C.z(), 1e-12);
    EXPECT_NEAR((v.measured - v.predicted).norm() * v.depth / K.fx, 0.003, 0.0002);
  }
}

// A turn about a declared symmetry axis (parallel to the object's x, 10 mm beside its origin) is
// what no image of a solid of revolution shows. 24 features on two rims around that axis, seen
// with the object turned 3° about it: without the symmetry the filter turns the estimate by nearly
// the 3° (it takes them for fixed points of the surface); with it, the estimate stays where it
// was, the information along the turn is what it was before, and a shift across the axis is still
// measured in full. Features flagged as outline points are fused whole.
TEST(Filter, ATurnAboutTheSymmetryAxisIsNotMeasured) {
  FingerScene s;
  const Intrinsics K = TestIntrinsics();
  const Vec3 p(0.0, 0.06, 0.04);
  const Transform T_PC = CameraLookingAt(p);
  const Vec3 c_O(0.0, 0.01, 0.0);
  const Vec3 axis_O = Vec3::UnitX();
  std::vector<Vec3> rims;
  for (double x : {-0.04, 0.04})
    for (int k = 0; k < 12; ++k)
      rims.push_back(c_O + Vec3(x, 0.012 * std::cos(0.5236 * k), 0.012 * std::sin(0.5236 * k)));
  const auto seen = [&](const Transform& T_PO_true, bool on_outline = false) {
    std::vector<VisualFeature> features;
    for (const Vec3& x_O : rims)
      features.push_back({static_cast<int>(features.size()), x_O,
                          K.Project(T_PC.inverse() * (T_PO_true * x_O)), on_outline});
    return features;
  };
  const double turn = 3.0 * M_PI / 180;
  const Transform turned = At(p) * MakeTransform(c_O, Mat3::Identity()) *
                           MakeTransform(Vec3::Zero(), ExpSO3(turn * axis_O)) *
                           MakeTransform(-c_O, Mat3::Identity());
  FilterParams params;
  params.pixel_sigma = 1.0;
  params.visual_gate_chi2 = 0.0;
  params.visual_model_sigma = 0.0;
  const auto fused = [&](bool symmetric, const std::vector<VisualFeature>& features) {
    FilterOptions options;
    if (symmetric) options.symmetry_axis_O = axis_O, options.symmetry_point_O = c_O;
    Filter f(s.hand, s.query, params, options);
    f.Reset(At(p), s.q0, StartSigmas{0.02, 0.087, 1e-9, {}});
    EXPECT_EQ(f.UpdateVisual(features, T_PC, K), static_cast<int>(features.size()));
    return f;
  };
  const auto turn_of = [](const Filter& f) {
    const Mat3 R = f.rotation();
    return std::atan2(R(2, 1), R(1, 1));
  };
  const Filter plain = fused(false, seen(turned)), symmetric = fused(true, seen(turned));
  EXPECT_GT(turn_of(plain), 0.8 * turn);
  EXPECT_LT(std::abs(turn_of(symmetric)), 0.01 * turn);
  // The turn moves the origin 0.52 mm; what is left of it is its second order.
  EXPECT_NEAR((turned.translation() - p).norm(), 0.00052, 0.00001);
  EXPECT_LT((symmetric.position() - p).norm(), 0.1 * (turned.translation() - p).norm());
  // The information along the turn (δp, δθ) = (-a × c, a) is the prior's; across it, it grew.
  Eigen::Matrix<double, 6, 1> v, w;
  v << -axis_O.cross(c_O), axis_O;
  w << 0, 1, 0, 0, 0, 0;
  const Filter prior = fused(true, {});
  const auto information = [](const Filter& f, const Eigen::Matrix<double, 6, 1>& d) {
    return d.dot(f.covariance().topLeftCorner<6, 6>().inverse() * d);
  };
  EXPECT_NEAR(information(symmetric, v), information(prior, v), 1e-6 * information(prior, v));
  EXPECT_GT(information(symmetric, w), 100.0 * information(prior, w));
  // A shift of 1 mm across the axis is seen with the symmetry as without it.
  const Transform shifted = MakeTransform(p + Vec3(0, 0, 0.001), Mat3::Identity());
  const double moved = fused(true, seen(shifted)).position().z() - p.z();
  EXPECT_NEAR(moved, 0.001, 0.0001);
  EXPECT_NEAR(moved, fused(false, seen(shifted)).position().z() - p.z(), 0.00005);
  // Outline points (grazing points, which the turn moves along the line of sight) are fused whole:
  // the same update as without the symmetry.
  const Filter outline = fused(true, seen(turned, true));
  EXPECT_EQ(outline.rotation(), plain.rotation());
  EXPECT_EQ(outline.position(), plain.position());
}

// WidenPose adds σ² to each axis of the pose's variance and nothing elsewhere; a negative or
// non-finite σ is refused.
TEST(Filter, WidenPoseAddsToThePoseVarianceOnly) {
  FingerScene s;
  Filter f = s.Started(At(Vec3(0.0, 0.06, 0.04)), FilterParams(), false);
  const Eigen::MatrixXd before = f.covariance();
  f.WidenPose(0.03, 0.1);
  Eigen::MatrixXd added = f.covariance() - before;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(added(i, i), 0.03 * 0.03, 1e-15);
  for (int i = 3; i < 6; ++i) EXPECT_NEAR(added(i, i), 0.1 * 0.1, 1e-15);
  added.diagonal().head<6>().setZero();
  EXPECT_EQ(added.cwiseAbs().maxCoeff(), 0.0);
  for (const auto& [sp, so] :
       std::vector<std::pair<double, double>>{{-0.01, 0.0}, {0.0, std::nan("")}, {INFINITY, 0.0}})
    EXPECT_THROW(f.WidenPose(sp, so), InputError);
}

// Relocate puts the object at the given pose with the given covariance; the pose forgets its
// correlations, the biases keep their own variance; the contacts that moved the object with the
// fingers are dropped (the next Predict leaves it where it was put). A covariance that is not
// symmetric positive definite, or a pose that is not finite, is refused.
TEST(Filter, RelocatePutsTheObjectWhereItWasMeasured) {
  FingerScene s;
  Filter f =
      s.Started(At(Vec3(0.0, 0.07, 0.025)), PerfectContacts(), false);  // penetrating: a contact
  f.Predict(s.q0, 0.001);
  f.UpdateContacts(Eigen::Vector2d::Zero());
  ASSERT_FALSE(f.state().active.empty());
  ASSERT_GT(f.covariance().block(0, 6, 6, 2).cwiseAbs().maxCoeff(),
            0.0);  // the pose is correlated with the biases
  const Eigen::MatrixXd bias_block = f.covariance().bottomRightCorner(2, 2);
  const Transform T = MakeTransform(Vec3(0.01, 0.2, -0.03), ExpSO3(Vec3(0.3, -2.0, 0.5)));
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  const Mat6 C = A * A.transpose() * 1e-4 + Mat6::Identity() * 1e-6;
  f.Relocate(T, C);
  EXPECT_LT((f.position() - T.translation()).norm(), 1e-15);
  EXPECT_LT((f.rotation() - T.linear()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((f.covariance().topLeftCorner<6, 6>() - C).cwiseAbs().maxCoeff(), 1e-18);
  EXPECT_EQ(f.covariance().block(0, 6, 6, 2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(f.covariance().block(6, 0, 2, 6).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(f.covariance().bottomRightCorner(2, 2), bias_block);
  EXPECT_TRUE(f.state().active.empty());
  f.Predict(Eigen::Vector2d(0.2, 0.1), 0.001);  // the finger moves; nothing holds the object
  EXPECT_LT((f.position() - T.translation()).norm(), 1e-15);
  Mat6 asymmetric = C;
  asymmetric(0, 1) += 1e-3;
  for (const Mat6& bad : {Mat6(-C), asymmetric, Mat6(Mat6::Zero()), Mat6(C * std::nan(""))})
    EXPECT_THROW(f.Relocate(T, bad), InputError);
  Transform not_finite = T;
  not_finite.translation().x() = INFINITY;
  EXPECT_THROW(f.Relocate(not_finite, C), InputError);
}

}  // namespace
}  // namespace inhand
