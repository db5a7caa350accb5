// Whether a pose explains the hand (filter/plausibility.hpp): its penetration against brute
// force (every link piece filled with a grid of points, each looked up in the object's distance
// field), its pressing gaps against the exhaustive query, and the settled pose against what it
// promises (the pressing finger on the surface, no link inside), on the project's hand with its
// ketchup bottle and with a YCB scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/distance_field.hpp"
#include "inhand/filter/health.hpp"
#include "inhand/filter/plausibility.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

constexpr double kGrid = 0.001;  // [m] the brute force's grid: its depth is low by <= 0.87 mm
// [m] Both sides sample: the grid above, and the query's probes (a hull's surface samples, a
// capsule's segment every half field step) on a field of 1 mm nodes, interpolated.
constexpr double kTolerance = 0.0015;

// The deepest point of any link inside the object: the largest -field(x) over a grid of
// points inside each link piece (PieceSignedDistance <= 0), the link that holds it.
std::pair<double, int> BruteForcePenetration(const HandModel& hand,
                                             const std::vector<Transform>& T_PL,
                                             const Transform& T_PO, const DistanceField& field) {
  double deepest = 0.0;
  int link = -1;
  const Transform T_OP = T_PO.inverse();
  for (std::size_t l = 0; l < hand.links.size(); ++l)
    for (const ConvexPiece& piece : hand.links[l].collision) {
      const Transform T_OL = T_OP * T_PL[l];
      // Skip pieces that the field's 1-Lipschitz bound puts outside.
      if (field.Distance(T_OL * piece.bounding_center) > piece.bounding_radius) continue;
      const double r = piece.bounding_radius;
      const int n = static_cast<int>(std::ceil(r / kGrid));
      for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
          for (int k = -n; k <= n; ++k) {
            const Vec3 x_L = piece.bounding_center + kGrid * Vec3(i, j, k);
            if ((x_L - piece.bounding_center).norm() > r) continue;
            if (PieceSignedDistance(piece, x_L) > 0.0) continue;
            const double d = -field.Distance(T_OL * x_L);
            if (d > deepest) deepest = d, link = static_cast<int>(l);
          }
    }
  return {deepest, link};
}

Eigen::VectorXd RandomConfiguration(const HandModel& hand, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(hand.num_q());
  for (int j = 0; j < hand.num_q(); ++j) {
    const Joint& joint = hand.QJoint(j);
    q[j] = joint.lower + (joint.upper - joint.lower) * u(rng);
  }
  return q;
}

void ComparePenetration(const HandModel& hand, const ObjectModel& object) {
  ASSERT_TRUE(object.field && !object.field->empty());
  BulletContactQuery query(hand, object);
  HandPlausibility plausibility(hand, query);
  KinematicsData kin(hand);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  HealthParams p;
  const Eigen::VectorXd no_torque = Eigen::VectorXd::Zero(hand.num_q());
  const Vec3 centre_O = object.Bounds().Center();
  int deep = 0, clear = 0;
  for (int i = 0; i < 80; ++i) {
    kin.Update(hand, RandomConfiguration(hand, rng));
    // The object's centre near a random link: most poses put a link inside it.
    const int near = static_cast<int>((u(rng) + 1.0) * 0.5 * (hand.links.size() - 1));
    const Mat3 R = ExpSO3(Vec3(u(rng), u(rng), u(rng)));
    Transform T_PO = MakeTransform(Vec3::Zero(), R);
    // The link's origin within 12 mm inside the surface or 2 mm outside (every 4th pose: the
    // object 15 cm away).
    const Vec3 origin = kin.link_poses()[static_cast<std::size_t>(near)].translation();
    for (int tries = 0; tries < 200; ++tries) {
      const double offset = i % 4 == 3 ? 0.15 : 0.08 * (u(rng) + 1.0) * 0.5;
      T_PO.translation() =
          origin + offset * Vec3(u(rng), u(rng), u(rng)).normalized() - R * centre_O;
      const double d = object.field->Distance(T_PO.inverse() * origin);
      if (i % 4 == 3 || (d > -0.012 && d < 0.002)) break;
    }
    const Plausibility s = plausibility.Score(no_torque, kin.link_poses(), T_PO, p, 0.05);
    const auto [brute, link] = BruteForcePenetration(hand, kin.link_poses(), T_PO, *object.field);
    EXPECT_EQ(s.pressing, 0);
    // The query's depth is the field at a link's core less the core's radius (a capsule's
    // segment, a sphere's centre; a hull's surface samples): never shallower than the deepest
    // point inside the link, and that deep until the core's ball reaches the object's medial
    // axis (the bottles' inscribed radius, ~24 mm, caps the true depth).
    EXPECT_GE(s.penetration, brute - kTolerance) << "pose " << i;
    if (brute > 0.015) continue;
    EXPECT_LE(s.penetration, brute + kTolerance) << "pose " << i;
    if (brute > 0.003) {
      ++deep;
      EXPECT_GE(s.penetration_link, 0);
      // The deepest link is the brute force's, unless another lies within its grid error.
      if (s.penetration_link != link) {
        EXPECT_LT(s.penetration - brute, kTolerance) << "pose " << i;
      }
    }
    clear += brute == 0.0 && s.penetration < 1e-3;
  }
  EXPECT_GE(deep, 5);  // both outcomes exercised
  EXPECT_GE(clear, 5);
}

TEST(HandPlausibility, PenetrationAgreesWithBruteForceOnTheProjectsHand) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  ComparePenetration(hand, object);
}

TEST(HandPlausibility, PenetrationAgreesWithBruteForceOnAYcbScan) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::SharedAssets() + "/objects/ycb/mustard_bottle.urdf");
  ComparePenetration(hand, object);
}

// One finger presses, the object some distance from it: Score's gap is that finger's nearest
// pair in the exhaustive query, and Settle puts the object on that link without a link inside
// it whenever the translation along the pair's normal does so.
void CheckSettle(const HandModel& hand, const ObjectModel& object) {
  BulletContactQuery query(hand, object);
  HandPlausibility plausibility(hand, query);
  const HandFingers& fingers = plausibility.fingers();
  ASSERT_GE(fingers.size(), 2);
  KinematicsData kin(hand);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  HealthParams p;
  const double reach = 0.15;
  const Vec3 centre_O = object.Bounds().Center();
  std::vector<ContactPair> all;
  int settled = 0;
  for (int i = 0; i < 4000 && settled < 20; ++i) {
    kin.Update(hand, RandomConfiguration(hand, rng));
    const Mat3 R = ExpSO3(Vec3(u(rng), u(rng), u(rng)));
    Transform T_PO = MakeTransform(Vec3(0.0, 0.06, 0.06) + 0.06 * Vec3(u(rng), u(rng), u(rng)), R);
    T_PO.translation() -= R * centre_O;
    const int finger = static_cast<int>((u(rng) + 1.0) * 0.5 * fingers.size()) % fingers.size();
    Eigen::VectorXd tau = Eigen::VectorXd::Constant(hand.num_q(), 0.1);
    tau[fingers.finger_q[static_cast<std::size_t>(finger)].back()] = -0.9;
    query.QueryExhaustive(kin.link_poses(), T_PO, reach, all);
    const ContactPair* nearest = nullptr;
    double deepest = 0.0;
    for (const ContactPair& c : all) {
      deepest = std::max(deepest, -c.distance);
      if (fingers.link_finger[static_cast<std::size_t>(c.link)] == finger &&
          (!nearest || c.distance < nearest->distance))
        nearest = &c;
    }
    const Plausibility s = plausibility.Score(tau, kin.link_poses(), T_PO, p, reach);
    ASSERT_EQ(s.pressing, 1);
    EXPECT_NEAR(s.pressing_gap, nearest ? nearest->distance : reach, 1e-9) << "pose " << i;
    EXPECT_NEAR(s.penetration, deepest, 1e-9) << "pose " << i;
    if (!nearest || deepest > 0.0 || nearest->distance < 0.005) continue;
    // Where the translation along the normal leaves the object touching and nothing inside.
    Transform T_touch = T_PO;
    T_touch.translation() -= nearest->normal_P * nearest->distance;
    const Plausibility touching = plausibility.Score(tau, kin.link_poses(), T_touch, p, reach);
    if (touching.penetration > 5e-4 || std::abs(touching.pressing_gap) > 5e-4) continue;
    const Transform T = plausibility.Settle(tau, kin.link_poses(), T_PO, p, reach);
    const Plausibility after = plausibility.Score(tau, kin.link_poses(), T, p, reach);
    EXPECT_LT(std::abs(after.pressing_gap), 1e-3)
        << "pose " << i << ", gap before " << nearest->distance;
    EXPECT_LT(after.penetration, 1e-3) << "pose " << i;
    EXPECT_EQ(after.Excess(p), 0.0);
    // A translation only, no longer than the gap it closed (plus the damping's slack).
    EXPECT_TRUE(T.linear().isApprox(T_PO.linear()));
    EXPECT_LT((T.translation() - T_PO.translation()).norm(), nearest->distance + 2e-3);
    ++settled;
  }
  EXPECT_GE(settled, 10);
}

TEST(HandPlausibility, SettlesOntoThePressingFingerOnTheProjectsHand) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  CheckSettle(hand, LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json")));
}

TEST(HandPlausibility, SettlesOntoThePressingFingerOnAYcbScan) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  CheckSettle(hand, LoadObjectModel(test::SharedAssets() + "/objects/ycb/mustard_bottle.urdf"));
}

TEST(HandPlausibility, ExcessCountsOnlyWhatTheThresholdsDoNotAdmit) {
  HealthParams p;
  Plausibility s;
  EXPECT_EQ(s.Excess(p), 0.0);
  s.penetration = p.penetration + 0.002;
  EXPECT_NEAR(s.Excess(p), 0.002, 1e-12);
  s.pressing_gap = p.press_gap + 0.03;  // nobody presses: the gap does not count
  EXPECT_NEAR(s.Excess(p), 0.002, 1e-12);
  s.pressing = 1;
  EXPECT_NEAR(s.Excess(p), 0.032, 1e-12);
}

}  // namespace
}  // namespace inhand
