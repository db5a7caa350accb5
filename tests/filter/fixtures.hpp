#pragma once
// The fixtures of the filter's tests: a finger of two capsule links and a ball, the camera of the
// visual tests and features seen from it.
#include <cmath>
#include <vector>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/so3.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"

namespace inhand::filter_test {

// One finger of two capsule links along +y, flexing about x (towards +z).
inline constexpr const char* kFinger = R"(<robot name="finger">
  <link name="palm"/>
  <link name="l1"><collision><origin xyz="0 0.025 0" rpy="-1.5707963267948966 0 0"/>
    <geometry><cylinder radius="0.01" length="0.05"/></geometry></collision>
    <collision><origin xyz="0 0 0"/><geometry><sphere radius="0.01"/></geometry></collision>
    <collision><origin xyz="0 0.05 0"/><geometry><sphere radius="0.01"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0 0.02 0" rpy="-1.5707963267948966 0 0"/>
    <geometry><cylinder radius="0.01" length="0.04"/></geometry></collision>
    <collision><origin xyz="0 0 0"/><geometry><sphere radius="0.01"/></geometry></collision>
    <collision><origin xyz="0 0.04 0"/><geometry><sphere radius="0.01"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="palm"/><child link="l1"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="2" effort="2" velocity="3"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0.05 0"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="2" effort="2" velocity="3"/></joint>
</robot>)";

inline ObjectModel Ball(double radius) {
  ObjectModel o;
  o.name = "ball";
  o.pieces.push_back(ConvexPiece::Sphere(radius, Transform::Identity()));
  o.mass = 0.1;
  return o;
}

inline Transform At(const Vec3& p) { return MakeTransform(p, Mat3::Identity()); }

// The paper's "perfect" contact measurement (σ = 1 mm): the single-update and convergence-rate
// expectations below are derived for it.
inline FilterParams PerfectContacts() {
  FilterParams params;
  params.contact_sigma = 0.001;
  params.contact_model_sigma = 0.0;  // perfect geometry too: no floor on what contacts can know
  return params;
}

struct FingerScene {
  HandModel hand = ParseHandModel(kFinger, ".", "finger.urdf");
  ObjectModel ball = Ball(0.02);
  BulletContactQuery query{hand, ball};
  int l2 = hand.LinkIndex("l2");
  Eigen::Vector2d q0 = Eigen::Vector2d::Zero();

  // A filter on this finger, started at T0 with the paper's initial σ (20 mm, 5°) and exact joints.
  Filter Started(const Transform& T0, const FilterParams& params, bool torque) {
    Filter f(hand, query, params, FilterOptions{torque});
    f.Reset(T0, q0, StartSigmas{0.02, 0.087, 1e-9, {}});
    return f;
  }

  // τ = J_cᵀ λ for a force λ applied by link l2 at c_f (palm frame).
  Eigen::Vector2d Torque(const Eigen::Vector2d& q, const Vec3& c_f, const Vec3& force) const {
    KinematicsData kin(hand);
    kin.Update(hand, q);
    Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, 2);
    PointJacobian(hand, kin, l2, c_f, J);
    return J.transpose() * force;
  }
  double Distance(const Eigen::Vector2d& q, const Transform& T_PO) {
    KinematicsData kin(hand);
    kin.Update(hand, q);
    std::vector<ContactPair> pairs;
    query.Query(kin.link_poses(), T_PO, 1.0, pairs);
    for (const ContactPair& p : pairs)
      if (p.link == l2) return p.distance;
    return 1.0;
  }
};

// The camera of the visual tests: 0.4 m from p, z towards it, y roughly down.
inline Transform CameraLookingAt(const Vec3& p) {
  const Vec3 eye(0.05, -0.3, 0.25);
  const Vec3 z = (p - eye).normalized();
  const Vec3 x = z.cross(Vec3(0, 0, -1)).normalized();
  Mat3 Rc;
  Rc << x, z.cross(x), z;
  return MakeTransform(eye, Rc);
}

// 640x480-like pinhole without distortion.
inline Intrinsics TestIntrinsics() {
  Intrinsics K;
  K.fx = 600;
  K.fy = 590;
  K.cx = 320;
  K.cy = 240;
  return K;
}

// 40 points spread over a 6 x 6 x 4 cm object at p (identity orientation), exactly as a camera
// at T_PC_true sees them.
inline std::vector<VisualFeature> FeaturesSeenFrom(const Transform& T_PC_true, const Intrinsics& K,
                                                   const Vec3& p) {
  std::vector<VisualFeature> features;
  for (int i = 0; i < 40; ++i) {
    const Vec3 x_O(0.03 * std::cos(0.7 * i), 0.03 * std::sin(1.3 * i), 0.02 * std::cos(2.1 * i));
    features.push_back({i, x_O, K.Project(T_PC_true.inverse() * (p + x_O))});
  }
  return features;
}

}  // namespace inhand::filter_test
