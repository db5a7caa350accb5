#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

using J3 = Eigen::Matrix<double, 3, Eigen::Dynamic>;

Eigen::VectorXd RandomConfiguration(const HandModel& hand) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(hand.num_q());
  for (int i = 0; i < hand.num_q(); ++i) {
    const Joint& j = hand.joints[hand.q_joints[i]];
    const double lo = j.has_limits ? j.lower : -M_PI, hi = j.has_limits ? j.upper : M_PI;
    q[i] = lo + (hi - lo) * u(test::Rng());
  }
  return q;
}

// Checks the analytic point Jacobian of random points on every moving link against central
// differences of forward kinematics.
void CheckJacobians(const HandModel& hand, int configurations) {
  KinematicsData data(hand), probe(hand);
  J3 J(3, hand.num_q());
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  int checked = 0;
  for (int c = 0; c < configurations; ++c) {
    const Eigen::VectorXd q = RandomConfiguration(hand);
    data.Update(hand, q);
    for (std::size_t l = 0; l < hand.links.size(); ++l) {
      const Vec3 local(u(test::Rng()), u(test::Rng()), u(test::Rng()));
      const Vec3 p = data.T_PL(static_cast<int>(l)) * local;
      PointJacobian(hand, data, static_cast<int>(l), p, J);
      J3 N(3, hand.num_q());
      for (int i = 0; i < hand.num_q(); ++i) {
        const double h = 1e-6;
        Eigen::VectorXd qa = q, qb = q;
        qa[i] += h;
        qb[i] -= h;
        probe.Update(hand, qa);
        const Vec3 pa = probe.T_PL(static_cast<int>(l)) * local;
        probe.Update(hand, qb);
        const Vec3 pb = probe.T_PL(static_cast<int>(l)) * local;
        N.col(i) = (pa - pb) / (2 * h);
      }
      ASSERT_LT((J - N).cwiseAbs().maxCoeff(), 1e-8)
          << hand.name << " link " << hand.links[l].name << "\nJ=\n"
          << J << "\nN=\n"
          << N;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);
}

constexpr const char* kTwoFinger = R"(<?xml version="1.0"?>
<robot name="two_finger">
  <link name="palm"/>
  <link name="a1"/><link name="a2"/><link name="b1"/><link name="b2"/><link name="c"/>
  <joint name="ja1" type="revolute"><parent link="palm"/><child link="a1"/>
    <origin xyz="0.02 0 0" rpy="0.1 0.2 0.3"/><axis xyz="0 0 3"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="ja2" type="revolute"><parent link="a1"/><child link="a2"/>
    <origin xyz="0 0.05 0"/><axis xyz="1 1 0"/>
    <limit lower="0" upper="1.5" effort="1" velocity="1"/>
    <mimic joint="ja1" multiplier="-0.7" offset="0.2"/></joint>
  <joint name="jb1" type="prismatic"><parent link="palm"/><child link="b1"/>
    <origin xyz="-0.02 0 0" rpy="0 0.5 0"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
  <joint name="jb2" type="continuous"><parent link="b1"/><child link="b2"/>
    <origin xyz="0 0.03 0.01"/><axis xyz="0 0 1"/></joint>
  <joint name="jc" type="fixed"><parent link="b2"/><child link="c"/><origin xyz="0 0.02 0"/></joint>
</robot>)";

TEST(Kinematics, InlineHandWithMimicPrismaticContinuousAndFixed) {
  const HandModel hand = ParseHandModel(kTwoFinger, ".", "two_finger.urdf");
  ASSERT_EQ(hand.num_q(), 3);  // ja2 mimics ja1; jc is fixed
  EXPECT_EQ(hand.QNames(), (std::vector<std::string>{"ja1", "jb1", "jb2"}));
  const Joint& ja2 = hand.joints[hand.JointIndex("ja2")];
  EXPECT_TRUE(ja2.is_mimic);
  EXPECT_EQ(ja2.q_index, 0);
  EXPECT_NEAR(ja2.axis.norm(), 1.0, 1e-15);  // "1 1 0" normalised
  CheckJacobians(hand, 20);

  // Forward kinematics by hand for link a2.
  KinematicsData data(hand);
  Eigen::VectorXd q(3);
  q << 0.4, 0.01, -2.0;
  data.Update(hand, q);
  const Transform T_a1 = MakeTransform(Vec3(0.02, 0, 0), RotationFromRpy(Vec3(0.1, 0.2, 0.3))) *
                         Eigen::AngleAxisd(0.4, Vec3::UnitZ());
  const Transform T_a2 = T_a1 * MakeTransform(Vec3(0, 0.05, 0), Mat3::Identity()) *
                         Eigen::AngleAxisd(-0.7 * 0.4 + 0.2, Vec3(1, 1, 0).normalized());
  EXPECT_LT((data.T_PL(hand.LinkIndex("a2")).matrix() - T_a2.matrix()).norm(), 1e-14);
  EXPECT_NEAR(data.joint_value(hand.JointIndex("ja2")), -0.7 * 0.4 + 0.2, 1e-15);
  // Prismatic: b1 slides along its axis.
  const Vec3 axis_b = RotationFromRpy(Vec3(0, 0.5, 0)) * Vec3::UnitY();
  EXPECT_LT(
      (data.T_PL(hand.LinkIndex("b1")).translation() - (Vec3(-0.02, 0, 0) + 0.01 * axis_b)).norm(),
      1e-15);
}

TEST(Kinematics, RootJacobianIsZeroAndOutsideChainColumnsAreZero) {
  const HandModel hand = ParseHandModel(kTwoFinger, ".", "two_finger.urdf");
  KinematicsData data(hand);
  data.Update(hand, Eigen::Vector3d(0.1, 0.02, 0.3));
  J3 J(3, 3);
  PointJacobian(hand, data, hand.root_link, Vec3(0.1, 0.2, 0.3), J);
  EXPECT_EQ(J.norm(), 0.0);
  PointJacobian(hand, data, hand.LinkIndex("c"), data.T_PL(hand.LinkIndex("c")).translation(), J);
  EXPECT_EQ(J.col(0).norm(), 0.0);  // ja1 is not in c's chain
  EXPECT_GT(J.col(1).norm(), 0.0);
}

TEST(Kinematics, UpdateAndJacobianAllocateNothing) {
  const HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  KinematicsData data(hand);
  J3 J(3, hand.num_q());
  Eigen::VectorXd q = RandomConfiguration(hand);
  const int tip = hand.LinkIndex("index_distal");
  data.Update(hand, q);  // warm-up
  const long before = test::AllocationCount();
  for (int i = 0; i < 100; ++i) {
    q[0] += 1e-3;
    data.Update(hand, q);
    PointJacobian(hand, data, tip, data.T_PL(tip).translation(), J);
  }
  EXPECT_EQ(test::AllocationCount() - before, 0);
}

TEST(Kinematics, ProjectHandJacobians) {
  const HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  EXPECT_EQ(hand.num_q(), 16);
  CheckJacobians(hand, 10);
}

TEST(Kinematics, ProjectHandClosesTowardsThePalmSide) {
  // Flexing every finger curls its tip out of the palm plane (+z of P) and back towards the
  // wrist; opposing the thumb brings its tip in front of the palm, between fingers and wrist.
  const HandModel hand = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  KinematicsData data(hand);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(16);
  data.Update(hand, q);
  const Vec3 index_open = data.T_PL(hand.LinkIndex("index_tip")).translation();
  for (const char* f : {"index", "middle", "ring"})
    for (int k = 1; k <= 3; ++k)
      q[hand.joints[hand.JointIndex(std::string(f) + "_flex" + std::to_string(k))].q_index] = 0.9;
  data.Update(hand, q);
  const Vec3 index_closed = data.T_PL(hand.LinkIndex("index_tip")).translation();
  EXPECT_GT(index_closed.z(), index_open.z() + 0.04);
  EXPECT_LT(index_closed.y(), index_open.y() - 0.03);
  q[hand.joints[hand.JointIndex("thumb_abduction")].q_index] = 0.3;
  for (int k = 1; k <= 3; ++k)
    q[hand.joints[hand.JointIndex("thumb_flex" + std::to_string(k))].q_index] = 0.8;
  data.Update(hand, q);
  const Vec3 thumb = data.T_PL(hand.LinkIndex("thumb_tip")).translation();
  EXPECT_GT(thumb.z(), 0.02);  // in front of the palm
  EXPECT_GT(thumb.y(), 0.03);  // towards the fingers, not the wrist
  EXPECT_LT(thumb.y(), index_open.y());
  EXPECT_LT(thumb.x(), 0.036 + 0.01);  // curled back over the palm
}

TEST(Kinematics, SharedHandsJacobians) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  for (const char* urdf : {"allegro_hand/allegro_hand_right.urdf", "barrett_hand/bhand_model.urdf",
                           "shadow_hand/shadow_hand_right.urdf"}) {
    HandLoadOptions options;
    options.load_visual_meshes = false;
    const HandModel hand = LoadHandModel(hands + urdf, options);
    CheckJacobians(hand, 5);
  }
}

TEST(Kinematics, TwoAllegroDescriptionsGiveTheSameJointFrames) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  // dex-urdf (relative OBJ paths) and the original description (package:// STL paths).
  const HandModel a = LoadHandModel(hands + "allegro_hand/allegro_hand_right.urdf");
  const HandModel b =
      LoadHandModel(hands + "allegro_hand_description/allegro_hand_description_right.urdf");
  ASSERT_EQ(a.num_q(), 16);
  ASSERT_EQ(b.num_q(), 16);
  ASSERT_EQ(a.QNames(), b.QNames());
  KinematicsData da(a), db(b);
  for (int c = 0; c < 20; ++c) {
    const Eigen::VectorXd q = RandomConfiguration(a);
    da.Update(a, q);
    db.Update(b, q);
    for (const std::string& name : a.QNames()) {
      const Joint& ja = a.joints[a.JointIndex(name)];
      const Joint& jb = b.joints[b.JointIndex(name)];
      const double err =
          (da.T_PL(ja.child_link).matrix() - db.T_PL(jb.child_link).matrix()).cwiseAbs().maxCoeff();
      EXPECT_LT(err, 1e-9) << name;
    }
  }
}

}  // namespace
}  // namespace inhand
