#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "inhand/core/error.hpp"
#include "inhand/core/intrinsics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

Intrinsics Camera() {
  Intrinsics K;
  K.width = 640;
  K.height = 480;
  K.fx = 610.0;
  K.fy = 605.0;
  K.cx = 321.3;
  K.cy = 238.7;
  return K;
}

Eigen::Matrix<double, 2, 3> NumericJacobian(const Intrinsics& K, const Vec3& X) {
  Eigen::Matrix<double, 2, 3> J;
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-7 * std::max(1.0, std::abs(X[i]));
    Vec3 a = X, b = X;
    a[i] += h;
    b[i] -= h;
    J.col(i) = (K.Project(a) - K.Project(b)) / (2 * h);
  }
  return J;
}

TEST(Intrinsics, ProjectionJacobianMatchesFiniteDifferences) {
  const Intrinsics K = Camera();
  // Centre, image border, and grazing depth (a point far off-axis, close to the camera).
  const std::vector<Vec3> points = {Vec3(0.0, 0.0, 0.5),     Vec3(0.26, 0.19, 0.5),
                                    Vec3(-0.26, -0.19, 0.5), Vec3(0.4, 0.0, 0.05),
                                    Vec3(0.01, -0.3, 0.02),  Vec3(0.1, 0.1, 3.0)};
  for (const Vec3& X : points) {
    const auto J = K.ProjectJacobian(X);
    const auto N = NumericJacobian(K, X);
    EXPECT_LT((J - N).norm(), 1e-5 * std::max(1.0, J.norm())) << X.transpose();
  }
}

TEST(Intrinsics, PixelCentresAndUnprojection) {
  const Intrinsics K = Camera();
  EXPECT_LT((K.Project(Vec3(0, 0, 1)) - Vec2(K.cx, K.cy)).norm(), 1e-12);
  const Vec3 X(0.05, -0.02, 0.7);
  EXPECT_LT((K.Unproject(K.Project(X), X.z()) - X).norm(), 1e-12);
  EXPECT_TRUE(K.Contains(Vec2(-0.5, -0.5)));
  EXPECT_TRUE(K.Contains(Vec2(639.5, 479.5)));
  EXPECT_FALSE(K.Contains(Vec2(639.6, 10)));
}

TEST(Intrinsics, UndistortInvertsDistort) {
  Intrinsics K = Camera();
  K.distortion = {-0.21, 0.08, 0.001, -0.0007, -0.01};
  for (const Vec2& uv : {Vec2(10, 10), Vec2(320, 240), Vec2(600, 450), Vec2(100, 400)}) {
    EXPECT_LT((K.Undistort(K.Distort(uv)) - uv).norm(), 1e-6) << uv.transpose();
  }
  // Without coefficients both are the identity.
  const Intrinsics plain = Camera();
  EXPECT_FALSE(plain.HasDistortion());
  EXPECT_EQ(plain.Undistort(Vec2(1, 2)), Vec2(1, 2));
}

TEST(Intrinsics, ValidateNamesTheField) {
  Intrinsics K = Camera();
  K.fx = 0.0;
  try {
    K.Validate("cam.json");
    FAIL() << "fx = 0 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cam.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'fx'"), std::string::npos);
  }
  K = Camera();
  K.height = -3;
  EXPECT_THROW(K.Validate("x"), InputError);
  K = Camera();
  K.distortion[2] = std::nan("");
  EXPECT_THROW(K.Validate("x"), InputError);
}

// Distortion that a lens can have passes (the realistic profile's, OpenCV's calibration of a
// wide lens); coefficients under which the model folds over inside the image, or that are
// corrupt, are refused with the field: Undistort could not invert them.
TEST(Intrinsics, ValidateRefusesDistortionThatCannotBeInverted) {
  Intrinsics K = Camera();
  for (const std::array<double, 5>& d :
       std::vector<std::array<double, 5>>{{-0.21, 0.08, 0.001, -0.0007, -0.01},
                                          {-0.35, 0.15, 0.0, 0.0, -0.03},
                                          {0.1, -0.02, 0.0, 0.0, 0.0},
                                          {0, 0, 0, 0, 0}}) {
    K.distortion = d;
    EXPECT_NO_THROW(K.Validate("x")) << d[0];
    // and Undistort does invert them at the image's corner
    const Vec2 corner(K.width - 0.5, K.height - 0.5);
    EXPECT_LT((K.Distort(K.Undistort(corner)) - corner).norm(), 1e-3) << d[0];
  }
  for (const std::array<double, 5>& d : std::vector<std::array<double, 5>>{{1e6, 0, 0, 0, 0},
                                                                           {0, 0, 0, 0, -1e6},
                                                                           {-2.0, 0, 0, 0, 0},
                                                                           {0, 0, 1e6, 0, 0},
                                                                           {0, 0, 0, -2.0, 0}}) {
    K.distortion = d;
    try {
      K.Validate("cam.json");
      ADD_FAILURE() << "accepted " << d[0] << " " << d[2] << " " << d[3] << " " << d[4];
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cam.json: camera intrinsics field 'distortion"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace inhand
