// The estimate's health (filter/health.hpp): the monitor's rules on their own, the press check
// against brute force, and a tracker on a recording with faults injected, each declared within
// 0.5 s, the clean recording declaring none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/core/error.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/filter/health.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "recording.hpp"

namespace inhand {
namespace {

using test::Recording;

// A fault injected into the recording over [from, to).
struct Fault {
  double from = 1e9, to = 1e9;
  Vec3 camera_shift = Vec3::Zero();  // [m] added to the camera position (palm frame)
  bool freeze = false;               // every image from `from` on is the one before it
  bool cover = false;                // every image from `from` on is a plain grey frame, noisy
  int joint = -1;                    // configuration entry offset by joint_offset [rad]
  double joint_offset = 0.0;
  double torque_scale = 1.0;  // every joint torque multiplied by this
  bool Active(double t) const { return t >= from - 1e-9 && t < to - 1e-9; }
};

struct Timeline {
  std::vector<double> t;
  std::vector<Health> health;
  std::vector<TrackerEvent> events;  // the tracker's (Tracker::TakeEvents), bursts closed
  // The first event of `kind` at or after t0; +inf when none.
  double FirstEvent(double t0, EventKind kind) const {
    for (const TrackerEvent& e : events)
      if (e.kind == kind && e.t >= t0 - 1e-9) return e.t;
    return INFINITY;
  }
  // The first sample at or after t0 whose health satisfies `is`; +inf when none.
  template <typename Is>
  double First(double t0, Is&& is) const {
    for (std::size_t i = 0; i < t.size(); ++i)
      if (t[i] >= t0 - 1e-9 && is(health[i])) return t[i];
    return INFINITY;
  }
};

Timeline Replay(const Recording& r, const std::string& set, const Fault& fault, int n = -1) {
  auto tracker = test::Make(r, set);
  const auto& frames = r.session.camera_frames();
  const int samples = n < 0 ? r.session.num_samples() : n;
  std::size_t next = 0;
  int frozen = -1;
  Timeline out;
  for (int k = 0; k < samples; ++k) {
    const double t = r.session.t(k);
    Eigen::VectorXd q = r.q[static_cast<std::size_t>(k)];
    if (fault.joint >= 0 && fault.Active(t)) q[fault.joint] += fault.joint_offset;
    Eigen::VectorXd tau = r.tau[static_cast<std::size_t>(k)];
    if (fault.Active(t)) tau *= fault.torque_scale;
    tracker->AddJointSample(t, q, tau);
    const bool vision = tracker->modalities().tags || tracker->modalities().features;
    while (vision && next < frames.size() && frames[next].t <= t + 1e-9) {
      Transform T_PC = frames[next].T_PC;
      if (fault.Active(frames[next].t)) T_PC.translation() += fault.camera_shift;
      int image = static_cast<int>(next);
      if (fault.freeze && fault.Active(frames[next].t)) {
        if (frozen < 0) frozen = std::max(0, image - 1);
        image = frozen;
      }
      const Image8& pixels = r.images[static_cast<std::size_t>(image)];
      Image8 grey;
      if (fault.cover && fault.Active(frames[next].t)) {
        grey = pixels;  // grey with a sensor's noise (identical frames would be frozen ones)
        std::uint32_t state = 12345u + static_cast<std::uint32_t>(next);
        for (std::uint8_t& v : grey.data) {
          state = state * 1664525u + 1013904223u;
          v = static_cast<std::uint8_t>(126 + (state >> 30));
        }
      }
      tracker->AddImage(frames[next].t, grey.data.empty() ? pixels : grey, T_PC,
                        *r.session.info().camera);
      ++next;
    }
    out.t.push_back(t);
    out.health.push_back(tracker->health());
    tracker->TakeEvents(out.events);
  }
  tracker->CloseEvents();
  tracker->TakeEvents(out.events);
  return out;
}

std::string Describe(const Timeline& tl, const HandModel& hand) {
  std::string s;
  HealthState last = HealthState::kOk;
  HealthCause cause = HealthCause::kNone;
  for (std::size_t i = 0; i < tl.t.size(); ++i)
    if (i == 0 || tl.health[i].state != last || tl.health[i].cause != cause) {
      last = tl.health[i].state, cause = tl.health[i].cause;
      s += "  t " + std::to_string(tl.t[i]) + ": " + HealthMessage(tl.health[i], hand) + "\n";
    }
  return s;
}

// --- the monitor's rules, on inputs whose answer is known

FilterTrace Penetrating(double depth, int link) {
  FilterTrace trace;
  trace.penetration = depth;
  FilterTrace::Contact c;
  c.link = link;
  c.distance = -depth;
  trace.contacts.push_back(c);
  return trace;
}

const Vec3 kNarrow = Vec3::Constant(0.002);  // σ well inside HealthParams' bounds

TEST(HealthMonitor, ALinkDeepInsideIsInconsistentAfterSustainThenLost) {
  HealthParams p;
  HealthMonitor m(p);
  m.Reset(0.0);
  double t = 0.0;
  for (; t < 0.05; t += 0.002) m.OnSample(t, Penetrating(0.003, 2), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);  // 3 mm: within what a closing finger does
  const double onset = t;
  for (; t < onset + p.sustain - 0.004; t += 0.002)
    m.OnSample(t, Penetrating(0.008, 2), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);  // not yet sustained
  for (; t < onset + p.sustain + 0.01; t += 0.002)
    m.OnSample(t, Penetrating(0.008, 2), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kInconsistent);
  EXPECT_EQ(m.health().cause, HealthCause::kPenetration);
  EXPECT_EQ(m.health().subject, 2);
  EXPECT_DOUBLE_EQ(m.health().value, 0.008);
  const double inconsistent_since = m.health().since;
  EXPECT_NEAR(inconsistent_since, onset + p.sustain, 0.003);
  for (; t < inconsistent_since + p.lost_after - 0.004; t += 0.002)
    m.OnSample(t, Penetrating(0.008, 2), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kInconsistent);
  for (; t < inconsistent_since + p.lost_after + 0.01; t += 0.002)
    m.OnSample(t, Penetrating(0.008, 2), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kLost);
  m.OnSample(t, FilterTrace(), kNarrow, kNarrow);  // resolved: ok again at once
  EXPECT_EQ(m.health().state, HealthState::kOk);
  EXPECT_DOUBLE_EQ(m.health().since, t);
}

TEST(HealthMonitor, EachConditionDecidesItsStateAndTheWorstWins) {
  HealthParams p;
  HealthMonitor m(p);
  m.Reset(0.0);
  m.OnSample(0.0, FilterTrace(), Vec3(0.002, 0.015, 0.002), kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kUncertain);
  EXPECT_EQ(m.health().cause, HealthCause::kWideSigma);
  EXPECT_DOUBLE_EQ(m.health().value, 0.015);
  m.OnSample(0.01, FilterTrace(), kNarrow, Vec3(0.0, 0.5, 0.0));
  EXPECT_EQ(m.health().cause, HealthCause::kWideSigma);
  EXPECT_EQ(m.health().subject, 1);  // the orientation
  // Images: frozen after images_frozen identical ones, stale after images_stale without one.
  double t = 0.1;
  for (int i = 0; i < p.images_frozen; ++i, t += 0.1) {
    EXPECT_NE(m.health().cause, HealthCause::kImagesFrozen);
    m.OnImageAdded(t, 42);
    m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  }
  EXPECT_EQ(m.health().cause, HealthCause::kImagesFrozen);
  m.OnImageAdded(t, 43);
  m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
  m.OnSample(t + p.images_stale - 0.01, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
  m.OnSample(t + p.images_stale + 0.01, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().cause, HealthCause::kImagesStale);
  // Vision: over the window, more than vision_gated_share of the offered features gated.
  t += 0.4;
  for (int i = 0; i < p.vision_window; ++i, t += 0.1) {
    m.OnImageAdded(t, 100 + static_cast<unsigned long long>(i));
    // 10 + 8 of 50 used; the gated images put the object 20 mm away, the good one 1 mm.
    m.OnImage({t, 10, i < 1 ? 10 : 2, false, false, 0.0, i < 1 ? 0.001 : 0.020});
    m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  }
  EXPECT_EQ(m.health().state, HealthState::kInconsistent);
  EXPECT_EQ(m.health().cause, HealthCause::kVisionDisagrees);
  EXPECT_NEAR(m.health().value, 1.0 - 18.0 / 50.0, 1e-12);
  // Its distance, for the claim: the window's images' displacement, averaged.
  EXPECT_NEAR(m.health().distance, (0.001 + 4 * 0.020) / 5, 1e-12);
  EXPECT_NEAR(HealthPositionSigma(m.health()), (0.001 + 4 * 0.020) / 5, 1e-12);
  // The worst wins: a penetration beside the gated vision stays inconsistent; the grip loosening
  // (uncertain) does not lower it.
  FilterTrace slipping;
  slipping.slipping = true;
  m.OnSample(t, slipping, kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kInconsistent);
  // Good images again: uncertain for the slip, then ok after slip_hold.
  for (int i = 0; i < p.vision_window; ++i, t += 0.02) {
    m.OnImageAdded(t, 200 + static_cast<unsigned long long>(i));
    m.OnImage({t, 10, 10, false, false, 0.0});
  }
  m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().cause, HealthCause::kSlipping);
  m.OnSample(t + p.slip_hold + 0.01, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
  // Vision blind: a full window whose images fused fewer than vision_min_used together; not
  // before the window is full, and ok again once an image fuses enough.
  t += p.slip_hold + 0.02;
  for (int i = 0; i < p.vision_window; ++i, t += 0.02) {
    m.OnImageAdded(t, 250 + static_cast<unsigned long long>(i));
    m.OnImage({t, 2, 1, false, false, 0.0});
    m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
    if (i < p.vision_window - 1) {
      EXPECT_NE(m.health().cause, HealthCause::kVisionBlind) << i;  // 10 fused remain in it
    }
  }
  EXPECT_EQ(m.health().state, HealthState::kUncertain);
  EXPECT_EQ(m.health().cause, HealthCause::kVisionBlind);
  EXPECT_DOUBLE_EQ(m.health().value, p.vision_window);
  m.OnImageAdded(t, 260);
  m.OnImage({t, 8, 4, false, false, 0.0});  // 4 + 4 × 1 fused: enough
  m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
  for (int i = 0; i < p.vision_window; ++i, t += 0.02) {
    m.OnImageAdded(t, 270 + static_cast<unsigned long long>(i));
    m.OnImage({t, 10, 10, false, false, 0.0});
  }
  // Tags elsewhere: inconsistent; found again: uncertain for relocalized_hold.
  t += p.slip_hold + 0.02;
  m.OnImageAdded(t, 300);
  m.OnImage({t, 4, 0, false, true, 0.0});
  m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().cause, HealthCause::kTagsElsewhere);
  m.OnImageAdded(t + 0.1, 301);
  m.OnImage({t + 0.1, 0, 0, false, false, 0.04});
  m.OnSample(t + 0.1, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().cause, HealthCause::kRelocalized);
  EXPECT_DOUBLE_EQ(m.health().value, 0.04);
  m.OnImageAdded(t + 0.2, 302);
  m.OnImage({t + 0.2, 0, 0, false, false, 0.0});
  m.OnImageAdded(t + 0.1 + p.relocalized_hold + 0.01, 303);
  m.OnSample(t + 0.1 + p.relocalized_hold + 0.01, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
}

TEST(HealthMonitor, ASetWithoutImagesIsNeverBlindAndZeroTurnsTheCheckOff) {
  HealthParams p;
  HealthMonitor m(p);
  m.Reset(0.0);
  for (double t = 0.0; t < 2.0; t += 0.01) m.OnSample(t, FilterTrace(), kNarrow, kNarrow);
  EXPECT_EQ(m.health().state, HealthState::kOk);
  p.vision_min_used = 0;
  HealthMonitor off(p);
  off.Reset(0.0);
  for (int i = 0; i < 2 * p.vision_window; ++i) {
    off.OnImageAdded(0.1 * i, 1000 + static_cast<unsigned long long>(i));
    off.OnImage({0.1 * i, 0, 0, false, false, 0.0});
    off.OnSample(0.1 * i, FilterTrace(), kNarrow, kNarrow);
  }
  EXPECT_EQ(off.health().state, HealthState::kOk);
  p.vision_min_used = -1;
  EXPECT_THROW(p.Validate(), InputError);
}

TEST(HealthMonitor, MessagesNameTheLinkAndTheFigure) {
  HandModel hand;
  hand.links.resize(3);
  hand.links[2].name = "thumb_tip";
  Health h;
  h.state = HealthState::kInconsistent;
  h.cause = HealthCause::kPressingInAir;
  h.value = 0.0231;
  h.subject = 2;
  h.since = 1.2;
  EXPECT_EQ(HealthMessage(h, hand),
            "inconsistent since 1.20 s: thumb_tip presses but the object is 23.1 mm from it");
  EXPECT_STREQ(HealthCauseName(HealthCause::kVisionDisagrees), "vision_disagrees");
  EXPECT_STREQ(HealthCauseName(HealthCause::kVisionBlind), "vision_blind");
  h.state = HealthState::kUncertain;
  h.cause = HealthCause::kVisionBlind;
  h.value = 3;
  EXPECT_EQ(HealthMessage(h, hand),
            "uncertain since 1.20 s: the last images fused 3 points of the object, too few to "
            "check the estimate");
  h.value = 1;
  EXPECT_EQ(HealthMessage(h, hand),
            "uncertain since 1.20 s: the last images fused 1 point of the object, too few to "
            "check the estimate");
  EXPECT_STREQ(HealthStateName(HealthState::kLost), "lost");
  HealthParams bad;
  bad.press_gap = 0.0;
  EXPECT_THROW(bad.Validate(), InputError);
}

// --- the press check against brute force: the exhaustive query, per finger

void ComparePressCheck(const HandModel& hand, const ObjectModel& object, const Vec3& centre) {
  BulletContactQuery query(hand, object);
  PressCheck check(hand);
  ASSERT_GE(check.num_fingers(), 2);
  KinematicsData kin(hand);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  HealthParams p;
  std::vector<ContactPair> all;
  int in_air = 0, near = 0;
  for (int i = 0; i < 200; ++i) {
    Eigen::VectorXd q(hand.num_q());
    for (int j = 0; j < hand.num_q(); ++j) {
      const Joint& joint = hand.QJoint(j);
      q[j] = joint.lower + (joint.upper - joint.lower) * u(rng);
    }
    kin.Update(hand, q);
    const Transform T_PO =
        MakeTransform(centre + Vec3(0.1 * u(rng) - 0.05, 0.1 * u(rng) - 0.05, 0.1 * u(rng) - 0.05),
                      ExpSO3(Vec3(u(rng), u(rng), u(rng))));
    // One joint presses; the others carry less than press_torque.
    const int pressing = static_cast<int>(u(rng) * hand.num_q()) % hand.num_q();
    Eigen::VectorXd tau = Eigen::VectorXd::Constant(hand.num_q(), 0.1);
    tau[pressing] = -0.9;
    const PressEvidence e = check.Measure(tau, kin.link_poses(), T_PO, FilterTrace(), query, p);
    ASSERT_TRUE(e.pressing);
    EXPECT_DOUBLE_EQ(e.torque, 0.9);
    // Brute force: the links whose chains hold the pressing joint's finger (same first joint).
    const int first = [&] {
      for (std::size_t l = 0; l < hand.links.size(); ++l)
        for (int jj : hand.support[l])
          if (jj == hand.q_joints[pressing]) return hand.support[l].front();
      return -1;
    }();
    query.QueryExhaustive(kin.link_poses(), T_PO, p.press_reach, all);
    double gap = p.press_reach;
    int link = -1;
    for (const ContactPair& c : all)
      if (!hand.support[c.link].empty() && hand.support[c.link].front() == first &&
          c.distance < gap)
        gap = c.distance, link = c.link;
    EXPECT_NEAR(e.gap, gap, 1e-9) << "configuration " << i;
    EXPECT_EQ(e.link, link) << "configuration " << i;
    in_air += gap > p.press_gap;
    near += gap <= p.press_gap;
  }
  EXPECT_GT(in_air, 20);  // both outcomes exercised
  EXPECT_GT(near, 20);
}

// What an estimate claims (ClaimedPoseCovariance): a set inconsistent or lost because a pressing
// finger is g in the air, a link d inside, or its gate refuses images that put the object v away,
// claims at least that σ on every position axis, so
// that an error of that size along any direction has a NEES below 1 however small the filter's own
// σ; every other state and cause claims the filter's covariance, bit for bit.
TEST(ClaimedCovariance, WidensThePositionByTheDistanceTheHealthSees) {
  Mat6 P = Mat6::Zero();
  P.diagonal() << 1e-6, 2e-6, 3e-6, 1e-4, 2e-4, 3e-4;  // σ 1-1.7 mm, 0.6-1 deg
  P(0, 1) = P(1, 0) = 5e-7;
  P(3, 4) = P(4, 3) = 2e-5;
  for (const HealthState state : {HealthState::kInconsistent, HealthState::kLost})
    for (const HealthCause cause :
         {HealthCause::kPressingInAir, HealthCause::kPenetration, HealthCause::kVisionDisagrees}) {
      const Health h{state, cause, cause == HealthCause::kVisionDisagrees ? 0.8 : 0.034,
                     3,     1.0,   0.034};
      EXPECT_DOUBLE_EQ(HealthPositionSigma(h), 0.034);
      const Mat6 C = ClaimedPoseCovariance(P, h, Mat3::Identity(), Mat3::Zero());  // Γ not known
      Mat6 expected = P;
      expected.topLeftCorner<3, 3>() += 0.034 * 0.034 * Mat3::Identity();
      EXPECT_EQ(C, expected);
      std::mt19937 rng(7);
      std::normal_distribution<double> normal;
      for (int i = 0; i < 100; ++i) {
        const Vec3 u = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
        Vec6 e = Vec6::Zero();
        e.head<3>() = 0.034 * u;
        EXPECT_LT(e.dot(C.ldlt().solve(e)), 1.0);
        EXPECT_GT(e.dot(P.ldlt().solve(e)), 300.0);  // what the filter alone would claim
      }
    }
  // No distance to add: the filter's own.
  const Health quiet[] = {
      {HealthState::kOk, HealthCause::kNone, 0.0, -1, 0.0},
      {HealthState::kUncertain, HealthCause::kWideSigma, 0.02, 0, 0.0},
      {HealthState::kUncertain, HealthCause::kPressingInAir, 0.02, 3, 0.0, 0.02},  // not sustained
      {HealthState::kInconsistent, HealthCause::kTagsElsewhere, 0.0, -1, 0.0},
      {HealthState::kInconsistent, HealthCause::kVisionDisagrees, 0.8, -1, 0.0},  // no distance
      {HealthState::kLost, HealthCause::kFeaturesLost, 0.0, -1, 0.0}};
  for (const Health& h : quiet) {
    EXPECT_EQ(HealthPositionSigma(h), 0.0);
    EXPECT_EQ(ClaimedPoseCovariance(P, h, Mat3::Identity(), Mat3::Zero()), P);
    EXPECT_EQ(ClaimedPoseCovariance(P, h, Mat3::Identity(), 1e-3 * Mat3::Identity()), P);
  }
}

// The same distance s as a turn: about each principal axis of the object's gyration tensor, the
// claim adds the variance of the turn that moves the object's points by s (RMS), here measured on
// points drawn uniformly inside a solid cylinder (radius 20 mm, length 150 mm, its axis along a
// random direction of O) rather than read from the tensor; a turn beyond π²/3 is capped there (a
// 5 mm pen's own axis).
TEST(ClaimedCovariance, WidensTheOrientationByTheTurnThatMovesTheObjectAsFar) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto random_rotation = [&] {
    return Mat3(Quat(normal(rng), normal(rng), normal(rng), normal(rng)).normalized());
  };
  const Mat3 Q = random_rotation();  // the cylinder's axes in O
  const Mat3 R_PO = random_rotation();
  const auto cylinder = [&](double r, double length) {
    const Vec3 g(r * r / 2, r * r / 4 + length * length / 12, r * r / 4 + length * length / 12);
    return Mat3(Q * g.asDiagonal() * Q.transpose());
  };
  Mat6 P = Mat6::Zero();
  P.diagonal() << 1e-6, 2e-6, 3e-6, 1e-4, 2e-4, 3e-4;
  const double s = 0.020;
  const Health lost{HealthState::kLost, HealthCause::kPressingInAir, s, 3, 1.0, s};
  {
    const double r = 0.020, length = 0.150;
    const Mat6 C = ClaimedPoseCovariance(P, lost, R_PO, cylinder(r, length));
    EXPECT_EQ(C, C.transpose());
    const Mat3 position = P.topLeftCorner<3, 3>() + s * s * Mat3::Identity();
    EXPECT_EQ(Mat3(C.topLeftCorner<3, 3>()), position);
    EXPECT_EQ(Mat3(C.topRightCorner<3, 3>()), Mat3(P.topRightCorner<3, 3>()));
    std::vector<Vec3> points;  // uniform inside the cylinder, O axes about its centre
    while (points.size() < 20000) {
      const Vec3 c(uniform(rng) * length / 2, uniform(rng) * r, uniform(rng) * r);
      if (c.tail<2>().norm() <= r) points.push_back(Q * c);
    }
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 e_O = Q.col(axis);
      double moved = 0.0;  // mean squared displacement of the points per unit turn about e_O
      for (const Vec3& x : points) moved += e_O.cross(x).squaredNorm();
      const double turn = s / std::sqrt(moved / points.size());  // moves them by s, RMS
      const Vec3 e_P = R_PO * e_O;
      const double added = e_P.dot((C - P).bottomRightCorner<3, 3>() * e_P);
      EXPECT_NEAR(added, turn * turn, 0.03 * turn * turn) << "axis " << axis;
      // That turn, however small the filter's own σ, has a NEES of about 1 (the sampled turn is
      // within 3 % of the tensor's).
      Vec6 err = Vec6::Zero();
      err.tail<3>() = turn * e_P;
      EXPECT_LT(err.dot(C.ldlt().solve(err)), 1.03);
      EXPECT_GT(err.dot(P.ldlt().solve(err)), 100.0);
    }
  }
  {  // A pen: s moves its points by far more than any turn about its own axis does.
    const Mat6 C = ClaimedPoseCovariance(P, lost, R_PO, cylinder(0.005, 0.140));
    const Vec3 axis_P = R_PO * Q.col(0);
    EXPECT_NEAR(axis_P.dot((C - P).bottomRightCorner<3, 3>() * axis_P), M_PI * M_PI / 3, 1e-12);
  }
}

TEST(PressCheck, AgreesWithTheExhaustiveQueryOnTheProjectsHand) {
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  ComparePressCheck(hand, object, Vec3(0.0, 0.06, 0.06));
}

TEST(PressCheck, AgreesWithTheExhaustiveQueryOnAYcbScan) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel hand =
      LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"), {{}, false});
  const ObjectModel object =
      LoadObjectModel(test::SharedAssets() + "/objects/ycb/mustard_bottle.urdf");
  ComparePressCheck(hand, object, Vec3(0.0, 0.06, 0.06));
}

// --- faults injected into a recording (ketchup, paper noise): each declared within 0.5 s of
// its onset, the clean recording declaring none. What a set declares, and the closing direction
// of a joint offset that the filter explains away, in docs/evaluation.md ("Health").

bool Alarm(const Health& h) { return h.state >= HealthState::kInconsistent; }

TEST(HealthFaults, TheCleanRecordingRaisesNoAlarm) {
  const Recording& r = Recording::Get();
  for (const std::string set : {"jt", "jta", "jtf"}) {
    const Timeline tl = Replay(r, set, Fault{});
    EXPECT_EQ(tl.First(0.0, Alarm), INFINITY) << set << "\n" << Describe(tl, r.models.hand);
    EXPECT_EQ(tl.First(0.0,
                       [](const Health& h) {
                         return h.cause == HealthCause::kImagesFrozen ||
                                h.cause == HealthCause::kImagesStale;
                       }),
              INFINITY)
        << set;
    // Its events: contacts, the state's changes between ok and uncertain, the grip loosening
    // while the lifted bottle tilts in the hand, and nothing of what would need a look.
    std::string unexpected;
    for (const TrackerEvent& e : tl.events) {
      const bool expected =
          e.kind == EventKind::kContactMade || e.kind == EventKind::kContactBroken ||
          e.kind == EventKind::kGripLoosened ||
          (e.kind == EventKind::kHealth && e.health.state <= HealthState::kUncertain);
      if (!expected)
        unexpected += "  " + std::to_string(e.t) + " " + EventKindName(e.kind) + ": " +
                      EventMessage(e, r.models.hand) + "\n";
    }
    EXPECT_EQ(unexpected, "") << set;
    EXPECT_GE(tl.events.size(), 6u) << set;  // the fingers close on the bottle
  }
}

TEST(HealthFaults, ACameraPose50mmOffFor2sIsInconsistent) {
  const Recording& r = Recording::Get();
  Fault f{2.0, 4.0};
  f.camera_shift = Vec3(0.05, 0.0, 0.0);
  for (const std::string set : {"jta", "jtf"}) {
    const Timeline tl = Replay(r, set, f);
    EXPECT_LE(tl.First(f.from, Alarm), f.from + 0.5) << set << "\n" << Describe(tl, r.models.hand);
    // And its event, at that time.
    double alarm_event = INFINITY;
    for (const TrackerEvent& e : tl.events)
      if (e.kind == EventKind::kHealth && Alarm(e.health) && e.t >= f.from - 1e-9) {
        alarm_event = e.t;
        break;
      }
    EXPECT_DOUBLE_EQ(alarm_event, tl.First(f.from, Alarm)) << set;
  }
}

TEST(HealthFaults, AFrozenImageStreamIsDeclared) {
  const Recording& r = Recording::Get();
  Fault f{2.0, 1e9};
  f.freeze = true;
  for (const std::string set : {"jta", "jtf"}) {
    const Timeline tl = Replay(r, set, f);
    EXPECT_LE(
        tl.First(f.from, [](const Health& h) { return h.cause == HealthCause::kImagesFrozen; }),
        f.from + 0.5)
        << set << "\n"
        << Describe(tl, r.models.hand);
  }
}

// A hand over the lens: the images keep coming, but show nothing. Each vision set says that its
// images no longer check the estimate (the extracted features first say they are lost), and no
// set calls the estimate wrong for it.
TEST(HealthFaults, ACoveredCameraIsDeclaredBlind) {
  const Recording& r = Recording::Get();
  Fault f{2.0, 1e9};
  f.cover = true;
  for (const std::string set : {"jta", "jtf"}) {
    const Timeline tl = Replay(r, set, f);
    const auto blind = [](const Health& h) {
      return h.cause == HealthCause::kVisionBlind || h.cause == HealthCause::kFeaturesLost;
    };
    EXPECT_EQ(tl.First(0.0, blind), tl.First(f.from, blind)) << set << ": blind before the fault";
    EXPECT_LE(tl.First(f.from, blind), f.from + 0.5) << set << "\n" << Describe(tl, r.models.hand);
    EXPECT_EQ(tl.First(f.from, Alarm), INFINITY) << set << "\n" << Describe(tl, r.models.hand);
    EXPECT_EQ(tl.health.back().state, HealthState::kUncertain) << set;
  }
}

// The fingers let go (their torques fall to 5 %): nothing holds the object any more, and each
// set with torques says it may slip out of the grip. (The recording's object stays where it was:
// the simulator does not drop it; what the sets see of the slip itself is the vision checks'.)
TEST(HealthFaults, AGripThatLetsGoIsDeclared) {
  const Recording& r = Recording::Get();
  Fault f{2.0, 1e9};
  f.torque_scale = 0.05;
  for (const std::string set : {"jt", "jta", "jtf"}) {
    const Timeline tl = Replay(r, set, f);
    EXPECT_EQ(tl.First(0.0, [](const Health& h) { return h.cause == HealthCause::kSlipping; }),
              tl.First(f.from, [](const Health& h) { return h.cause == HealthCause::kSlipping; }))
        << set << ": the firm grip before the fault said slipping\n"
        << Describe(tl, r.models.hand);
    EXPECT_LE(tl.First(f.from,
                       [](const Health& h) {
                         return h.state >= HealthState::kUncertain &&
                                (h.cause == HealthCause::kSlipping || Alarm(h));
                       }),
              f.from + 0.5)
        << set << "\n"
        << Describe(tl, r.models.hand);
    // And it keeps saying so while the grip stays open.
    EXPECT_GE(tl.health.back().state, HealthState::kUncertain) << set;
    // The event: the grip loosened within 0.5 s of the fault.
    EXPECT_LE(tl.FirstEvent(f.from, EventKind::kGripLoosened), f.from + 0.5) << set;
  }
}

// The index finger's first flexion read 0.2 rad more open than it is: the estimate keeps the
// object where the finger is not, and the finger presses on it.
TEST(HealthFaults, AJointOffsetOf02RadIsInconsistent) {
  const Recording& r = Recording::Get();
  Fault f{2.0, 1e9};
  f.joint = 1;  // index_flex1
  f.joint_offset = -0.2;
  for (const std::string set : {"jt", "jtf"}) {
    const Timeline tl = Replay(r, set, f);
    EXPECT_LE(tl.First(f.from, Alarm), f.from + 0.5) << set << "\n" << Describe(tl, r.models.hand);
  }
}

}  // namespace
}  // namespace inhand
