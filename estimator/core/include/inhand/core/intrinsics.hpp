#pragma once
// Pinhole camera. Conventions (shared with the renderer and features):
//  - camera frame C: x right, y down, z forward (OpenCV);
//  - pixel (u, v) = (fx x/z + cx, fy y/z + cy) with integer values at pixel centres, so the
//    top-left pixel's centre is (0, 0) and the image spans [-0.5, width - 0.5];
//  - distortion (k1, k2, p1, p2, k3) in OpenCV's model, applied to measured pixels only:
//    the estimator works on undistorted pixels.
#include <array>
#include <string>

#include "inhand/core/so3.hpp"

namespace inhand {

struct Intrinsics {
  int width = 640;                                            // [px]
  int height = 480;                                           // [px]
  double fx = 525.0;                                          // [px]
  double fy = 525.0;                                          // [px]
  double cx = 319.5;                                          // [px]
  double cy = 239.5;                                          // [px]
  std::array<double, 5> distortion{0.0, 0.0, 0.0, 0.0, 0.0};  // k1 k2 p1 p2 k3

  // Throws InputError naming `context` and the field when a value is impossible.
  void Validate(const std::string& context) const;

  bool HasDistortion() const;

  // X_C in the camera frame, z > 0.
  Vec2 Project(const Vec3& X_C) const;
  // ∂(u, v)/∂X_C, 2×3.
  Eigen::Matrix<double, 2, 3> ProjectJacobian(const Vec3& X_C) const;
  // The point at depth z (along the optical axis, not the ray length) seen at pixel uv.
  Vec3 Unproject(const Vec2& uv, double z) const;
  bool Contains(const Vec2& uv) const;

  // Distortion model: undistorted normalized (x, y) → distorted pixel, and its inverse
  // (fixed-point iteration, converges for the mild distortion of real lenses).
  Vec2 Distort(const Vec2& uv_undistorted) const;
  Vec2 Undistort(const Vec2& uv_distorted) const;
};

}  // namespace inhand
