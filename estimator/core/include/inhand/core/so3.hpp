#pragma once
// SO(3)/SE(3) helpers. Rotations act on the left: R_AB maps coordinates in B to A.
// Exp/Log follow docs/estimator.md: R = Exp(δθ) R̂ with δθ expressed in the outer frame.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace inhand {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;
using Transform = Eigen::Isometry3d;  // T_AB: pose of frame B expressed in A

// [a]x with [a]x v = a × v.
Mat3 Skew(const Vec3& a);

// Exponential map so(3) → SO(3) (Rodrigues, Taylor series below 1e-8 rad).
Mat3 ExpSO3(const Vec3& omega);

// Logarithm SO(3) → so(3), |result| in [0, π]. Accurate near identity and near π
// (through the quaternion, which Eigen extracts with Shepperd's method).
Vec3 LogSO3(const Mat3& R);

// Rotation angle of R_a R_bᵀ in radians, in [0, π].
double RotationDistance(const Mat3& R_a, const Mat3& R_b);

// URDF roll-pitch-yaw (fixed axes X, then Y, then Z): R = Rz(yaw) Ry(pitch) Rx(roll).
Mat3 RotationFromRpy(const Vec3& rpy);
Vec3 RpyFromRotation(const Mat3& R);

Transform MakeTransform(const Vec3& p, const Mat3& R);
Transform MakeTransform(const Vec3& p, const Quat& q);

// Projects a nearly orthonormal matrix onto SO(3) (polar decomposition via SVD).
Mat3 Orthonormalize(const Mat3& R);

}  // namespace inhand
