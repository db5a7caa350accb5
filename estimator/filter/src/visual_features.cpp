// Visual features (paper Sec. III-C): the pixel of an object point, tag corner or extracted
// feature alike, seen by the camera. h = π(K, T_CP (p + R x_O)), r = z - h, H = [∂h/∂(δp, δθ),
// 0 (biases), ∂h/∂ξ (camera error, when estimated)], R = σ_px² I, gated by χ²₂. Features are
// fused one by one at one linearisation point and applied together (one retraction per frame). On
// an object with a continuous symmetry, a feature off the outline measures only across the pixel
// direction in which a turn about it moves the feature (ProjectOutSymmetry).
#include <cmath>

#include "inhand/filter/filter.hpp"

namespace inhand {

int Filter::UpdateVisual(const std::vector<VisualFeature>& features, const Transform& T_PC_recorded,
                         const Intrinsics& K) {
  // With a camera σ the camera pose's error ξ is a state: shared by all features and frames, it
  // keeps a common error from being counted once per feature.
  const Transform T_PC =
      camera_state_
          ? Transform(T_PC_recorded * MakeTransform(s_.xi.head<3>(), ExpSO3(s_.xi.tail<3>())))
          : T_PC_recorded;
  const Mat3 Rc_T = T_PC.linear().transpose();
  const Eigen::Matrix2d Rv =
      Eigen::Matrix2d::Identity() * (params_.pixel_sigma * params_.pixel_sigma);
  // The symmetric turn in the error state, the same for every feature of the frame (one
  // linearisation point); zero when the object declares no symmetry.
  Vec6 turn = Vec6::Zero();
  if (!options_.symmetry_axis_O.isZero()) {
    const Vec3 a = s_.R * options_.symmetry_axis_O.normalized();
    turn << -a.cross(s_.R * options_.symmetry_point_O), a;
  }
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
    rec.depth = X_C.z();
    H2_.leftCols<6>() = VisualMeasurementJacobian(X, s_.p, T_PC, K);
    if (camera_state_) H2_.rightCols<6>() = CameraPoseJacobian(X, T_PC, K);
    Eigen::Vector2d r = f.pixel - rec.predicted;
    if (!turn.isZero() && !f.on_outline) ProjectOutSymmetry(turn, r);
    rec.gated =
        Update<2>(r, H2_, Rv, params_.visual_gate_chi2, &rec.mahalanobis) != Outcome::kApplied;
    if (!rec.gated) CapVisualInformation(Rv);
    used += !rec.gated;
    s_.trace.visual.push_back(rec);
  }
  Commit();
  RefreshKinematics();
  return used;
}

// A turn of the object about its symmetry axis (FilterOptions::symmetry_axis_O) changes no image:
// in the error state it is the motion v = (δp, δθ) = (-a × R c_O, a), with a the axis in P and c_O
// a point on it (UpdateVisual's `turn`), and it moves the feature's predicted pixel along u = H v.
// Where along that turn the matched point lies is the matcher's choice among points that all look
// alike (a corner on a rim of the barrel), not a measurement: r and H keep only their components
// across u, so that H v = 0, and the feature measures one direction instead of two, none of it
// along v. Not for a point on the outline (VisualFeature::on_outline): the grazing point already
// moves along the line of sight with the turn, so u is only what the grazing walk's tolerance
// leaves, and it points across the outline, the one direction such a feature measures.
void Filter::ProjectOutSymmetry(const Vec6& v, Eigen::Vector2d& r) {
  const Eigen::Vector2d u = H2_.leftCols<6>() * v;
  const double uu = u.squaredNorm();
  if (!(uu > 1e-18)) return;  // a point on the axis
  const Eigen::Matrix2d across = Eigen::Matrix2d::Identity() - u * u.transpose() / uu;
  r = across * r;
  H2_ = across * H2_;
}

// visual_model_sigma: the variance of a feature's predicted pixel (the mean over its two axes) may
// not fall below σ_v² through visual updates: what the camera calibration, the hand-eye pose and
// the object model get wrong is the same for every feature and every frame, and would otherwise
// count once per feature per frame. As for contacts (CapContactInformation): the information the
// update removed below the floor is given back in the directions it was taken from, never more.
void Filter::CapVisualInformation(const Eigen::Matrix2d& R) {
  const double floor = params_.visual_model_sigma * params_.visual_model_sigma;
  if (!(floor > 0.0)) return;
  const Eigen::Matrix2d V_before = HP2_ * H2_.transpose();
  const Eigen::Matrix2d S = V_before + R;
  const Eigen::Matrix2d S_inv = S.inverse();
  const double v_before = 0.5 * V_before.trace();
  const double v_after = v_before - 0.5 * (V_before * S_inv * V_before).trace();
  if (!(v_after < floor) || !(v_before > v_after)) return;
  const double alpha = std::min(1.0, (floor - v_after) / (v_before - v_after));
  const Eigen::LLT<Eigen::Matrix2d> llt(alpha * S_inv);
  if (llt.info() != Eigen::Success) return;
  HP2_ = llt.matrixU() * HP2_;  // scratch: G with Gᵀ G = α (HP)ᵀ S⁻¹ (HP), exactly symmetric
  s_.P.noalias() += HP2_.transpose() * HP2_;
}

}  // namespace inhand
