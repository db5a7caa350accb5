#include <gtest/gtest.h>

#include <cmath>

#include "inhand/core/so3.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

Vec3 RandomUnit() {
  std::normal_distribution<double> n(0.0, 1.0);
  auto& rng = test::Rng();
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

TEST(So3, SkewIsCrossProduct) {
  for (int i = 0; i < 50; ++i) {
    const Vec3 a = RandomUnit() * 3.0, b = RandomUnit() * 0.5;
    EXPECT_LT((Skew(a) * b - a.cross(b)).norm(), 1e-15);
  }
}

TEST(So3, ExpIsARotationAndMatchesAngleAxis) {
  std::uniform_real_distribution<double> angle(0.0, M_PI);
  for (int i = 0; i < 200; ++i) {
    const Vec3 axis = RandomUnit();
    const double th = angle(test::Rng());
    const Mat3 R = ExpSO3(th * axis);
    EXPECT_LT((R * R.transpose() - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    EXPECT_LT((R - Eigen::AngleAxisd(th, axis).toRotationMatrix()).norm(), 1e-14);
  }
}

TEST(So3, LogInvertsExpIncludingDegenerateAngles) {
  std::uniform_real_distribution<double> angle(0.0, M_PI - 1e-6);
  for (int i = 0; i < 500; ++i) {
    const Vec3 w = RandomUnit() * angle(test::Rng());
    EXPECT_LT((LogSO3(ExpSO3(w)) - w).norm(), 1e-9) << w.transpose();
  }
  // Identity and tiny angles: no division by zero, first order exact.
  EXPECT_EQ(LogSO3(Mat3::Identity()).norm(), 0.0);
  for (double tiny : {1e-14, 1e-10, 1e-7}) {
    const Vec3 w = RandomUnit() * tiny;
    EXPECT_LT((LogSO3(ExpSO3(w)) - w).norm(), 1e-20 + 1e-9 * tiny);
  }
  // Exactly π: the axis comes back up to sign, with angle π.
  for (const Vec3& axis :
       {Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY()), Vec3(Vec3::UnitZ()), RandomUnit()}) {
    const Vec3 w = LogSO3(ExpSO3(M_PI * axis));
    EXPECT_NEAR(w.norm(), M_PI, 1e-9);
    EXPECT_NEAR(std::abs(w.normalized().dot(axis)), 1.0, 1e-9);
    EXPECT_LT((ExpSO3(w) - ExpSO3(M_PI * axis)).norm(), 1e-9);
  }
}

TEST(So3, RotationDistanceIsTheAngleBetween) {
  const Mat3 A = ExpSO3(Vec3(0.3, -0.2, 0.9));
  const Vec3 axis = RandomUnit();
  EXPECT_NEAR(RotationDistance(ExpSO3(0.7 * axis) * A, A), 0.7, 1e-12);
  EXPECT_NEAR(RotationDistance(A, A), 0.0, 1e-12);
}

TEST(So3, RpyRoundTripAndUrdfConvention) {
  // URDF: rotation about fixed X by roll, then fixed Y by pitch, then fixed Z by yaw.
  const Vec3 rpy(0.3, -0.4, 1.2);
  const Mat3 expected = Eigen::AngleAxisd(1.2, Vec3::UnitZ()).toRotationMatrix() *
                        Eigen::AngleAxisd(-0.4, Vec3::UnitY()).toRotationMatrix() *
                        Eigen::AngleAxisd(0.3, Vec3::UnitX()).toRotationMatrix();
  EXPECT_LT((RotationFromRpy(rpy) - expected).norm(), 1e-15);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int i = 0; i < 100; ++i) {
    const Vec3 r(u(test::Rng()) * 2, u(test::Rng()), u(test::Rng()) * 2);
    EXPECT_LT((RpyFromRotation(RotationFromRpy(r)) - r).norm(), 1e-12);
  }
  // Gimbal lock: the rotation still round-trips.
  const Mat3 locked = RotationFromRpy(Vec3(0.2, M_PI / 2, 0.5));
  EXPECT_LT((RotationFromRpy(RpyFromRotation(locked)) - locked).norm(), 1e-9);
}

TEST(So3, OrthonormalizeProjectsOntoSO3) {
  const Mat3 R = ExpSO3(Vec3(0.1, 0.2, 0.3));
  Mat3 noisy = R;
  noisy(0, 1) += 1e-4;
  const Mat3 P = Orthonormalize(noisy);
  EXPECT_LT((P * P.transpose() - Mat3::Identity()).norm(), 1e-14);
  EXPECT_LT((P - R).norm(), 2e-4);
}

}  // namespace
}  // namespace inhand
