#include "inhand/filter/plausibility.hpp"

#include <algorithm>
#include <cmath>

#include "inhand/filter/health.hpp"

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

}  // namespace inhand
