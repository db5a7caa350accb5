#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include "alloc_counter.hpp"
#include "fixtures.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/distance_field.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/filter/joint_samples.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

using namespace filter_test;  // NOLINT: the fixtures of this folder

TEST(Filter, PenetratingObjectIsPushedOutAlongTheNormal) {
  FingerScene s;
  // The ball's centre 25 mm above the distal link's axis: 5 mm penetration, normal +z.
  const Transform T0 = At(Vec3(0, 0.07, 0.025));
  Filter filter = s.Started(T0, PerfectContacts(), false);  // one update removes it all
  filter.Predict(s.q0, 0.001);
  filter.UpdateContacts(Eigen::Vector2d::Zero());
  ASSERT_FALSE(filter.trace().contacts.empty());
  EXPECT_EQ(filter.trace().contacts[0].kind, ContactKind::kKinematic);
  const Vec3 moved = filter.position() - T0.translation();
  EXPECT_NEAR(moved.norm(), 0.005, 1e-4);
  EXPECT_GT(moved.normalized().dot(Vec3::UnitZ()), std::cos(1.0 * M_PI / 180));
  EXPECT_GT(s.Distance(s.q0, filter.T_PO()), -1e-4);
  EXPECT_LT(filter.biases().norm(), 1e-6);  // the finger was held fixed
}

// A palm through the middle of a thin object: a 40 mm thick box across a 10 mm slab (the object,
// its field from the piece), 5 mm deep at the slab's middle plane and 0.3 mm off it. The inside
// samples lie symmetrically about that plane, so the field's normal is decided by a sample or two
// and flips as the estimate moves a fraction of a millimetre; pushed one way and then back, the
// palm stayed inside (a hard shampoo run ended with the palm 12.5 mm inside). Each penetration
// keeps the direction of its link's last push, so the slab leaves the palm one way: 25 mm of
// travel along the slab's normal. With the default noise (σ 15 mm, a few percent of the depth
// per step) that takes a few hundred steps; the first pushes and the last are along one axis.
TEST(Filter, APenetrationKeepsItsDirectionAcrossTheObjectsMiddle) {
  const HandModel hand = ParseHandModel(R"(<robot name="palm">
  <link name="palm"><collision><geometry><box size="0.03 0.03 0.04"/></geometry></collision></link>
  <link name="f"/>
  <joint name="j" type="revolute"><parent link="palm"/><child link="f"/><origin xyz="0 0.2 0"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>)",
                                        ".", "palm.urdf");
  ObjectModel slab;
  slab.name = "slab";
  slab.mass = 0.1;
  slab.pieces.push_back(ConvexPiece::Box(Vec3(0.04, 0.04, 0.005), Transform::Identity()));
  slab.field = std::make_shared<const DistanceField>(
      BuildDistanceFieldFromPieces(slab.pieces, DistanceFieldParams{}));
  BulletContactQuery query(hand, slab);
  Filter f(hand, query, FilterParams{}, FilterOptions{false});
  const Transform T0 = At(Vec3(0, 0, 0.0003));
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(1), tau = Eigen::VectorXd::Zero(1);
  f.Reset(T0, q, StartSigmas{0.02, 0.087, 0.01, {}});
  f.Step(q, tau, 0.002);
  EXPECT_NEAR(f.trace().penetration, 0.0047, 3e-4);
  const Vec3 first = f.position() - T0.translation();
  ASSERT_GT(first.norm(), 0.0);
  EXPECT_GT(std::abs(first.normalized().z()), 0.99);
  int steps = 1;
  for (; steps < 2000 && f.trace().penetration > 1e-4; ++steps) f.Step(q, tau, 0.002);
  EXPECT_LE(f.trace().penetration, 1e-4) << "after " << steps << " steps";
  const Vec3 moved = f.position() - T0.translation();
  EXPECT_GT(moved.dot(first), 0.0);                 // the way the first push went
  EXPECT_NEAR(std::abs(moved.z()), 0.0247, 0.002);  // out of the palm along the normal
  EXPECT_LT(moved.head<2>().norm(), 0.003);
}

// The estimate's own penetration (FilterTrace::penetration): the depth of the deepest link inside
// the object at the step's contact query, here 5 mm by construction (a 20 mm ball 25 mm above the
// distal link's 10 mm capsule) and the same as the query's distance; after the update has pushed
// the ball out, the next step's is ~0; a ball 3 cm clear of the finger reads 0, not a negative.
TEST(Filter, TheTraceSaysHowDeepTheHandLiesInsideTheEstimate) {
  FingerScene s;
  const Transform T0 = At(Vec3(0, 0.07, 0.025));
  Filter filter = s.Started(T0, PerfectContacts(), false);
  filter.Step(s.q0, Eigen::Vector2d::Zero(), 0.001);
  EXPECT_NEAR(filter.trace().penetration, 0.005, 1e-6);
  EXPECT_NEAR(filter.trace().penetration, -s.Distance(s.q0, T0), 1e-12);
  filter.Step(s.q0, Eigen::Vector2d::Zero(), 0.001);
  EXPECT_LT(filter.trace().penetration, 1e-4);
  Filter clear = s.Started(At(Vec3(0, 0.07, 0.06)), PerfectContacts(), false);
  clear.Step(s.q0, Eigen::Vector2d::Zero(), 0.001);
  EXPECT_EQ(clear.trace().penetration, 0.0);
}

// What the contacts at the estimate leave of the torques (FilterTrace::unexplained_torque): a
// force on the distal link 2 mm from the object is explained (but for the damping's share, under
// 1 %); the same
// torques with the estimate 5 cm away, where no link is within reach, are unexplained whole; a
// set without torques reports 0.
TEST(Filter, TheTraceSaysWhatTheContactsLeaveOfTheTorques) {
  FingerScene s;
  const Eigen::Vector2d tau = s.Torque(s.q0, Vec3(0, 0.085, 0.01), Vec3(0, 0, 5.0));
  Filter near = s.Started(At(Vec3(0, 0.085, 0.032)), PerfectContacts(), true);
  near.Step(s.q0, tau, 0.001);
  EXPECT_LT(near.trace().unexplained_torque, 0.01 * tau.cwiseAbs().maxCoeff());
  Filter far = s.Started(At(Vec3(0, 0.085, 0.08)), PerfectContacts(), true);
  far.Step(s.q0, tau, 0.001);
  EXPECT_DOUBLE_EQ(far.trace().unexplained_torque, tau.cwiseAbs().maxCoeff());
  Filter blind = s.Started(At(Vec3(0, 0.085, 0.032)), PerfectContacts(), false);
  blind.Step(s.q0, tau, 0.001);
  EXPECT_EQ(blind.trace().unexplained_torque, 0.0);
}

TEST(Filter, TorqueConfirmedContactPullsTheObjectIntoTouch) {
  FingerScene s;
  // 2 mm above the distal link's far end (within the 3 mm candidate range), out of the
  // proximal link's.
  const Transform T0 = At(Vec3(0, 0.085, 0.032));
  Filter filter = s.Started(T0, PerfectContacts(), true);  // one update closes the gap
  ASSERT_NEAR(s.Distance(s.q0, T0), 0.002, 1e-9);
  const Eigen::Vector2d tau = s.Torque(s.q0, Vec3(0, 0.085, 0.01), Vec3(0, 0, 5.0));
  filter.Predict(s.q0, 0.001);
  filter.UpdateContacts(tau);
  ASSERT_EQ(filter.trace().contacts.size(), 1u);
  const auto& c = filter.trace().contacts[0];
  EXPECT_EQ(c.kind, ContactKind::kTorque);
  EXPECT_NEAR(c.force_P.z(), 5.0, 0.05);  // λ̄ recovers the applied force
  EXPECT_NEAR(s.Distance(s.q0, filter.T_PO()), 0.0, 1e-4);
  EXPECT_LT(filter.position().z(), T0.translation().z() - 0.0018);
}

// A grip that weakens after the object was held may let it slip: the random walk of the pose
// grows by slip_scale² in variance while Σ|τ| is below slip_torque, and only then; before the
// first firm grip (the object untouched) it does not.
TEST(Filter, AWeakenedGripGrowsTheRandomWalk) {
  FingerScene s;
  FilterParams params;
  params.slip_torque = 2.0;
  params.slip_scale = 30.0;
  const Transform T0 = At(Vec3(0, 0.085, 0.06));  // out of reach: no contacts
  Filter filter = s.Started(T0, params, true);
  const double dt = 0.002;
  const auto growth = [&](const Eigen::Vector2d& tau) {
    filter.UpdateContacts(tau);
    const double before = filter.covariance()(0, 0);
    filter.Predict(s.q0, dt);
    return filter.covariance()(0, 0) - before;
  };
  const double walk = params.process_position * params.process_position * dt;
  EXPECT_NEAR(growth(Eigen::Vector2d(0.1, 0.1)), walk, 1e-12);  // never held yet
  EXPECT_FALSE(filter.trace().slipping);
  EXPECT_NEAR(growth(Eigen::Vector2d(1.5, -1.0)), walk, 1e-12);  // held: Σ|τ| = 2.5 N m
  EXPECT_FALSE(filter.trace().slipping);
  EXPECT_NEAR(growth(Eigen::Vector2d(0.1, 0.1)), 900.0 * walk, 1e-10);  // let go
  EXPECT_TRUE(filter.trace().slipping);
  params.slip_torque = 0.0;  // disabled
  Filter off = s.Started(T0, params, true);
  off.UpdateContacts(Eigen::Vector2d(1.5, -1.0));
  off.Predict(s.q0, dt);
  off.UpdateContacts(Eigen::Vector2d(0.1, 0.1));
  off.Predict(s.q0, dt);
  EXPECT_FALSE(off.trace().slipping);
}

TEST(Filter, ForcesOutsideTheConeOrBelowThresholdAreRejected) {
  FingerScene s;
  const Transform T0 = At(Vec3(0, 0.085, 0.032));
  const Vec3 c_f(0, 0.085, 0.01);
  const std::vector<std::pair<Vec3, ContactKind>> cases = {
      {Vec3(0, 0, 5.0), ContactKind::kTorque},
      {Vec3(0, 0, 1.0), ContactKind::kRejectedForce},  // below 2 N
      // (A planar finger senses no force along x: tangential forces lie along y here.)
      {Vec3(0, 4.0, 3.5), ContactKind::kRejectedCone},  // 48.8° off the normal
      {Vec3(0, 3.0, 4.0), ContactKind::kTorque},        // 36.9°: inside
      {Vec3(0, 0, -5.0), ContactKind::kRejectedCone}};  // pulling, not pushing
  for (const auto& [force, kind] : cases) {
    Filter filter = s.Started(T0, FilterParams(), true);
    filter.Predict(s.q0, 0.001);
    filter.UpdateContacts(s.Torque(s.q0, c_f, force));
    ASSERT_EQ(filter.trace().contacts.size(), 1u);
    EXPECT_EQ(filter.trace().contacts[0].kind, kind) << force.transpose();
    if (kind != ContactKind::kTorque) {
      EXPECT_LT((filter.position() - T0.translation()).norm(), 1e-12);
    }
  }
}

// A ball pressed by the distal link (0.5 mm away at the estimate) that also lies 2.1 mm from the
// proximal link's tip: both are candidates. The paper's (J_cᵀ)⁺ spreads j1's torque over both
// links; the weighted one explains it by the nearer link, as it was applied.
TEST(Filter, TorquesAreExplainedByTheNearestLinksFirst) {
  FingerScene s;
  const Transform T0 = At(Vec3(0, 0.06, 0.0305));
  ASSERT_NEAR(s.Distance(s.q0, T0), 0.0005, 1e-6);
  const Vec3 force(0, 0, 5.0);
  const Eigen::Vector2d tau = s.Torque(s.q0, Vec3(0, 0.06, 0.01), force);
  const auto forces = [&](double scale) {
    FilterParams params;
    params.torque_distance_scale = scale;
    Filter filter = s.Started(T0, params, true);
    filter.Predict(s.q0, 0.001);
    filter.UpdateContacts(tau);
    std::map<std::string, Vec3> by_link;
    for (const auto& c : filter.trace().contacts) by_link[s.hand.links[c.link].name] = c.force_P;
    return by_link;
  };
  const auto paper = forces(0.0);
  const auto weighted = forces(FilterParams().torque_distance_scale);
  ASSERT_EQ(paper.size(), 2u);
  ASSERT_EQ(weighted.size(), 2u);
  // Measured: paper l1 1.6 N, l2 off by 2.3 N (28° out of the normal); weighted l1 0.5 N, l2
  // off by 0.7 N.
  EXPECT_GT(paper.at("l1").norm(), 1.0);
  EXPECT_LT(weighted.at("l1").norm(), 0.35 * paper.at("l1").norm());
  EXPECT_LT(weighted.at("l1").norm(), FilterParams().force_min);  // not taken for a contact
  EXPECT_LT((weighted.at("l2") - force).norm(), 0.35 * (paper.at("l2") - force).norm());
}

TEST(Filter, JointBiasConvergesWhenAContactConstrainsIt) {
  FingerScene s;
  const double bias = 2.0 * M_PI / 180;  // the real j2 is 2° more flexed than measured
  const Eigen::Vector2d q_true(0.0, bias);
  // Put the ball in touch with the true distal link, 20 mm along it.
  KinematicsData kin(s.hand);
  kin.Update(s.hand, q_true);
  const Transform& T_l2 = kin.T_PL(s.l2);
  const Vec3 n = T_l2.linear() * Vec3::UnitZ();
  const Vec3 c_f = T_l2 * Vec3(0, 0.02, 0.01);
  const Transform T_PO = At(c_f + 0.02 * n);
  ASSERT_NEAR(s.Distance(q_true, T_PO), 0.0, 1e-9);
  const Eigen::Vector2d tau = s.Torque(q_true, c_f, 5.0 * n);

  Filter filter(s.hand, s.query, PerfectContacts(),
                FilterOptions{true});  // the rate below is for 1 mm
  // The object pose is known; j1 is accurate, j2's bias is uncertain (5°).
  filter.Reset(T_PO, s.q0, StartSigmas{1e-6, 1e-6, 0.0, Eigen::Vector2d(1e-9, 5.0 * M_PI / 180)});
  const double sigma0 = std::sqrt(filter.covariance()(7, 7));
  // The same constraint every step: σ(b2) shrinks like 1/√k and the estimate closes the gap.
  for (int k = 0; k < 100; ++k) {
    filter.Predict(s.q0, 0.001);
    filter.UpdateContacts(tau);
  }
  EXPECT_NEAR(filter.biases()[1], bias, 0.2 * M_PI / 180);
  EXPECT_NEAR(filter.biases()[0], 0.0, 1e-6);
  EXPECT_LT(std::sqrt(filter.covariance()(7, 7)), 0.2 * sigma0);
  EXPECT_LT((filter.position() - T_PO.translation()).norm(), 5e-5);
}

// The project's hand closed around the ketchup bottle (fingers flexed to touch it roughly).
struct GraspScene {
  HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  ObjectModel object = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  BulletContactQuery query{hand, object};
  Transform T_PO =
      MakeTransform(Vec3(0.0, 0.06, 0.045), ExpSO3(Vec3(0, M_PI / 2, 0)) * ExpSO3(Vec3(0, 0, 0.3)));
  Eigen::VectorXd q = Eigen::VectorXd::Constant(16, 0.6);
};

TEST(Filter, CovarianceStaysSymmetricPositiveDefiniteOver10000Steps) {
  GraspScene s;
  FilterParams params;
  params.contact_iterations = 2;
  Filter filter(s.hand, s.query, params, FilterOptions{true});
  filter.Reset(s.T_PO, s.q, StartSigmas{0.02, 0.087, 0.087, {}});
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::VectorXd q = s.q;
  int with_contacts = 0;
  for (int k = 0; k < 10000; ++k) {
    for (int j = 0; j < 16; ++j)
      q[j] += 0.002 * noise(test::Rng()) + 0.0005 * std::sin(0.01 * k + j);
    ClampToLimits(s.hand, q);
    Eigen::VectorXd tau(16);
    for (int j = 0; j < 16; ++j) tau[j] = 0.3 * noise(test::Rng());
    filter.Predict(q, 0.001);
    filter.UpdateContacts(tau);
    with_contacts += filter.trace().num_constraints > 0;
    if (k % 500 == 0 || k == 9999) {
      const Eigen::MatrixXd& P = filter.covariance();
      ASSERT_TRUE(P.allFinite()) << k;
      ASSERT_EQ((P - P.transpose()).cwiseAbs().maxCoeff(), 0.0) << k;
      Eigen::LLT<Eigen::MatrixXd> llt(P);
      ASSERT_EQ(llt.info(), Eigen::Success) << "not positive definite at step " << k;
      ASSERT_TRUE(filter.position().allFinite());
      ASSERT_LT((filter.rotation() * filter.rotation().transpose() - Mat3::Identity()).norm(),
                1e-12);
    }
  }
  EXPECT_GT(with_contacts, 1000);  // the run exercised the updates
}

// Joint-rate steps and, every tenth step, a visual update of 60 features: nothing is allocated
// after warm-up, with the camera pose's error in the state and without.
TEST(Filter, StepAllocatesNothingAfterWarmUp) {
  for (const double camera_sigma : {0.0, 0.002}) {
    GraspScene s;
    FilterParams params;
    params.contact_iterations = 3;
    params.camera_position_sigma = camera_sigma;
    Filter filter(s.hand, s.query, params, FilterOptions{true});
    filter.Reset(s.T_PO, s.q, StartSigmas{0.02, 0.087, 0.087, {}});
    const Intrinsics K = TestIntrinsics();
    const Transform T_PC = CameraLookingAt(s.T_PO.translation());
    std::vector<VisualFeature> features;
    for (int i = 0; i < 60; ++i) {
      const Vec3 x_O(0.02 * std::cos(0.7 * i), 0.02 * std::sin(1.3 * i), 0.05 * std::cos(2.1 * i));
      features.push_back({i, x_O, K.Project(T_PC.inverse() * (s.T_PO * x_O)) + Vec2(0.5, -0.3)});
    }
    Eigen::VectorXd q = s.q, tau = Eigen::VectorXd::Constant(16, 0.5);
    const auto step = [&](int k) {
      q.array() += (k % 2 ? -1e-4 : 1e-4);
      filter.Step(q, tau, 0.001);
      return k % 10 == 0 ? filter.UpdateVisual(features, T_PC, K) : 0;
    };
    for (int k = 0; k < 20; ++k) step(k);
    const long before = test::AllocationCount();
    int constraints = 0, used = 0;
    for (int k = 0; k < 100; ++k) {
      used += step(k);
      constraints += filter.trace().num_constraints;
    }
    EXPECT_EQ(test::AllocationCount() - before, 0) << "camera sigma " << camera_sigma;
    EXPECT_GT(constraints, 0);
    EXPECT_GT(used, 100);  // the visual updates fused features
  }
}

// What reaches the filter of a joint sample: numbers within the limits and the margin pass,
// the first joint that is not (position or torque) is named; clamping and undeflection act on
// the joints that have limits or stiffness only.
TEST(JointSamples, ScreeningClampingAndUndeflection) {
  GraspScene s;
  const Eigen::VectorXd tau = Eigen::VectorXd::Constant(16, 0.5);
  EXPECT_EQ(ScreenJointSample(s.hand, 0.5, s.q, tau).joint, -1);
  const Joint& j3 = s.hand.QJoint(3);
  ASSERT_TRUE(j3.has_limits);
  Eigen::VectorXd q = s.q;
  q[3] = j3.upper + 0.4;  // within the margin
  EXPECT_EQ(ScreenJointSample(s.hand, 0.5, q, tau).joint, -1);
  EXPECT_EQ(ScreenJointSample(s.hand, 0.3, q, tau).joint, 3);
  EXPECT_FALSE(ScreenJointSample(s.hand, 0.3, q, tau).torque);
  Eigen::VectorXd bad_tau = tau;
  bad_tau[7] = std::numeric_limits<double>::quiet_NaN();
  const RejectedJoint r = ScreenJointSample(s.hand, 0.5, s.q, bad_tau);
  EXPECT_EQ(r.joint, 7);
  EXPECT_TRUE(r.torque);
  q[5] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ScreenJointSample(s.hand, 0.5, q, tau).joint, 5);
  EXPECT_EQ(ScreenJointSample(s.hand, 0.3, q, tau).joint, 3);  // the first one
  q[5] = s.q[5];
  ClampToLimits(s.hand, q);
  EXPECT_EQ(q[3], j3.upper);
  for (int i = 0; i < 16; ++i) {
    const Joint& j = s.hand.QJoint(i);
    if (i == 3) continue;
    EXPECT_EQ(q[i], j.has_limits ? std::clamp(s.q[i], j.lower, j.upper) : s.q[i]) << i;
  }
  q = s.q;

  HandModel elastic = s.hand;
  EXPECT_FALSE(HasElasticJoints(elastic));
  elastic.joint_stiffness.assign(16, 0.0);
  elastic.joint_stiffness[2] = 4.0;
  ValidateJointStiffness(elastic);
  EXPECT_TRUE(HasElasticJoints(elastic));
  Undeflect(elastic, tau, q);
  EXPECT_DOUBLE_EQ(q[2], s.q[2] - 0.5 / 4.0);
  q[2] = s.q[2];
  EXPECT_EQ(q, s.q);
  elastic.joint_stiffness[9] = -1.0;
  EXPECT_THROW(ValidateJointStiffness(elastic), InputError);
  elastic.joint_stiffness.resize(3);
  EXPECT_THROW(ValidateJointStiffness(elastic), InputError);
}

// Nothing non-finite enters the state: a joint sample of 1e300 rad or NaN, torques that are not
// numbers, a NaN pixel are skipped and counted; the estimate stays where it was and finite.
TEST(Filter, NonFiniteInputsAreSkippedAndCounted) {
  GraspScene s;
  Filter filter(s.hand, s.query, FilterParams(), FilterOptions{true});
  filter.Reset(s.T_PO, s.q, StartSigmas{0.02, 0.087, 0.087, {}});
  const Eigen::VectorXd tau = Eigen::VectorXd::Constant(16, 0.5);
  for (int k = 0; k < 10; ++k) filter.Predict(s.q, 0.002), filter.UpdateContacts(tau);
  for (const double bad :
       {1e300, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    Eigen::VectorXd q = s.q;
    q[5] = bad;
    filter.Predict(q, 0.002);
    EXPECT_GE(filter.trace().numeric_events, bad == 1e300 ? 0 : 1);
    filter.UpdateContacts(tau);
    Eigen::VectorXd nan_tau = tau;
    nan_tau[3] = std::numeric_limits<double>::quiet_NaN();
    filter.Predict(s.q, 0.002);
    filter.UpdateContacts(nan_tau);
    EXPECT_GE(filter.trace().numeric_events, 1);
    std::vector<VisualFeature> f{
        {0, Vec3::Zero(), Vec2(std::numeric_limits<double>::quiet_NaN(), 1.0)}};
    EXPECT_EQ(filter.UpdateVisual(f, CameraLookingAt(s.T_PO.translation()), TestIntrinsics()), 0);
    EXPECT_TRUE(filter.T_PO().matrix().allFinite());
    EXPECT_TRUE(filter.state().P.allFinite());
    EXPECT_TRUE(filter.biases().allFinite());
  }
  // (1e300 rad is a number: the filter takes it, its state stays finite; the tracker screens
  // such samples out before they reach the filter.)
}

// A saved state restored into another filter of the same hand continues bit-identically; the
// restored one steps with Step, the original with its two halves (Step is exactly them).
TEST(Filter, RestoredStateContinuesBitIdentically) {
  GraspScene s;
  FilterParams params;
  params.camera_position_sigma = 0.002;
  Filter a(s.hand, s.query, params, FilterOptions{true}),
      b(s.hand, s.query, params, FilterOptions{true});
  a.Reset(s.T_PO, s.q, StartSigmas{0.02, 0.087, 0.087, {}});
  b.Reset(s.T_PO * MakeTransform(Vec3(0.01, 0, 0), Mat3::Identity()), s.q,
          StartSigmas{0.03, 0.1, 0.1, {}});
  Eigen::VectorXd q = s.q, tau = Eigen::VectorXd::Constant(16, 0.5);
  const auto halves = [&](Filter& f, int k) {
    f.Predict(q.array() + 1e-4 * (k % 3), 0.001);
    f.UpdateContacts(tau);
  };
  for (int k = 0; k < 30; ++k) halves(a, k);
  b.Restore(a.state());
  for (int k = 30; k < 60; ++k) halves(a, k), b.Step(q.array() + 1e-4 * (k % 3), tau, 0.001);
  EXPECT_EQ(a.T_PO().matrix(), b.T_PO().matrix());
  EXPECT_EQ(a.state().P, b.state().P);
  EXPECT_EQ(a.biases(), b.biases());
  EXPECT_EQ(a.trace().contacts.size(), b.trace().contacts.size());
}

TEST(Filter, PredictionMovesAGraspedObjectWithTheFingers) {
  // The finger touches the ball and flexes: with one hard contact the minimum-norm twist is a
  // pure translation, so the ball follows the contact point.
  FingerScene s;
  const Transform T0 = At(Vec3(0, 0.07, 0.0295));  // 0.5 mm penetration: an active contact
  Filter filter = s.Started(T0, FilterParams(), false);
  filter.Predict(s.q0, 0.001);
  filter.UpdateContacts(Eigen::Vector2d::Zero());
  const Vec3 before = filter.position();
  KinematicsData kin(s.hand);
  kin.Update(s.hand, s.q0);
  const Vec3 c_L = kin.T_PL(s.l2).inverse() * filter.trace().contacts.at(0).c_f_P;
  const Eigen::Vector2d q1(0.0, 0.01);
  filter.Predict(q1, 0.001);
  kin.Update(s.hand, q1);
  const Vec3 c_moved = kin.T_PL(s.l2) * c_L;
  EXPECT_EQ(filter.trace().prediction_contacts, 1);
  const Vec3 expected = c_moved - [&] {
    KinematicsData k0(s.hand);
    k0.Update(s.hand, s.q0);
    return Vec3(k0.T_PL(s.l2) * c_L);
  }();
  // First order in Δq: the point's second-order motion (0.02 m · 0.01² / 2) is left out.
  EXPECT_LT((filter.position() - before - expected).norm(), 3e-6);
  EXPECT_GT(expected.norm(), 1e-4);
}

// travel_orientation: while the finger moves the ball through its contact, the orientation's
// variance grows by travel_orientation · D · Γ⁻¹ per 50 ms window (D: the contact point's
// displacement over the window). The growth is the same at 100 Hz and at 1 kHz with the joints'
// noise (which cancels within a window); nothing grows without a gyration tensor or at 0.
TEST(Filter, TheOrientationsVarianceGrowsWithTheContactsTravelNotWithTheJointRate) {
  FingerScene s;
  const double gyration = 0.4 * 0.02 * 0.02;  // solid ball, radius 20 mm
  FilterParams params;
  params.process_orientation = 0.0;  // only the travel grows it here
  params.motion_orientation = 0.0;
  const auto run = [&](const FilterParams& p, const Mat3& G, int rate, double noise, double* path) {
    Filter f(s.hand, s.query, p, FilterOptions{false, G});
    f.Reset(At(Vec3(0, 0.07, 0.0295)), s.q0,
            StartSigmas{0.02, 0.087, 1e-9, {}});  // 0.5 mm into the ball
    f.Predict(s.q0, 1.0 / rate);
    f.UpdateContacts(Eigen::Vector2d::Zero());
    const int link = f.state().active.at(0).link;
    const Vec3 c_L = f.state().active.at(0).c_f_L;
    const Mat3 before = f.covariance().block(3, 3, 3, 3);
    KinematicsData kin(s.hand);
    const auto point = [&](const Eigen::Vector2d& q) {
      kin.Update(s.hand, q);
      return Vec3(kin.T_PL(link) * c_L);
    };
    const int steps = rate / 2;  // 0.5 s, flexing the distal joint by 0.3 rad
    Vec3 last = point(s.q0);
    *path = 0.0;
    for (int k = 1; k <= steps; ++k) {
      const Eigen::Vector2d q(0.0, 0.3 * k / steps);
      f.Predict(q + Eigen::Vector2d::Constant(k % 2 ? noise : -noise), 1.0 / rate);
      if (k % (rate / 20) == 0)
        *path += (point(q) - last).norm(), last = point(q);  // at each window's end
    }
    const Mat3 growth = f.covariance().block(3, 3, 3, 3) - before;  // isotropic, as Γ is
    EXPECT_LT((growth - growth(0, 0) * Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-12);
    return growth(0, 0);
  };
  const Mat3 G = Mat3::Identity() * gyration;
  double path = 0.0, path_fast = 0.0;
  const double slow = run(params, G, 100, 0.0, &path);
  const double fast = run(params, G, 1000, 2e-4, &path_fast);
  EXPECT_GT(path, 0.004);  // the contact point travels about 8 mm
  // The filter takes D to first order at the window's last configuration (0.03 rad a window).
  EXPECT_NEAR(slow, params.travel_orientation * path / gyration, 0.04 * slow);
  EXPECT_NEAR(fast, slow, 0.05 * slow);
  FilterParams off = params;
  off.travel_orientation = 0.0;
  EXPECT_EQ(run(off, G, 100, 0.0, &path), 0.0);
  EXPECT_EQ(run(params, Mat3::Zero(), 100, 0.0, &path), 0.0);
}

// A gyration tensor, when given, must be symmetric positive definite; none (zero) is allowed.
TEST(FilterOptions, AGyrationTensorMustBeSymmetricPositiveDefinite) {
  FingerScene s;
  EXPECT_NO_THROW(Filter(s.hand, s.query, FilterParams(), FilterOptions{false, Mat3::Zero()}));
  EXPECT_NO_THROW(Filter(s.hand, s.query, FilterParams(),
                         FilterOptions{false, Vec3(1e-5, 4e-4, 4e-4).asDiagonal()}));
  for (const Mat3& bad :
       {Mat3(Vec3(1e-4, 1e-4, 0.0).asDiagonal()), Mat3(Vec3(1e-4, -1e-4, 1e-4).asDiagonal()),
        Mat3((Mat3() << 1e-4, 5e-5, 0, 0, 1e-4, 0, 0, 0, 1e-4).finished()),
        Mat3(Mat3::Constant(std::nan("")))}) {
    try {
      Filter f(s.hand, s.query, FilterParams(), FilterOptions{false, bad});
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("gyration tensor"), std::string::npos) << e.what();
    }
  }
}

TEST(FilterParams, ValidationAndJsonRoundTrip) {
  FilterParams p;
  p.contact_iterations = 3;
  p.contact_normal_only = true;
  p.force_min = 4.5;
  const FilterParams q = FilterParamsFromJson(FilterParamsToJson(p), "p.json");
  EXPECT_EQ(q.contact_iterations, 3);
  EXPECT_TRUE(q.contact_normal_only);
  EXPECT_EQ(q.force_min, 4.5);
  const auto expect_error = [](const std::string& json, const std::string& fragment) {
    try {
      FilterParamsFromJson(json, "p.json");
      ADD_FAILURE() << json;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error("{\"contact_sigma\": 0}", "'contact_sigma' is 0");
  expect_error("{\"friction_cone_deg\": 120}", "'friction_cone_deg'");
  expect_error("{\"contact_iterations\": 1.5}", "integer");
  expect_error("{\"force_mni\": 3}", "unknown parameter 'force_mni'");
  expect_error("{\"force_min\": \"3\"}", "must be a number");
  expect_error("[1, 2]", "expected a JSON object");
}

}  // namespace
}  // namespace inhand
