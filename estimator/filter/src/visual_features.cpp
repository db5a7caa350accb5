// Visual features (paper Sec. III-C): the pixel of an object point, tag corner or extracted
// feature alike, seen by the camera. h = π(K, T_CP (p + R x_O)), r = z - h, H = [∂h/∂(δp, δθ),
// 0 (biases), ∂h/∂ξ (camera error, when estimated)], R = σ_px² I, gated by χ²₂. Features are
// fused one by one at one linearisation point and applied together (one retraction per frame).
#include <cmath>

#include "inhand/filter/filter.hpp"

namespace inhand {

int Filter::UpdateVisual(const std::vector<VisualFeature>& features, const Transform& T_PC_recorded, const Intrinsics& K) {
  // With a camera σ the camera pose's error ξ is a state: shared by all features and frames, it
  // keeps a common error from being counted once per feature.
  const Transform T_PC = camera_state_ ? Transform(T_PC_recorded * MakeTransform(s_.xi.head<3>(), ExpSO3(s_.xi.tail<3>())))
                                       : T_PC_recorded;
  const Mat3 Rc_T = T_PC.linear().transpose();
  const Eigen::Matrix2d Rv = Eigen::Matrix2d::Identity() * (params_.pixel_sigma * params_.pixel_sigma);
  int used = 0;
  for (const VisualFeature& f : features) {
    FilterTrace::Visual rec;
    rec.id = f.id;
    rec.measured = f.pixel;
    const Vec3 X = s_.p + s_.R * f.x_O;
    const Vec3 X_C = Rc_T * (X - T_PC.translation());
    if (!(X_C.z() > 1e-6) || !f.pixel.allFinite()) {
      ++s_.trace.numeric_events;
      rec.gated = true;
      s_.trace.visual.push_back(rec);
      continue;
    }
    rec.predicted = K.Project(X_C);
    H2_.leftCols<6>() = VisualMeasurementJacobian(X, s_.p, T_PC, K);
    if (camera_state_) H2_.rightCols<6>() = CameraPoseJacobian(X, T_PC, K);
    const Eigen::Vector2d r = f.pixel - rec.predicted;
    rec.gated = Update<2>(r, H2_, Rv, params_.visual_gate_chi2, &rec.mahalanobis) != Outcome::kApplied;
    used += !rec.gated;
    s_.trace.visual.push_back(rec);
  }
  Commit();
  RefreshKinematics();
  return used;
}

}  // namespace inhand
