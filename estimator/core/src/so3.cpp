#include "inhand/core/so3.hpp"

#include <Eigen/SVD>
#include <cmath>

#include "inhand/core/error.hpp"

namespace inhand {

void CheckFailed(const char* condition, const char* file, int line, const std::string& message) {
  std::fprintf(stderr, "inhand: internal check failed at %s:%d: %s (%s)\n", file, line, condition,
               message.c_str());
  std::abort();
}

Mat3 Skew(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return S;
}

Mat3 ExpSO3(const Vec3& omega) {
  const double theta2 = omega.squaredNorm();
  const Mat3 W = Skew(omega);
  double a, b;  // R = I + a W + b W²
  if (theta2 < 1e-16) {
    a = 1.0 - theta2 / 6.0;
    b = 0.5 - theta2 / 24.0;
  } else {
    const double theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  return Mat3::Identity() + a * W + b * W * W;
}

Vec3 LogSO3(const Mat3& R) {
  Quat q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Vec3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-8) {
    // θ ≈ 2 s / w: first-order term with the cubic correction of atan.
    const double w = q.w();
    return (2.0 / w - (2.0 / 3.0) * s * s / (w * w * w)) * v;
  }
  const double theta = 2.0 * std::atan2(s, q.w());
  return (theta / s) * v;
}

double RotationDistance(const Mat3& R_a, const Mat3& R_b) {
  return LogSO3(R_a * R_b.transpose()).norm();
}

Mat3 RotationFromRpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

Vec3 RpyFromRotation(const Mat3& R) {
  // R = Rz(y) Ry(p) Rx(r): R(2,0) = -sin p.
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double roll, yaw;
  if (std::abs(std::cos(pitch)) > 1e-9) {
    roll = std::atan2(R(2, 1), R(2, 2));
    yaw = std::atan2(R(1, 0), R(0, 0));
  } else {  // gimbal lock: put everything in yaw
    roll = 0.0;
    yaw = std::atan2(-R(0, 1), R(1, 1));
  }
  return Vec3(roll, pitch, yaw);
}

Transform MakeTransform(const Vec3& p, const Mat3& R) {
  Transform T = Transform::Identity();
  T.linear() = R;
  T.translation() = p;
  return T;
}

Transform MakeTransform(const Vec3& p, const Quat& q) {
  return MakeTransform(p, q.normalized().toRotationMatrix());
}

Mat3 Orthonormalize(const Mat3& R) {
  Eigen::JacobiSVD<Mat3> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3 V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) = -U.col(2);
  return U * V.transpose();
}

}  // namespace inhand
