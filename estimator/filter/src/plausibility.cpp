#include "inhand/filter/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "inhand/filter/health.hpp"
#include "inhand/kinematics/kinematics.hpp"

namespace inhand {

HandFingers::HandFingers(const HandModel& hand) {
  const std::size_t links = hand.links.size();
  link_finger.assign(links, -1);
  std::vector<int> joint_q(hand.joints.size(), -1);
  for (int i = 0; i < hand.num_q(); ++i) joint_q[static_cast<std::size_t>(hand.q_joints[i])] = i;
  std::vector<int> first_joints;
  std::vector<std::size_t> depth;  // per finger: its tip's chain length
  for (std::size_t l = 0; l < links && l < hand.support.size(); ++l) {
    const std::vector<int>& chain = hand.support[l];
    if (chain.empty()) continue;
    auto it = std::find(first_joints.begin(), first_joints.end(), chain.front());
    if (it == first_joints.end()) {
      first_joints.push_back(chain.front());
      finger_q.emplace_back();
      tip.push_back(static_cast<int>(l));
      depth.push_back(chain.size());
      it = first_joints.end() - 1;
    }
    const int f = static_cast<int>(it - first_joints.begin());
    link_finger[l] = f;
    if (chain.size() > depth[static_cast<std::size_t>(f)])
      depth[static_cast<std::size_t>(f)] = chain.size(),
      tip[static_cast<std::size_t>(f)] = static_cast<int>(l);
    for (int j : chain) {
      const int qi = joint_q[static_cast<std::size_t>(j)];
      std::vector<int>& qs = finger_q[static_cast<std::size_t>(f)];
      if (qi >= 0 && std::find(qs.begin(), qs.end(), qi) == qs.end()) qs.push_back(qi);
    }
  }
  // The palm's widths along directions spread over a half sphere (a golden spiral): its normal
  // is the thinnest, its centre the mean of the midpoints between opposite support points. Which
  // way the normal points cannot come from the configuration of the moment: at the start of a
  // grasp the fingers are straight, or bent back a little, and their tips lie in the palm's
  // plane or behind it.
  constexpr int kDirections = 256;
  double widest = 0.0;
  for (std::size_t l = 0; l < links; ++l) {
    const std::vector<ConvexPiece>& pieces = hand.links[l].collision;
    if (link_finger[l] >= 0 || pieces.empty()) continue;
    const auto extent = [&](const Vec3& d) {
      double e = -std::numeric_limits<double>::infinity();
      Vec3 at = Vec3::Zero();
      for (const ConvexPiece& piece : pieces) {
        const Vec3 s = piece.Support(d);
        if (s.dot(d) > e) e = s.dot(d), at = s;
      }
      return at;
    };
    double thinnest = std::numeric_limits<double>::infinity(), width_max = 0.0;
    Vec3 normal = Vec3::UnitZ(), centre = Vec3::Zero();
    for (int i = 0; i < kDirections; ++i) {
      const double z = (i + 0.5) / kDirections;  // the upper half sphere, even in area
      const double r = std::sqrt(1.0 - z * z), phi = i * M_PI * (3.0 - std::sqrt(5.0));
      const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
      const Vec3 a = extent(d), b = extent(-d);
      const double width = (a - b).dot(d);
      centre += 0.5 * (a + b) / kDirections;
      width_max = std::max(width_max, width);
      if (width < thinnest) thinnest = width, normal = d;
    }
    if (width_max > widest)
      widest = width_max, palm = static_cast<int>(l), palm_centre_L = centre,
      palm_normal_L = normal;
  }
  // A hand whose links all hang from one joint (a wrist, as the Shadow hand's URDF has) is one
  // finger here, and its "palm" a forearm: no grasp side.
  if (palm < 0 || tip.size() < 2) {
    palm_normal_L.setZero();
    return;
  }
  Eigen::VectorXd q_mid = Eigen::VectorXd::Zero(hand.num_q());
  for (int i = 0; i < hand.num_q(); ++i)
    if (hand.QJoint(i).has_limits) q_mid[i] = 0.5 * (hand.QJoint(i).lower + hand.QJoint(i).upper);
  KinematicsData kin(hand);
  kin.Update(hand, q_mid);
  const Transform T_LP = kin.link_poses()[static_cast<std::size_t>(palm)].inverse();
  Vec3 tips_L = Vec3::Zero();
  for (int l : tip) tips_L += T_LP * kin.link_poses()[static_cast<std::size_t>(l)].translation();
  const double side = (tips_L / tip.size() - palm_centre_L).dot(palm_normal_L);
  palm_normal_L = side > 0.0 ? palm_normal_L : side < 0.0 ? Vec3(-palm_normal_L) : Vec3::Zero();
}

std::pair<Vec3, Vec3> HandFingers::GraspSide(const std::vector<Transform>& T_PL) const {
  if (palm < 0) return {Vec3::Zero(), Vec3::Zero()};
  const Transform& T = T_PL[static_cast<std::size_t>(palm)];
  return {T * palm_centre_L, T.linear() * palm_normal_L};
}

double HandFingers::Torque(int f, const Eigen::Ref<const Eigen::VectorXd>& tau) const {
  double t = 0.0;
  for (int qi : finger_q[static_cast<std::size_t>(f)])
    if (qi < tau.size()) t = std::max(t, std::abs(tau[qi]));
  return t;
}

double Plausibility::Excess(const HealthParams& params) const {
  return std::max(penetration - params.penetration, 0.0) +
         (pressing > 0 ? std::max(pressing_gap - params.press_gap, 0.0) : 0.0);
}

HandPlausibility::HandPlausibility(const HandModel& hand, ContactQuery& query)
    : fingers_(hand), query_(query) {
  pairs_.reserve(2 * hand.links.size() + 8);
  nearest_.assign(fingers_.finger_q.size(), -1);
  torque_.assign(fingers_.finger_q.size(), 0.0);
}

void HandPlausibility::Measure(const std::vector<Transform>& T_PL, const Transform& T_PO,
                               double reach) {
  query_.Query(T_PL, T_PO, reach, pairs_);
  std::fill(nearest_.begin(), nearest_.end(), -1);
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    const int f = fingers_.link_finger[static_cast<std::size_t>(pairs_[i].link)];
    if (f < 0) continue;
    int& n = nearest_[static_cast<std::size_t>(f)];
    if (n < 0 || pairs_[i].distance < pairs_[static_cast<std::size_t>(n)].distance)
      n = static_cast<int>(i);
  }
}

Plausibility HandPlausibility::Score(const Eigen::Ref<const Eigen::VectorXd>& tau,
                                     const std::vector<Transform>& T_PL, const Transform& T_PO,
                                     const HealthParams& params, double reach) {
  Measure(T_PL, T_PO, reach);
  Plausibility out;
  for (const ContactPair& p : pairs_)
    if (-p.distance > out.penetration) out.penetration = -p.distance, out.penetration_link = p.link;
  if (!tau.allFinite()) return out;
  for (int f = 0; f < fingers_.size(); ++f) {
    if (fingers_.Torque(f, tau) < params.press_torque) continue;
    const int n = nearest_[static_cast<std::size_t>(f)];
    const double gap = n < 0 ? reach : pairs_[static_cast<std::size_t>(n)].distance;
    if (out.pressing == 0 || gap > out.pressing_gap) {
      out.pressing_gap = gap;
      out.pressing_link = n < 0 ? -1 : pairs_[static_cast<std::size_t>(n)].link;
    }
    ++out.pressing;
  }
  return out;
}

// Each pair's signed distance d moves by n·δ when the object moves by δ (n from the link into
// the object). A pressing finger's nearest pair asks for d + n·δ = 0, a link inside the object
// for the same (out to the surface); the damped normal equations give δ.
Transform HandPlausibility::Settle(const Eigen::Ref<const Eigen::VectorXd>& tau,
                                   const std::vector<Transform>& T_PL, const Transform& T_PO,
                                   const HealthParams& params, double reach, int iterations,
                                   double max_step) {
  Transform T = T_PO;
  const bool torques = tau.allFinite();
  for (int f = 0; f < fingers_.size(); ++f)
    torque_[static_cast<std::size_t>(f)] = torques ? fingers_.Torque(f, tau) : 0.0;
  for (int it = 0; it < iterations; ++it) {
    Measure(T_PL, T, reach);
    Mat3 A = Mat3::Zero();
    Vec3 b = Vec3::Zero();
    int rows = 0;
    const auto row = [&](const ContactPair& p) {
      A.noalias() += p.normal_P * p.normal_P.transpose();
      b -= p.normal_P * p.distance;
      ++rows;
    };
    for (std::size_t i = 0; i < pairs_.size(); ++i) {
      const ContactPair& p = pairs_[i];
      const int f = fingers_.link_finger[static_cast<std::size_t>(p.link)];
      const bool pressing_nearest = f >= 0 &&
                                    torque_[static_cast<std::size_t>(f)] >= params.press_torque &&
                                    nearest_[static_cast<std::size_t>(f)] == static_cast<int>(i);
      if (p.distance < 0.0 || pressing_nearest) row(p);
    }
    if (rows == 0) break;
    A.diagonal().array() += 1e-3;
    Vec3 delta = A.ldlt().solve(b);
    if (!delta.allFinite()) break;
    if (delta.norm() > max_step) delta *= max_step / delta.norm();
    T.translation() += delta;
    if (delta.norm() < 1e-4) break;
  }
  return T;
}

HandPlausibility::StartChoice HandPlausibility::SettleStart(
    const Eigen::Ref<const Eigen::VectorXd>& tau, const std::vector<Transform>& T_PL,
    const Transform& T_PO, const Vec3& centre_O, double sigma_position, const HealthParams& params,
    double reach) {
  StartChoice out;
  out.T_PO = T_PO;
  const Plausibility start = Score(tau, T_PL, T_PO, params, reach);
  out.penetration = start.penetration;
  out.link = start.penetration_link;
  const auto [centre_P, normal_P] = fingers_.GraspSide(T_PL);
  if (out.penetration <= params.penetration || normal_P.isZero()) return out;
  // Ranked by (implausible, excess if implausible else Mahalanobis²) among those on the grasp
  // side; ties keep the first.
  std::pair<bool, double> best{true, 0.0};
  for (int h = 0; h < 7; ++h) {
    Transform seed = T_PO;
    if (h > 0) seed.translation()[(h - 1) / 2] += (h % 2 ? 2.0 : -2.0) * sigma_position;
    const Transform T = Settle(tau, T_PL, seed, params, reach);
    const double excess = Score(tau, T_PL, T, params, reach).Excess(params);
    const bool wrong_side = (T * centre_O - centre_P).dot(normal_P) <= 0.0;
    const double m2 =
        (T.translation() - T_PO.translation()).squaredNorm() / (sigma_position * sigma_position);
    const std::pair<bool, double> key{excess > 0.0, excess > 0.0 ? excess : m2};
    if (!wrong_side && (out.hypothesis < 0 || key < best))
      best = key, out.hypothesis = h, out.T_PO = T;
  }
  if (out.hypothesis == 0) out.hypothesis = -1, out.T_PO = T_PO;
  return out;
}

}  // namespace inhand
