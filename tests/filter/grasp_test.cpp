// Static grasps (issue 15): fingers closed until they touch an object at a known pose, so the
// truth fits the model, then the filter on constant joints.
//  - Honest under contradiction: the estimator's fingers are 3 mm thicker than the real ones,
//    so no pose satisfies every contact; the estimate must settle (not drift) and its NEES stay
//    within the chi-square bounds over 10 s.
//  - The Allegro hand around the YCB scans (../shared/assets): joints only, starts 10 mm / 5 deg
//    off, 10 runs per object; the terminal error is below the start in most runs and never
//    above twice the start.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include <Eigen/Cholesky>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

struct Grasp {
  Eigen::VectorXd q;
  Transform T_PO;
  int touching = 0;   // links within 0.3 mm of the object (or in it)
  std::string links;  // their names
  double shift = 0.0;
};

// Joints whose range is symmetric about 0 (abduction) stay at 0; the others close from near
// their lower limit towards the upper one; `fixed` sets some joints (the thumb's opposition).
// The object is placed at the palm, moved out along the direction the fingers close in until the
// open hand is clear of it, then every finger closes until a link it carries touches.
Grasp CloseAround(const HandModel& hand, BulletContactQuery& query, const Aabb& object_box,
                  const Mat3& R_PO, const std::map<std::string, double>& fixed,
                  double extra_shift) {
  const int n = hand.num_q();
  Eigen::VectorXd open(n), half(n), target(n);
  std::vector<bool> closes(static_cast<std::size_t>(n), false);
  for (int i = 0; i < n; ++i) {
    const Joint& j = hand.QJoint(i);
    const bool symmetric = std::abs(j.lower + j.upper) < 0.2 * (j.upper - j.lower);
    open[i] = half[i] = target[i] = symmetric ? 0.0 : j.lower + 0.05 * (j.upper - j.lower);
    if (!symmetric) {
      half[i] = j.lower + 0.5 * (j.upper - j.lower);
      target[i] = j.upper;
      closes[static_cast<std::size_t>(i)] = true;
    }
    const auto it = fixed.find(j.name);
    if (it != fixed.end()) {
      open[i] = half[i] = target[i] = it->second;
      closes[static_cast<std::size_t>(i)] = false;
    }
  }
  // The fingers' links move from c_open towards c_half as they close: that is the side of the
  // palm the object goes on.
  KinematicsData kin(hand);
  auto centroid = [&](const Eigen::VectorXd& q) {
    kin.Update(hand, q);
    Vec3 c = Vec3::Zero();
    int links = 0;
    for (std::size_t l = 0; l < hand.links.size(); ++l)
      if (!hand.links[l].collision.empty() && static_cast<int>(l) != hand.root_link)
        c += kin.T_PL(static_cast<int>(l)).translation(), ++links;
    return Vec3(c / links);
  };
  const Vec3 c_open = centroid(open);
  const Vec3 out = (centroid(half) - c_open).normalized();
  // From the palm's centre outwards: the object rests against the palm (a power grasp).
  Vec3 palm = Vec3::Zero();
  for (const ConvexPiece& p : hand.links[static_cast<std::size_t>(hand.root_link)].collision)
    palm += p.bounding_center;
  if (!hand.links[static_cast<std::size_t>(hand.root_link)].collision.empty())
    palm /=
        static_cast<double>(hand.links[static_cast<std::size_t>(hand.root_link)].collision.size());
  Grasp g;
  std::vector<ContactPair> pairs;
  kin.Update(hand, open);
  double shift = 0.0;
  for (; shift < 0.3; shift += 0.001) {
    g.T_PO = MakeTransform(palm + shift * out - R_PO * object_box.Center(), R_PO);
    query.Query(kin.link_poses(), g.T_PO, 0.0, pairs);
    if (pairs.empty()) break;
  }
  shift += extra_shift;
  g.T_PO = MakeTransform(palm + shift * out - R_PO * object_box.Center(), R_PO);
  // Close each joint in 0.004 rad steps while no link it carries is in contact.
  g.q = open;
  std::vector<bool> moving = closes;
  for (int step = 0; step < 2000; ++step) {
    bool any = false;
    for (int i = 0; i < n; ++i) {
      if (!moving[static_cast<std::size_t>(i)]) continue;
      Eigen::VectorXd trial = g.q;
      trial[i] = std::min(trial[i] + 0.004, target[i]);
      kin.Update(hand, trial);
      query.Query(kin.link_poses(), g.T_PO, 0.0, pairs);
      bool blocked = false;
      const int joint = hand.q_joints[static_cast<std::size_t>(i)];
      for (const ContactPair& p : pairs)
        for (int s : hand.support[static_cast<std::size_t>(p.link)])
          if (s == joint) blocked = true;
      if (blocked || trial[i] >= target[i]) {
        moving[static_cast<std::size_t>(i)] = false;
        if (!blocked) g.q = trial;
        continue;
      }
      g.q = trial;
      any = true;
    }
    if (!any) break;
  }
  kin.Update(hand, g.q);
  query.Query(kin.link_poses(), g.T_PO, 3e-4, pairs);
  g.touching = static_cast<int>(pairs.size());
  for (const ContactPair& p : pairs)
    g.links += hand.links[static_cast<std::size_t>(p.link)].name + " ";
  g.shift = shift;
  return g;
}

// The first grasp with `enough` touching links (else the one with the most) over placements 0-40 mm
// beyond the first clear one, the object as given or tipped by 90 degrees about x, turned about z
// in 45-degree steps.
Grasp BestGrasp(const HandModel& hand, BulletContactQuery& query, const Aabb& object_box,
                const Mat3& R0, const std::map<std::string, double>& fixed, int enough) {
  Grasp best;
  for (int tip = 0; tip < 2; ++tip)
    for (int turn = 0; turn < 4; ++turn)
      for (int extra = 0; extra <= 4; ++extra) {
        const Mat3 R =
            ExpSO3(Vec3(0, 0, turn * M_PI / 4)) * ExpSO3(Vec3(tip * M_PI / 2, 0, 0)) * R0;
        const Grasp g = CloseAround(hand, query, object_box, R, fixed, 0.01 * extra);
        if (g.touching > best.touching) best = g;
        if (best.touching >= enough) return best;
      }
  return best;
}

Vec6 BodyPoseError(const Transform& T_est, const Transform& T_true) {
  Vec6 e;
  e.head<3>() = T_est.translation() - T_true.translation();
  e.tail<3>() = LogSO3(T_true.linear().transpose() * T_est.linear());
  return e;
}

double Nees(const Filter& f, const Transform& T_true) {
  const Vec6 e = BodyPoseError(f.T_PO(), T_true);
  const Eigen::Matrix<double, 6, 6> P = f.covariance().topLeftCorner<6, 6>();
  return e.dot(P.ldlt().solve(e));
}

// The project's hand, its capsules `extra` thicker (the model the estimator gets).
HandModel ThickerHand(HandModel hand, double extra) {
  for (Link& link : hand.links)
    for (ConvexPiece& p : link.collision) {
      if (p.kind == ConvexPiece::Kind::kCapsule || p.kind == ConvexPiece::Kind::kSphere ||
          p.kind == ConvexPiece::Kind::kCylinder) {
        p = p.kind == ConvexPiece::Kind::kCapsule
                ? ConvexPiece::Capsule(p.radius + extra, p.half_length, p.T_BS)
            : p.kind == ConvexPiece::Kind::kSphere
                ? ConvexPiece::Sphere(p.radius + extra, p.T_BS)
                : ConvexPiece::Cylinder(p.radius + extra, p.half_length, p.T_BS);
      } else if (p.kind == ConvexPiece::Kind::kBox) {
        p = ConvexPiece::Box(p.half_extents + Vec3::Constant(extra), p.T_BS);
      }
    }
  return hand;
}

TEST(Grasp, ContradictoryContactsSettleAndStayConsistent) {
  const std::string root = test::SourceDir() + "/assets/";
  HandLoadOptions options;
  options.load_visual_meshes = false;
  const HandModel hand = LoadHandModel(root + "hands/inhand_hand/inhand_hand.urdf", options);
  const ObjectModel object = LoadObjectModel(root + "objects/water_bottle/object.json");
  BulletContactQuery truth_query(hand, object);
  const Grasp g = BestGrasp(hand, truth_query, object.Bounds(), ExpSO3(Vec3(0, M_PI / 2, 0)),
                            {{"thumb_abduction", 1.0}}, 6);
  ASSERT_GE(g.touching, 3) << "the fingers did not close on the object";
  std::printf("grasp: %s(shift %.3f)\n", g.links.c_str(), g.shift);

  const HandModel thick = ThickerHand(hand, 0.003);
  BulletContactQuery query(thick, object);
  Filter filter(thick, query, FilterParams(), FilterOptions{false});
  filter.Reset(g.T_PO, g.q, StartSigmas{0.01, 5.0 * M_PI / 180, 1e-9, {}});
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(hand.num_q());
  double worst_nees = 0.0, nees_sum = 0.0;
  int nees_n = 0;
  Transform at_5s;
  std::printf(
      "t [s] | position error [mm] | orientation error [deg] | sigma_p [mm] | NEES | penetration "
      "[mm]\n");
  for (int k = 1; k <= 10000; ++k) {
    filter.Predict(g.q, 0.001);
    filter.UpdateContacts(tau);
    if (k % 100 == 0) {
      const double nees = Nees(filter, g.T_PO);
      worst_nees = std::max(worst_nees, nees);
      nees_sum += nees, ++nees_n;
      if (k % 1000 == 0) {
        double deepest = 0.0;
        for (const auto& c : filter.trace().contacts) deepest = std::min(deepest, c.distance);
        const Vec6 e = BodyPoseError(filter.T_PO(), g.T_PO);
        std::printf("%4.1f | %5.2f | %5.2f | %5.2f | %6.2f | %5.2f\n", k * 1e-3,
                    e.head<3>().norm() * 1e3, e.tail<3>().norm() * 180 / M_PI,
                    std::sqrt(filter.covariance().topLeftCorner<3, 3>().trace() / 3) * 1e3, nees,
                    -deepest * 1e3);
      }
    }
    if (k == 5000) at_5s = filter.T_PO();
  }
  // The thicker fingers did push the estimate away from the truth (the test is not vacuous).
  EXPECT_GT(BodyPoseError(filter.T_PO(), g.T_PO).head<3>().norm(), 2e-3);
  // Settled: over the last 5 s it moves less than 1 mm and 1 deg.
  const Vec6 moved = BodyPoseError(filter.T_PO(), at_5s);
  EXPECT_LT(moved.head<3>().norm(), 1e-3);
  EXPECT_LT(moved.tail<3>().norm(), 1.0 * M_PI / 180);
  // NEES of the 6-D pose error: every 0.1 s below chi2_6 at 99.9 % (22.46), the mean below the
  // 99 % bound of a mean of 100 (correlated) samples' expectation, 6 -> below 15 as issue 16 asks.
  EXPECT_LT(worst_nees, chi2::k6Dof999);
  EXPECT_LT(nees_sum / nees_n, 15.0);
}

// The Allegro hand around the YCB scans: joints only, 10 starts per object.
TEST(Grasp, AllegroStaticGraspsAroundYcbScans) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string shared = test::SharedAssets();
  HandLoadOptions options;
  options.load_visual_meshes = false;
  const HandModel hand =
      LoadHandModel(shared + "/hands/allegro_hand/allegro_hand_right.urdf", options);
  std::printf("object | run | start [mm, deg] | terminal [mm, deg]\n");
  for (const char* name : {"mustard_bottle", "bleach_cleanser", "large_marker"}) {
    const ObjectModel object = LoadObjectModel(shared + "/objects/ycb/" + name + ".urdf");
    BulletContactQuery query(hand, object);
    const Grasp g =
        BestGrasp(hand, query, object.Bounds(), Mat3::Identity(), {{"joint_12.0", 1.3}}, 4);
    std::printf("%s grasp: %s(shift %.3f)\n", name, g.links.c_str(), g.shift);
    ASSERT_GE(g.touching, 3) << name << ": the fingers did not close on the object";
    std::mt19937 rng(15);
    std::normal_distribution<double> normal;
    int better = 0;
    for (int run = 0; run < 10; ++run) {
      Vec3 dp(normal(rng), normal(rng), normal(rng)), dr(normal(rng), normal(rng), normal(rng));
      dp = dp.normalized() * 0.010;
      dr = dr.normalized() * (5.0 * M_PI / 180);
      const Transform start =
          MakeTransform(g.T_PO.translation() + dp, g.T_PO.linear() * ExpSO3(dr));
      Filter filter(hand, query, FilterParams(), FilterOptions{false});
      filter.Reset(start, g.q, StartSigmas{0.01, 5.0 * M_PI / 180, 1e-9, {}});
      const Eigen::VectorXd tau = Eigen::VectorXd::Zero(hand.num_q());
      for (int k = 0; k < 3000; ++k) {
        filter.Predict(g.q, 0.001);
        filter.UpdateContacts(tau);
      }
      const Vec6 e0 = BodyPoseError(start, g.T_PO), e1 = BodyPoseError(filter.T_PO(), g.T_PO);
      const double p0 = e0.head<3>().norm(), p1 = e1.head<3>().norm();
      const double r0 = e0.tail<3>().norm(), r1 = e1.tail<3>().norm();
      std::printf("%s | %d | %.1f, %.1f | %.1f, %.1f\n", name, run, p0 * 1e3, r0 * 180 / M_PI,
                  p1 * 1e3, r1 * 180 / M_PI);
      better += p1 < p0;
      EXPECT_LT(p1, 2.0 * p0) << name << " run " << run;
      EXPECT_LT(r1, 2.0 * r0) << name << " run " << run;
    }
    EXPECT_GE(better, 6) << name;
  }
}

}  // namespace
}  // namespace inhand
