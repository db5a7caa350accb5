#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

// A hand of one link per primitive, all fixed to the palm at the origin (poses are passed to
// the query directly).
constexpr const char* kShapes = R"(<robot name="shapes">
  <link name="palm"/>
  <link name="sphere"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
  <link name="box"><collision><geometry><box size="0.02 0.02 0.02"/></geometry></collision></link>
  <link name="capsule">
    <collision><origin xyz="0 0 0"/><geometry><cylinder radius="0.005" length="0.04"/></geometry></collision>
    <collision><origin xyz="0 0 -0.02"/><geometry><sphere radius="0.005"/></geometry></collision>
    <collision><origin xyz="0 0 0.02"/><geometry><sphere radius="0.005"/></geometry></collision>
  </link>
  <joint name="a" type="fixed"><parent link="palm"/><child link="sphere"/></joint>
  <joint name="b" type="fixed"><parent link="palm"/><child link="box"/></joint>
  <joint name="c" type="fixed"><parent link="palm"/><child link="capsule"/></joint>
</robot>)";

struct Fixture {
  HandModel hand = ParseHandModel(kShapes, ".", "shapes.urdf");
  ObjectModel object = [] {
    ObjectModel o;
    o.pieces.push_back(ConvexPiece::Box(Vec3(0.05, 0.05, 0.05), Transform::Identity()));
    o.pieces.push_back(ConvexPiece::Sphere(0.01, Transform::Identity()));
    return o;
  }();
  BulletContactQuery query{hand, object};
  int link(const char* name) const { return hand.LinkIndex(name); }
};

Transform At(double x, double y, double z) {
  return MakeTransform(Vec3(x, y, z), Mat3::Identity());
}

Transform RandomPose(double spread) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto& rng = test::Rng();
  return MakeTransform(Vec3(u(rng), u(rng), u(rng)) * spread,
                       ExpSO3(Vec3(u(rng), u(rng), u(rng)) * 3.0));
}

void ExpectPair(const ContactPair& p, double d, const Vec3& c_f, const Vec3& c_o, const Vec3& n,
                double tol = 1e-9) {
  EXPECT_NEAR(p.distance, d, tol);
  EXPECT_LT((p.c_f_P - c_f).norm(), 10 * tol) << p.c_f_P.transpose();
  EXPECT_LT((p.c_o_P - c_o).norm(), 10 * tol) << p.c_o_P.transpose();
  EXPECT_LT((p.normal_P - n).norm(), 1e-6) << p.normal_P.transpose();
}

TEST(Contacts, SphereAgainstBoxSeparatedAndPenetrating) {
  Fixture f;
  // Box object centred at x = 0.07: its face at x = 0.02; the sphere (r = 10 mm) at the origin.
  ExpectPair(f.query.QueryPair(f.link("sphere"), 0, 0, Transform::Identity(), At(0.07, 0, 0)), 0.01,
             Vec3(0.01, 0, 0), Vec3(0.02, 0, 0), Vec3(1, 0, 0));
  // Penetrating by 5 mm: c_f is the sphere's deepest point, c_o on the face.
  ExpectPair(f.query.QueryPair(f.link("sphere"), 0, 0, Transform::Identity(), At(0.055, 0, 0)),
             -0.005, Vec3(0.01, 0, 0), Vec3(0.005, 0, 0), Vec3(1, 0, 0));
  // The same from below: normal flips.
  ExpectPair(f.query.QueryPair(f.link("sphere"), 0, 0, Transform::Identity(), At(0, 0, -0.058)),
             -0.002, Vec3(0, 0, -0.01), Vec3(0, 0, -0.008), Vec3(0, 0, -1));
}

TEST(Contacts, CoplanarBoxFacesAreExact) {
  Fixture f;
  // Link box (half 10 mm) and object box (half 50 mm), faces parallel: EPA's hard case.
  for (double gap : {0.003, 0.0, -0.0005, -0.004}) {
    const ContactPair p =
        f.query.QueryPair(f.link("box"), 0, 0, Transform::Identity(), At(0.06 + gap, 0.01, -0.02));
    EXPECT_NEAR(p.distance, gap, 1e-9) << gap;
    EXPECT_NEAR(p.c_f_P.x(), 0.01, 1e-9) << gap;
    EXPECT_NEAR(p.c_o_P.x(), 0.01 + gap, 1e-9) << gap;
    EXPECT_LT((p.normal_P - Vec3(1, 0, 0)).norm(), 1e-6) << gap;
  }
}

TEST(Contacts, CapsuleMergedAndAnalytic) {
  Fixture f;
  ASSERT_EQ(f.hand.links[f.link("capsule")].collision.size(), 1u);
  // Sphere object (r = 10 mm) beside the capsule's straight part, then beyond its end cap.
  ExpectPair(f.query.QueryPair(f.link("capsule"), 0, 1, Transform::Identity(), At(0.03, 0, 0.01)),
             0.015, Vec3(0.005, 0, 0.01), Vec3(0.02, 0, 0.01), Vec3(1, 0, 0));
  const Vec3 dir = Vec3(0.0, 0.03, 0.03).normalized();
  const ContactPair end =
      f.query.QueryPair(f.link("capsule"), 0, 1, Transform::Identity(), At(0, 0.03, 0.05));
  EXPECT_NEAR(end.distance, std::sqrt(2.0) * 0.03 - 0.015, 1e-9);
  EXPECT_LT((end.normal_P - dir).norm(), 1e-6);
}

TEST(Contacts, SpheresMatchTheFormulaAtRandomPoses) {
  Fixture f;
  for (int i = 0; i < 300; ++i) {
    const Transform T_PL = RandomPose(0.05), T_PO = RandomPose(0.05);
    const Vec3 a = T_PL.translation(), b = T_PO.translation();
    const double d = (b - a).norm() - 0.02;
    if (d < -0.01) continue;  // nearly concentric: no unique normal
    const ContactPair p = f.query.QueryPair(f.link("sphere"), 0, 1, T_PL, T_PO);
    const Vec3 n = (b - a).normalized();
    EXPECT_NEAR(p.distance, d, 1e-9);
    EXPECT_LT((p.normal_P - n).norm(), 1e-6);
    EXPECT_LT((p.c_f_P - (a + 0.01 * n)).norm(), 1e-8);
    EXPECT_LT((p.c_o_P - (b - 0.01 * n)).norm(), 1e-8);
  }
}

TEST(Contacts, DistanceIsInvariantUnderMovingTheWholeScene) {
  Fixture f;
  for (int i = 0; i < 100; ++i) {
    const Transform T_PL = RandomPose(0.02), T_PO = RandomPose(0.04), G = RandomPose(1.0);
    const ContactPair p = f.query.QueryPair(f.link("box"), 0, 0, T_PL, T_PO);
    const ContactPair q = f.query.QueryPair(f.link("box"), 0, 0, G * T_PL, G * T_PO);
    EXPECT_NEAR(p.distance, q.distance, 1e-8);
    // Witness points: c_f lies on the link box surface, c_o on the object box surface.
    const Vec3 f_local = T_PL.inverse() * p.c_f_P, o_local = T_PO.inverse() * p.c_o_P;
    EXPECT_NEAR(f_local.cwiseAbs().maxCoeff(), 0.01, 1e-7);
    EXPECT_NEAR(o_local.cwiseAbs().maxCoeff(), 0.05, 1e-7);
    EXPECT_NEAR((p.c_f_P - p.c_o_P).norm(), std::abs(p.distance), 1e-7);
  }
}

TEST(Contacts, BroadPhaseNeverDropsAPenetratingPair) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  BulletContactQuery query(hand, object);
  KinematicsData kin(hand);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<ContactPair> fast, slow;
  int penetrating = 0;
  for (int i = 0; i < 300; ++i) {
    Eigen::VectorXd q(hand.num_q());
    for (int j = 0; j < hand.num_q(); ++j) {
      const Joint& joint = hand.joints[hand.q_joints[j]];
      q[j] = joint.lower + (joint.upper - joint.lower) * u(test::Rng());
    }
    kin.Update(hand, q);
    // The bottle lying across the palm, somewhere the fingers reach.
    const Transform T_PO = MakeTransform(
        Vec3(-0.08 + 0.16 * u(test::Rng()), 0.02 + 0.1 * u(test::Rng()),
             0.02 + 0.04 * u(test::Rng())),
        ExpSO3(Vec3(0, M_PI / 2, 0) + 0.5 * Vec3(u(test::Rng()), u(test::Rng()), u(test::Rng()))));
    query.Query(kin.link_poses(), T_PO, 0.015, fast);
    query.QueryExhaustive(kin.link_poses(), T_PO, 0.015, slow);
    ASSERT_EQ(fast.size(), slow.size());
    for (std::size_t k = 0; k < fast.size(); ++k) {
      EXPECT_EQ(fast[k].link, slow[k].link);
      EXPECT_NEAR(fast[k].distance, slow[k].distance, 1e-12);
      penetrating += slow[k].distance < 0.0;
    }
  }
  EXPECT_GT(penetrating, 50);  // the poses do exercise penetrations
  EXPECT_GT(query.stats().pairs_skipped, 0);
}

TEST(Contacts, QueryAllocatesNothingAfterWarmUp) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object = LoadObjectModel(test::ProjectAsset("objects/brush/object.json"));
  BulletContactQuery query(hand, object);
  KinematicsData kin(hand);
  kin.Update(hand, Eigen::VectorXd::Constant(hand.num_q(), 0.4));
  std::vector<ContactPair> out;
  out.reserve(hand.links.size());
  const Transform T_PO = MakeTransform(Vec3(0.0, 0.06, 0.03), ExpSO3(Vec3(0, 0, 1.2)));
  query.Query(kin.link_poses(), T_PO, 0.02, out);
  const long before = test::AllocationCount();
  for (int i = 0; i < 50; ++i) query.Query(kin.link_poses(), T_PO, 0.02, out);
  EXPECT_EQ(test::AllocationCount() - before, 0);
  EXPECT_FALSE(out.empty());
}

}  // namespace
}  // namespace inhand
