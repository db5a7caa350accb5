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

// The project's palm is a box 86 x 96 x 30 mm centred at (0, 48, -15) mm, and its fingers close
// towards +z (assets/tools/generate_assets.py): the thinnest direction of the box, signed by the
// fingertips of a curled hand.
TEST(HandFingers, ThePalmsGraspSideIsWhereTheFingersClose) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const HandFingers fingers(hand);
  ASSERT_EQ(fingers.palm, hand.LinkIndex("palm"));
  EXPECT_LT((fingers.palm_centre_L - Vec3(0.0, 0.048, -0.015)).norm(), 5e-4);
  EXPECT_GT(std::abs(fingers.palm_normal_L.z()), std::cos(5.0 * M_PI / 180.0));
  KinematicsData kin(hand);
  for (const double curl : {0.2, 0.5, 0.9}) {
    Eigen::VectorXd q(hand.num_q());
    for (int j = 0; j < hand.num_q(); ++j)
      q[j] = hand.QJoint(j).lower + curl * (hand.QJoint(j).upper - hand.QJoint(j).lower);
    kin.Update(hand, q);
    const auto [centre, normal] = fingers.GraspSide(kin.link_poses());
    EXPECT_LT((centre - Vec3(0.0, 0.048, -0.015)).norm(), 5e-4) << "curl " << curl;
    EXPECT_GT(normal.z(), std::cos(5.0 * M_PI / 180.0)) << "curl " << curl;
  }
}

// Third-party hands: the Allegro's palm faces +x of its base link (its fingers point along +z
// and curl toward +x), the Barrett's +z (its fingers rise from the palm and close over it). The
// Shadow hand's URDF hangs every link from its wrist joints, which makes it one finger here:
// no grasp side, so a start inside the object is left to the filter.
TEST(HandFingers, ThirdPartyPalmsFaceWhereTheirFingersClose) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  struct Case {
    const char* urdf;
    const char* palm;
    Vec3 normal;
  };
  for (const Case& c : {Case{"allegro_hand/allegro_hand_right.urdf", "base_link", Vec3::UnitX()},
                        Case{"allegro_hand/allegro_hand_left.urdf", "base_link", Vec3::UnitX()},
                        Case{"allegro_hand_description/allegro_hand_description_right.urdf",
                             "base_link", Vec3::UnitX()},
                        Case{"barrett_hand/bhand_model.urdf", "base_link", Vec3::UnitZ()}}) {
    const HandModel hand = LoadHandModel(hands + c.urdf, {{}, false});
    const HandFingers fingers(hand);
    ASSERT_GE(fingers.palm, 0) << c.urdf;
    EXPECT_EQ(hand.links[static_cast<std::size_t>(fingers.palm)].name, c.palm) << c.urdf;
    EXPECT_GT(fingers.palm_normal_L.dot(c.normal), std::cos(15.0 * M_PI / 180.0)) << c.urdf;
  }
  const HandFingers shadow(LoadHandModel(hands + "shadow_hand/shadow_hand_left.urdf", {{}, false}));
  EXPECT_EQ(shadow.size(), 1);
  EXPECT_TRUE(shadow.palm_normal_L.isZero());
}

// A start with the palm deep inside the bottle and the bottle's centre just behind the palm's
// middle: settled by itself it leaves through the back of the palm. SettleStart puts it on the
// grasp side, with nothing inside, nearer the pose it came from. A start with nothing deep inside,
// or one whose own way out is the nearest on the grasp side, is kept as it is.
TEST(HandPlausibility, ADeepStartIsSettledOnTheGraspSide) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::ProjectAsset("objects/shampoo_bottle/object.json"));
  BulletContactQuery query(hand, object);
  HandPlausibility plausibility(hand, query);
  KinematicsData kin(hand);
  Eigen::VectorXd q(hand.num_q());
  for (int j = 0; j < hand.num_q(); ++j)
    q[j] = hand.QJoint(j).lower + 0.3 * (hand.QJoint(j).upper - hand.QJoint(j).lower);
  kin.Update(hand, q);
  const std::vector<Transform>& T_PL = kin.link_poses();
  const HealthParams p;
  const double reach = 0.15, sigma = 0.02;
  const Eigen::VectorXd no_torque;
  const Vec3 centre_O = object.Bounds().Center();
  const auto [palm_c, normal] = plausibility.fingers().GraspSide(T_PL);
  const auto side = [&](const Transform& T) { return (T * centre_O - palm_c).dot(normal); };
  // The bottle lying across the palm, its axis along the palm's x, in front of it where nothing
  // touches it.
  Transform truth = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0.0, M_PI / 2, 0.0)));
  for (double z = 0.0; z < 0.3; z += 0.001) {
    truth.translation() = palm_c + Vec3(0.01, 0.0, z) - truth.linear() * centre_O;
    if (plausibility.Score(no_torque, T_PL, truth, p, reach).penetration == 0.0) break;
  }
  ASSERT_EQ(plausibility.Score(no_torque, T_PL, truth, p, reach).penetration, 0.0);
  const HandPlausibility::StartChoice kept =
      plausibility.SettleStart(no_torque, T_PL, truth, centre_O, sigma, p, reach);
  EXPECT_EQ(kept.hypothesis, -1);
  EXPECT_TRUE(kept.T_PO.matrix() == truth.matrix());

  Transform start = truth;
  start.translation() += (-side(truth) - 0.003) * normal;  // the centre 3 mm behind the middle
  const HandPlausibility::StartChoice choice =
      plausibility.SettleStart(no_torque, T_PL, start, centre_O, sigma, p, reach);
  ASSERT_GT(choice.penetration, 0.01);
  const Transform alone = plausibility.Settle(no_torque, T_PL, start, p, reach);
  EXPECT_LT(side(alone), 0.0);  // what the start alone comes to: behind the palm
  ASSERT_GE(choice.hypothesis, 0);
  EXPECT_GT(side(choice.T_PO), 0.0);
  EXPECT_LE(plausibility.Score(no_torque, T_PL, choice.T_PO, p, reach).penetration, p.penetration);
  EXPECT_TRUE(choice.T_PO.linear().isApprox(start.linear()));
  EXPECT_LT((choice.T_PO.translation() - truth.translation()).norm(),
            (alone.translation() - truth.translation()).norm());
  // Within the hypotheses' reach: 2 sigma along an axis, then out of the palm.
  EXPECT_LT((choice.T_PO.translation() - start.translation()).norm(), 2.0 * sigma + 0.06);

  // 12 mm into the palm from the front: its own way out is the nearest, and the filter's contact
  // updates take it themselves.
  Transform shallow = truth;
  shallow.translation() -= 0.012 * normal;
  const HandPlausibility::StartChoice own =
      plausibility.SettleStart(no_torque, T_PL, shallow, centre_O, sigma, p, reach);
  ASSERT_GT(own.penetration, p.penetration);
  EXPECT_EQ(own.hypothesis, -1);
  EXPECT_TRUE(own.T_PO.matrix() == shallow.matrix());
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
