#include "inhand/core/intrinsics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {
void Require(bool ok, const std::string& context, const std::string& field, double value,
             const char* expected) {
  if (ok) return;
  std::ostringstream os;
  os << context << ": camera intrinsics field '" << field << "' is " << value << ", expected "
     << expected;
  throw InputError(os.str());
}
}  // namespace

void Intrinsics::Validate(const std::string& context) const {
  Require(width > 0 && width <= 16384, context, "width", width, "an integer in [1, 16384]");
  Require(height > 0 && height <= 16384, context, "height", height, "an integer in [1, 16384]");
  Require(std::isfinite(fx) && fx > 0.0, context, "fx", fx, "a finite value > 0");
  Require(std::isfinite(fy) && fy > 0.0, context, "fy", fy, "a finite value > 0");
  Require(std::isfinite(cx), context, "cx", cx, "a finite value");
  Require(std::isfinite(cy), context, "cy", cy, "a finite value");
  for (std::size_t i = 0; i < distortion.size(); ++i) {
    Require(std::isfinite(distortion[i]), context, "distortion[" + std::to_string(i) + "]",
            distortion[i], "a finite value");
  }
  // The model means a lens only where it can be inverted: the distorted radius r (1 + k1 r² +
  // k2 r⁴ + k3 r⁶) must grow with the undistorted radius r until it has passed the image's
  // farthest corner (normalised), and there differ from r by less than a factor of 2 (beyond,
  // the lens is a fisheye, which this model does not describe). Tangential terms of real lenses
  // are thousandths.
  const auto& [k1, k2, p1, p2, k3] = distortion;
  Require(std::abs(p1) <= 1.0, context, "distortion[2]", p1, "p1 in [-1, 1]");
  Require(std::abs(p2) <= 1.0, context, "distortion[3]", p2, "p2 in [-1, 1]");
  const double corner = std::hypot(std::max(cx + 0.5, width - 0.5 - cx) / fx,
                                   std::max(cy + 0.5, height - 0.5 - cy) / fy);
  // Walks r outwards (steps of 1e-3, up to 10) to where r_d reaches the corner.
  bool covers = false;
  for (int i = 0; i <= 10000; ++i) {
    const double r = 1e-3 * i, r2 = r * r;
    if (!(1.0 + r2 * (3.0 * k1 + r2 * (5.0 * k2 + r2 * 7.0 * k3)) > 0.0))
      break;  // d(r_d)/dr: folds over
    const double factor = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    if (r * factor < corner) continue;
    covers = factor >= 0.5 && factor <= 2.0;
    break;
  }
  if (!covers) {
    std::ostringstream os;
    os << context << ": camera intrinsics field 'distortion' is (" << k1 << ", " << k2 << ", " << p1
       << ", " << p2 << ", " << k3
       << "), expected a radial distortion that can be inverted over the whole image (r (1 + k1 "
          "r^2 + k2 r^4 + k3 r^6)"
       << " growing with r up to the corner's normalised radius " << corner
       << ", there within a factor of 2 of r)";
    throw InputError(os.str());
  }
}

bool Intrinsics::HasDistortion() const {
  for (double d : distortion)
    if (d != 0.0) return true;
  return false;
}

Vec2 Intrinsics::Project(const Vec3& X_C) const {
  return Vec2(fx * X_C.x() / X_C.z() + cx, fy * X_C.y() / X_C.z() + cy);
}

Eigen::Matrix<double, 2, 3> Intrinsics::ProjectJacobian(const Vec3& X_C) const {
  const double iz = 1.0 / X_C.z();
  Eigen::Matrix<double, 2, 3> J;
  J << fx * iz, 0.0, -fx * X_C.x() * iz * iz, 0.0, fy * iz, -fy * X_C.y() * iz * iz;
  return J;
}

Vec3 Intrinsics::Unproject(const Vec2& uv, double z) const {
  return Vec3((uv.x() - cx) / fx * z, (uv.y() - cy) / fy * z, z);
}

bool Intrinsics::Contains(const Vec2& uv) const {
  return uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() <= width - 0.5 && uv.y() <= height - 0.5;
}

Vec2 Intrinsics::Distort(const Vec2& uv) const {
  const double x = (uv.x() - cx) / fx, y = (uv.y() - cy) / fy;
  const auto& [k1, k2, p1, p2, k3] = distortion;
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  return Vec2(fx * xd + cx, fy * yd + cy);
}

Vec2 Intrinsics::Undistort(const Vec2& uv_d) const {
  if (!HasDistortion()) return uv_d;
  const double xd = (uv_d.x() - cx) / fx, yd = (uv_d.y() - cy) / fy;
  const auto& [k1, k2, p1, p2, k3] = distortion;
  double x = xd, y = yd;
  for (int it = 0; it < 20; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    x = (xd - dx) / radial;
    y = (yd - dy) / radial;
  }
  return Vec2(fx * x + cx, fy * y + cy);
}

}  // namespace inhand
