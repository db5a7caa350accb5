#include "scenarios.hpp"

#include <algorithm>
#include <cmath>

namespace inhand::sim {

namespace {

// Palm frame axes given in the world: x towards the thumb, y along the fingers, z out of the palm.
Mat3 PalmAxes(const Vec3& x, const Vec3& y) {
  Mat3 R;
  R << x.normalized(), y.normalized(), x.normalized().cross(y.normalized());
  return R;
}

Transform Pose(const Vec3& p, const Mat3& R) { return MakeTransform(p, R); }

std::map<std::string, double> Hand(double abduction, double f1, double f2, double f3, double thumb_abd,
                                   double t1, double t2, double t3) {
  std::map<std::string, double> q;
  for (const char* f : {"index", "middle", "ring"}) {
    q[std::string(f) + "_abduction"] = 0.0;
    q[std::string(f) + "_flex1"] = f1;
    q[std::string(f) + "_flex2"] = f2;
    q[std::string(f) + "_flex3"] = f3;
  }
  q["index_abduction"] = abduction;
  q["ring_abduction"] = -abduction;
  q["thumb_abduction"] = thumb_abd;
  q["thumb_flex1"] = t1;
  q["thumb_flex2"] = t2;
  q["thumb_flex3"] = t3;
  return q;
}

Keyframe Key(double t, const Transform& T_WP, std::map<std::string, double> q = {}, double grip = 1.0) {
  Keyframe k;
  k.t = t;
  k.T_WP = T_WP;
  k.q = std::move(q);
  k.grip = grip;
  return k;
}

Transform Lifted(const Transform& T, double dz) {
  Transform out = T;
  out.translation().z() += dz;
  return out;
}

// A pinch rolled between index and thumb: the index flexes by `amount` [rad], the thumb
// extends by as much, so the object held between the tips turns.
std::map<std::string, double> Rolled(std::map<std::string, double> pinch, double amount) {
  pinch["index_flex1"] += amount;
  pinch["thumb_flex1"] -= amount;
  return pinch;
}

Transform Back(const Transform& T, double d) {  // along the palm's -z
  Transform out = T;
  out.translation() -= d * T.linear().col(2);
  return out;
}

std::vector<Scenario> Build() {
  std::vector<Scenario> all;
  const auto open = Hand(0.05, 0.0, 0.05, 0.05, 0.3, 0.0, 0.1, 0.1);

  {  // Exp. I: power grasp of a ketchup bottle, which tilts in the hand as it is lifted.
    Scenario s;
    s.name = "ketchup-power-grasp";
    s.description = "side power grasp of a standing ketchup bottle below its centre of mass; lifted, it tilts in the hand";
    s.object = "ketchup_bottle";
    // The bottle's wide face towards the palm, its label towards +x.
    s.T_WO = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, M_PI / 2)));
    // Palm facing +x, thumb up, fingers towards the camera side (-y) around the narrow side.
    const Transform grasp = Pose(Vec3(-0.026, 0.05, 0.055), PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0)));
    const auto closed = Hand(0.0, 1.4, 1.3, 1.0, 0.0, 0.6, 0.6, 0.6);
    constexpr double kGrip = 0.7, kLoose = 0.06;  // loosened for a moment: the bottle tilts
    auto fingers_only = closed;  // fingers first, then the thumb
    for (const char* j : {"thumb_abduction", "thumb_flex1", "thumb_flex2", "thumb_flex3"}) fingers_only[j] = open.at(j);
    s.keys = {Key(0.0, Back(grasp, 0.07), open), Key(1.0, grasp, open), Key(1.2, grasp, open),
              Key(1.9, grasp, fingers_only, kGrip), Key(2.4, grasp, closed, kGrip), Key(2.6, grasp, closed, kGrip),
              Key(4.0, Lifted(grasp, 0.12), closed, kGrip), Key(4.6, Lifted(grasp, 0.12), closed, kLoose),
              Key(5.2, Lifted(grasp, 0.12), closed, kGrip), Key(6.0, Lifted(grasp, 0.12), closed, kGrip)};
    s.close_start = 1.2;
    s.grasp_closed = 2.6;
    s.camera_target = Vec3(0.0, 0.0, 0.17);
    s.initial_error_direction_W = Vec3(0, 0, 1);  // "20 mm too high", as in Exp. I
    all.push_back(s);
  }
  {  // Exp. II: fingertip grasp of a brush, then rolled in the hand by the thumb and the index.
    Scenario s;
    s.name = "brush-rotation";
    s.description = "fingertip grasp of a brush's handle from above (index under, thumb on top), lift, roll it in the fingers";
    s.object = "brush";
    s.T_WO = MakeTransform(Vec3(0.0, 0.0, 0.0312), ExpSO3(Vec3(0, 0, M_PI / 2)));  // on its bristles, handle along y
    // Palm down, fingers along +x across the handle; index and thumb tips meet around it.
    const Transform grasp = Pose(Vec3(-0.097, -0.036, 0.083), PalmAxes(Vec3(0, 1, 0), Vec3(1, 0, 0)));
    const auto pinch = Hand(0.0, 0.9, 1.1, 0.6, 0.9, 0.6, 0.6, 0.5);
    const auto roll_a = Rolled(pinch, 0.25), roll_b = Rolled(pinch, -0.25);
    s.keys = {Key(0.0, Lifted(grasp, 0.06), open), Key(1.0, grasp, open), Key(1.2, grasp, open),
              Key(2.2, grasp, pinch, 0.8), Key(2.5, grasp, pinch, 0.8), Key(3.5, Lifted(grasp, 0.08), pinch, 0.8),
              Key(4.5, Lifted(grasp, 0.08), roll_a, 0.8), Key(5.5, Lifted(grasp, 0.08), roll_b, 0.8),
              Key(6.0, Lifted(grasp, 0.08), roll_b, 0.8)};
    s.close_start = 1.2;
    s.grasp_closed = 2.5;
    all.push_back(s);
  }
  {  // Exp. III: push a mostly transparent water bottle along the table, then grasp it.
    Scenario s;
    s.name = "water-push-grasp";
    s.description = "push a standing water bottle 6 cm along the table with the palm, then power-grasp and lift it";
    s.object = "water_bottle";
    const Mat3 R = PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0));
    const Transform touch = Pose(Vec3(-0.035, 0.05, 0.055), R);
    Transform pushed = touch;
    pushed.translation().x() += 0.06;
    const auto closed = Hand(0.0, 1.4, 1.3, 1.0, 0.0, 0.6, 0.6, 0.6);
    auto fingers_only = closed;
    for (const char* j : {"thumb_abduction", "thumb_flex1", "thumb_flex2", "thumb_flex3"}) fingers_only[j] = open.at(j);
    s.keys = {Key(0.0, Back(touch, 0.06), open), Key(1.0, Back(touch, 0.005), open), Key(2.4, pushed, open),
              Key(2.6, pushed, open), Key(3.3, pushed, fingers_only, 0.7), Key(3.8, pushed, closed, 0.7),
              Key(4.0, pushed, closed, 0.7), Key(5.4, Lifted(pushed, 0.12), closed, 0.7), Key(6.2, Lifted(pushed, 0.12), closed, 0.7)};
    s.close_start = 2.6;
    s.grasp_closed = 4.0;
    s.camera_target = Vec3(0.04, 0.0, 0.12);
    all.push_back(s);
  }
  {  // Exp. IV: a free-form shampoo bottle in a grasp that is neither power nor fingertip.
    Scenario s;
    s.name = "shampoo-grasp";
    s.description = "grasp a free-form shampoo bottle with the middle phalanges and the thumb, neither power nor fingertip grasp; lift and turn";
    s.object = "shampoo_bottle";
    s.T_WO = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, M_PI / 2)));  // wide side towards the palm
    const Mat3 R = PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0));
    // Fingers half closed on the wide side: the middle phalanges and the thumb hold it.
    const Transform grasp = Pose(Vec3(-0.028, 0.045, 0.09), R);
    const auto closed = Hand(0.05, 1.2, 1.0, 0.9, 0.0, 0.6, 0.6, 0.6);
    auto fingers_only = closed;
    for (const char* j : {"thumb_abduction", "thumb_flex1", "thumb_flex2", "thumb_flex3"}) fingers_only[j] = open.at(j);
    Transform turned = Lifted(grasp, 0.10);
    turned.linear() = ExpSO3(Vec3(0, 0, 0.4)) * turned.linear();
    s.keys = {Key(0.0, Back(grasp, 0.06), open), Key(1.0, grasp, open), Key(1.2, grasp, open),
              Key(1.9, grasp, fingers_only, 0.7), Key(2.4, grasp, closed, 0.7), Key(2.6, grasp, closed, 0.7),
              Key(4.0, Lifted(grasp, 0.10), closed, 0.7), Key(5.2, turned, closed, 0.7), Key(6.0, turned, closed, 0.7)};
    s.close_start = 1.2;
    s.grasp_closed = 2.6;
    all.push_back(s);
  }
  {  // Exp. V: fingertip grasp of a pen lying on a book, rolled twice back and forth.
    Scenario s;
    s.name = "pen-fingertip";
    s.description = "fingertip grasp of a pen lying on a book, its end over the edge; lift, roll it twice back and forth";
    s.object = "pen";
    Scenario::Prop book;
    book.T_W = MakeTransform(Vec3(0.07, 0.0, 0.0125), Mat3::Identity());
    book.half_extents = Vec3(0.10, 0.075, 0.0125);  // its edge at x = -0.03
    book.rgba = Eigen::Vector4d(0.15, 0.35, 0.55, 1.0);
    s.props.push_back(book);
    s.T_WO = MakeTransform(Vec3(0.005, 0.0, 0.025 + 0.0055), Mat3::Identity());  // along x, 3.75 cm over the edge
    // Palm down, fingers along -y across the pen; index under, thumb on top, 2 cm from its end.
    const Transform grasp = Pose(Vec3(-0.077, 0.097, 0.0825), PalmAxes(Vec3(1, 0, 0), Vec3(0, -1, 0)));
    const auto pinch = Hand(0.0, 0.9, 1.1, 0.6, 0.9, 0.6, 0.6, 0.5);
    const auto roll_a = Rolled(pinch, 0.2), roll_b = Rolled(pinch, -0.2);
    s.keys = {Key(0.0, Lifted(grasp, 0.06), open), Key(1.0, grasp, open), Key(1.2, grasp, open),
              Key(2.2, grasp, pinch, 0.6), Key(2.5, grasp, pinch, 0.6), Key(3.3, Lifted(grasp, 0.07), pinch, 0.6),
              Key(4.0, Lifted(grasp, 0.07), roll_a, 0.6), Key(4.7, Lifted(grasp, 0.07), roll_b, 0.6),
              Key(5.4, Lifted(grasp, 0.07), roll_a, 0.6), Key(6.1, Lifted(grasp, 0.07), roll_b, 0.6),
              Key(6.5, Lifted(grasp, 0.07), pinch, 0.6)};
    s.close_start = 1.2;
    s.grasp_closed = 2.5;
    s.camera_target = Vec3(-0.03, 0.0, 0.06);
    all.push_back(s);
  }
  return all;
}

double Smooth(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// Index of the segment [keys[i], keys[i+1]] holding t and the blend weight.
std::pair<std::size_t, double> Segment(const Scenario& s, double t) {
  if (t <= s.keys.front().t) return {0, 0.0};
  for (std::size_t i = 0; i + 1 < s.keys.size(); ++i)
    if (t <= s.keys[i + 1].t) return {i, Smooth((t - s.keys[i].t) / (s.keys[i + 1].t - s.keys[i].t))};
  return {s.keys.size() - 2, 1.0};
}

}  // namespace

const std::vector<Scenario>& Scenarios() {
  static const std::vector<Scenario> all = Build();
  return all;
}

const Scenario* FindScenario(const std::string& name) {
  for (const Scenario& s : Scenarios())
    if (s.name == name) return &s;
  return nullptr;
}

Transform PalmAt(const Scenario& s, double t) {
  const auto [i, w] = Segment(s, t);
  const Transform& a = s.keys[i].T_WP;
  const Transform& b = s.keys[i + 1].T_WP;
  return MakeTransform((1.0 - w) * a.translation() + w * b.translation(),
                       Quat(a.linear()).slerp(w, Quat(b.linear())));
}

std::map<std::string, double> TargetsAt(const Scenario& s, double t, double* grip) {
  // Each key's targets hold from that key on; blends happen towards the next key's values.
  std::vector<std::map<std::string, double>> full(s.keys.size());
  for (std::size_t k = 0; k < s.keys.size(); ++k) {
    full[k] = k ? full[k - 1] : std::map<std::string, double>{};
    for (const auto& [name, v] : s.keys[k].q) full[k][name] = v;
  }
  const auto [i, w] = Segment(s, t);
  std::map<std::string, double> out = full[i];
  for (const auto& [name, v] : full[i + 1]) {
    const auto it = full[i].find(name);
    out[name] = it == full[i].end() ? v : (1.0 - w) * it->second + w * v;
  }
  if (grip) *grip = (1.0 - w) * s.keys[i].grip + w * s.keys[i + 1].grip;
  return out;
}

}  // namespace inhand::sim
