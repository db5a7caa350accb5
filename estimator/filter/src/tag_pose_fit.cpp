#include "inhand/filter/tag_pose_fit.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "inhand/filter/contact_model.hpp"

namespace inhand {

namespace {

// Gauss-Newton on the pose (δp, δθ in the palm frame, the filter's error state) over the corners'
// pixels; the squared error at the end and HᵀH there.
double RefinePose(const std::vector<VisualFeature>& corners, const Transform& T_PC,
                  const Intrinsics& K, Vec3& p, Mat3& R, Mat6& HtH) {
  const Transform T_CP = T_PC.inverse();
  double cost = 0.0;
  for (int it = 0; it < 30; ++it) {
    HtH.setZero();
    Vec6 Htr = Vec6::Zero();
    cost = 0.0;
    for (const VisualFeature& c : corners) {
      const Vec3 X_P = p + R * c.x_O;
      const Vec3 X_C = T_CP * X_P;
      if (!(X_C.z() > 1e-3)) return std::numeric_limits<double>::infinity();  // behind the camera
      const Vec2 r = c.pixel - K.Project(X_C);
      const Eigen::Matrix<double, 2, 6> H = VisualMeasurementJacobian(X_P, p, T_PC, K);
      HtH.noalias() += H.transpose() * H;
      Htr.noalias() += H.transpose() * r;
      cost += r.squaredNorm();
    }
    const Vec6 d = (HtH + 1e-9 * Mat6::Identity()).ldlt().solve(Htr);
    if (!d.allFinite()) return std::numeric_limits<double>::infinity();
    p += d.head<3>();
    R = ExpSO3(d.tail<3>()) * R;
    if (d.head<3>().norm() < 1e-7 && d.tail<3>().norm() < 1e-6) break;
  }
  cost = 0.0;
  for (const VisualFeature& c : corners) {
    const Vec3 X_C = T_CP * (p + R * c.x_O);
    if (!(X_C.z() > 1e-3)) return std::numeric_limits<double>::infinity();
    cost += (c.pixel - K.Project(X_C)).squaredNorm();
  }
  return cost;
}

// The tag's pose in the camera from the homography of its four corners (DLT on normalized image
// coordinates), R = [r1 r2 r1×r2] made orthonormal.
bool HomographyPose(const std::array<Vec2, 4>& plane, const std::array<Vec2, 4>& pixels,
                    const Intrinsics& K, Transform& T_CT) {
  Eigen::Matrix<double, 8, 9> A;
  for (int i = 0; i < 4; ++i) {
    const double x = plane[i].x(), y = plane[i].y();
    const double u = (pixels[i].x() - K.cx) / K.fx, v = (pixels[i].y() - K.cy) / K.fy;
    A.row(2 * i) << x, y, 1, 0, 0, 0, -u * x, -u * y, -u;
    A.row(2 * i + 1) << 0, 0, 0, x, y, 1, -v * x, -v * y, -v;
  }
  const Eigen::JacobiSVD<Eigen::Matrix<double, 8, 9>> svd(A, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> h = svd.matrixV().col(8);
  Mat3 H;
  H << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8];
  double scale = 2.0 / (H.col(0).norm() + H.col(1).norm());
  if (!std::isfinite(scale)) return false;
  if (H(2, 2) * scale < 0.0) scale = -scale;  // in front of the camera
  Mat3 M;
  M.col(0) = scale * H.col(0);
  M.col(1) = scale * H.col(1);
  M.col(2) = M.col(0).cross(M.col(1));
  T_CT = Transform::Identity();
  T_CT.linear() = Orthonormalize(M);
  T_CT.translation() = scale * H.col(2);
  return T_CT.matrix().allFinite();
}

}  // namespace

void FitTagPoses(const ObjectModel& object, const std::vector<VisualFeature>& corners,
                 const Transform& T_PC, const Intrinsics& K, const Transform& T_PO_guess,
                 double pixel_sigma, std::vector<TagPoseFit>& fits) {
  fits.clear();
  if (corners.size() < 4 || corners.size() % 4 != 0) return;
  struct Candidate {
    Vec3 p;
    Mat3 R;
    Mat6 HtH;
    double cost;
  };
  std::vector<Candidate> found;
  const auto refine = [&](const Transform& T_PO) {
    Candidate c{T_PO.translation(), Orthonormalize(T_PO.linear()), Mat6::Zero(), 0.0};
    c.cost = RefinePose(corners, T_PC, K, c.p, c.R, c.HtH);
    if (std::isfinite(c.cost)) found.push_back(c);
  };
  refine(T_PO_guess);
  for (std::size_t first = 0; first < corners.size(); first += 4) {
    const int id = corners[first].id / 4;
    const TagPlacement* tag = nullptr;
    for (const TagPlacement& t : object.tags)
      if (t.id == id) tag = &t;
    if (tag == nullptr) continue;
    const double h = 0.5 * tag->size;
    const std::array<Vec2, 4> plane = {Vec2(-h, -h), Vec2(h, -h), Vec2(h, h),
                                       Vec2(-h, h)};  // CornersO's order
    std::array<Vec2, 4> pixels;
    for (int c = 0; c < 4; ++c)
      pixels[static_cast<std::size_t>(c)] = corners[first + static_cast<std::size_t>(c)].pixel;
    Transform T_CT;
    if (!HomographyPose(plane, pixels, K, T_CT)) continue;
    // The other pose that nearly fits: the tag's normal mirrored about the line of sight.
    const Vec3 n = T_CT.linear().col(2), v = T_CT.translation().normalized();
    const Vec3 mirrored = 2.0 * n.dot(v) * v - n;
    const Vec3 axis = n.cross(mirrored);
    Transform T_flip = T_CT;
    if (axis.norm() > 1e-9)
      T_flip.linear() =
          ExpSO3(axis.normalized() * std::atan2(axis.norm(), n.dot(mirrored))) * T_CT.linear();
    for (const Transform& T : {T_CT, T_flip}) refine(T_PC * T * tag->T_OT.inverse());
  }
  std::sort(found.begin(), found.end(),
            [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  std::vector<const Candidate*> kept;
  for (const Candidate& c : found) {
    const bool seen = std::any_of(kept.begin(), kept.end(), [&](const Candidate* k) {
      return (c.p - k->p).norm() <= 0.005 &&
             LogSO3(c.R.transpose() * k->R).norm() <= 5.0 * M_PI / 180;
    });
    if (seen) continue;
    kept.push_back(&c);
    const Eigen::LDLT<Mat6> ldlt(c.HtH);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0))
      continue;  // not determined by the corners
    TagPoseFit fit;
    fit.T_PO = MakeTransform(c.p, c.R);
    const Mat6 cov = ldlt.solve(Mat6::Identity()) * (pixel_sigma * pixel_sigma);
    fit.covariance = 0.5 * (cov + cov.transpose());
    fit.cost = c.cost;
    fits.push_back(fit);
  }
}

}  // namespace inhand
