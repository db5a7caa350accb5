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

std::map<std::string, double> Hand(double abduction, double f1, double f2, double f3,
                                   double thumb_abd, double t1, double t2, double t3) {
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

Keyframe Key(double t, const Transform& T_WP, std::map<std::string, double> q = {},
             double grip = 1.0) {
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

// One finger's flexions, or the thumb's abduction and flexions, set in a hand pose.
std::map<std::string, double> With(std::map<std::string, double> q, const std::string& finger,
                                   double a, double b, double c) {
  q[finger + "_flex1"] = a;
  q[finger + "_flex2"] = b;
  q[finger + "_flex3"] = c;
  return q;
}
std::map<std::string, double> WithThumb(std::map<std::string, double> q, double abduction,
                                        double t1, double t2, double t3) {
  q["thumb_abduction"] = abduction;
  return With(std::move(q), "thumb", t1, t2, t3);
}

// `q` with the thumb's joints as in `from` (e.g. the fingers closed, the thumb still open).
std::map<std::string, double> WithThumbOf(std::map<std::string, double> q,
                                          const std::map<std::string, double>& from) {
  for (const char* j : {"thumb_abduction", "thumb_flex1", "thumb_flex2", "thumb_flex3"})
    q[j] = from.at(j);
  return q;
}

// A static box on the table.
Scenario::Prop Box(const Vec3& centre, const Vec3& half_extents, const Eigen::Vector4d& rgba) {
  Scenario::Prop p;
  p.T_W = MakeTransform(centre, Mat3::Identity());
  p.half_extents = half_extents;
  p.rgba = rgba;
  return p;
}

// A pinch between the index pad and the thumb tip (targets from the hand's inverse kinematics):
// the index curled under the object, touching it (thumb above it), squeezing it, and rolled
// both ways (the tips moved along the tangent in opposite directions).
struct Pinch {
  std::map<std::string, double> under, touch, pinch, roll_a, roll_b;
};

// The approach shared by the pinch scenarios: from 6 cm above to the grasp pose with the hand
// open, the index under the object by 2.0 s, touching by 2.4 s, squeezing from 2.9 s to 3.1 s.
std::vector<Keyframe> PinchApproach(const Transform& grasp,
                                    const std::map<std::string, double>& open, const Pinch& p,
                                    double grip) {
  return {Key(0.0, Lifted(grasp, 0.06), open),
          Key(1.0, grasp, open),
          Key(1.2, grasp, open),
          Key(2.0, grasp, p.under, grip),
          Key(2.4, grasp, p.touch, grip),
          Key(2.9, grasp, p.pinch, grip),
          Key(3.1, grasp, p.pinch, grip)};
}

Transform Back(const Transform& T, double d) {  // along the palm's -z
  Transform out = T;
  out.translation() -= d * T.linear().col(2);
  return out;
}

std::vector<Scenario> Build() {
  std::vector<Scenario> all;
  const auto open = Hand(0.05, 0.0, 0.05, 0.05, 0.3, 0.0, 0.1, 0.1);
  // For the pinches: middle and ring curled out of the way.
  const auto relaxed = With(With(open, "middle", 0.3, 1.0, 0.8), "ring", 0.3, 1.0, 0.8);

  {  // Exp. I: power grasp of a ketchup bottle, which tilts in the hand as it is lifted.
    Scenario s;
    s.name = "ketchup-power-grasp";
    s.description =
        "side power grasp of a standing ketchup bottle below its centre of mass; lifted, it tilts "
        "in the hand";
    s.object = "ketchup_bottle";
    // The bottle's wide face towards the palm, its label towards +x.
    s.T_WO = MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, M_PI / 2)));
    // Palm facing +x, thumb up, fingers towards the camera side (-y) around the narrow side.
    const Transform grasp =
        Pose(Vec3(-0.026, 0.05, 0.055), PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0)));
    const auto closed = Hand(0.0, 1.4, 1.3, 1.0, 0.0, 0.6, 0.6, 0.6);
    constexpr double kGrip = 0.7, kLoose = 0.06;          // loosened for a moment: the bottle tilts
    const auto fingers_only = WithThumbOf(closed, open);  // fingers first, then the thumb
    s.keys = {Key(0.0, Back(grasp, 0.07), open),
              Key(1.0, grasp, open),
              Key(1.2, grasp, open),
              Key(1.9, grasp, fingers_only, kGrip),
              Key(2.4, grasp, closed, kGrip),
              Key(2.6, grasp, closed, kGrip),
              Key(4.0, Lifted(grasp, 0.12), closed, kGrip),
              Key(4.6, Lifted(grasp, 0.12), closed, kLoose),
              Key(5.2, Lifted(grasp, 0.12), closed, kGrip),
              Key(6.0, Lifted(grasp, 0.12), closed, kGrip)};
    s.close_start = 1.2;
    s.grasp_closed = 2.6;
    s.camera_target = Vec3(0.0, 0.0, 0.17);
    s.start = Scenario::Start::kTooHigh;  // "purposely set 20 mm higher"
    all.push_back(s);
  }
  {  // Exp. II: fingertip grasp of a brush, then rolled in the hand by the thumb and the index.
    Scenario s;
    s.name = "brush-rotation";
    s.description =
        "fingertip grasp of a brush's handle overhanging a book (index under, thumb on top), lift, "
        "roll it in the fingers";
    s.object = "brush";
    // A book, its edge at y = 0.015 under the brush's head.
    s.props.push_back(Box(Vec3(0.0, 0.09, 0.0125), Vec3(0.075, 0.075, 0.0125),
                          Eigen::Vector4d(0.55, 0.2, 0.15, 1.0)));
    // On its bristles on the book, the handle along -y over the edge (its axis at z = 56.2 mm).
    s.T_WO = MakeTransform(Vec3(0.0, 0.0, 0.025 + 0.0312), ExpSO3(Vec3(0, 0, M_PI / 2)));
    // Palm down, fingers along +x across the handle, 5 cm from the head; the pinch of the pen
    // scenario solved again for the handle's radius (11.5 mm) with the palm 39 mm above its
    // axis, where both contact normals are within 19 deg of the vertical. Rolled: 6 mm each.
    const Transform grasp =
        Pose(Vec3(-0.097, -0.077, 0.0952), PalmAxes(Vec3(0, 1, 0), Vec3(1, 0, 0)));
    const Pinch p{
        With(relaxed, "index", 0.943, 0.813, 0.813),
        WithThumb(With(relaxed, "index", 0.897, 0.917, 0.917), 1.076, -0.154, 1.234, 0.987),
        WithThumb(With(relaxed, "index", 0.879, 0.965, 0.965), 0.996, 0.135, 1.042, 0.833),
        WithThumb(With(relaxed, "index", 0.984, 0.923, 0.923), 1.006, 0.146, 0.947, 0.757),
        WithThumb(With(relaxed, "index", 0.776, 0.997, 0.997), 0.984, 0.14, 1.126, 0.901)};
    constexpr double kGrip = 0.8;
    const Transform up = Lifted(grasp, 0.08);
    s.keys = PinchApproach(grasp, open, p, kGrip);
    s.keys.insert(s.keys.end(), {Key(4.1, up, p.pinch, kGrip), Key(4.9, up, p.roll_a, kGrip),
                                 Key(5.7, up, p.roll_b, kGrip), Key(6.5, up, p.roll_a, kGrip),
                                 Key(6.8, up, p.roll_a, kGrip)});
    s.close_start = 1.2;
    s.grasp_closed = 3.1;
    s.camera_target = Vec3(0.0, 0.0, 0.12);
    all.push_back(s);
  }
  {  // Exp. III: push a mostly transparent water bottle along the table, then grasp it.
    Scenario s;
    s.name = "water-push-grasp";
    s.description =
        "push a standing water bottle 6 cm along the table with the palm, then power-grasp and "
        "lift it";
    s.object = "water_bottle";
    const Mat3 R = PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0));
    const Transform touch = Pose(Vec3(-0.035, 0.05, 0.055), R);
    Transform pushed = touch;
    pushed.translation().x() += 0.06;
    const auto closed = Hand(0.0, 1.4, 1.3, 1.0, 0.0, 0.6, 0.6, 0.6);
    const auto fingers_only = WithThumbOf(closed, open);
    s.keys = {Key(0.0, Back(touch, 0.06), open),
              Key(1.0, Back(touch, 0.005), open),
              Key(2.4, pushed, open),
              Key(2.6, pushed, open),
              Key(3.3, pushed, fingers_only, 0.7),
              Key(3.8, pushed, closed, 0.7),
              Key(4.0, pushed, closed, 0.7),
              Key(5.4, Lifted(pushed, 0.12), closed, 0.7),
              Key(6.2, Lifted(pushed, 0.12), closed, 0.7)};
    s.close_start = 2.6;
    s.grasp_closed = 4.0;
    s.camera_target = Vec3(0.04, 0.0, 0.12);
    all.push_back(s);
  }
  {  // Exp. IV: a free-form shampoo bottle in a grasp that is neither power nor fingertip.
    Scenario s;
    s.name = "shampoo-grasp";
    s.description =
        "grasp a free-form shampoo bottle with the middle phalanges and the thumb, neither power "
        "nor fingertip grasp; lift and turn";
    s.object = "shampoo_bottle";
    s.T_WO =
        MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, 0, M_PI / 2)));  // wide side towards the palm
    const Mat3 R = PalmAxes(Vec3(0, 0, 1), Vec3(0, -1, 0));
    // Fingers half closed on the wide side: the middle phalanges and the thumb hold it.
    const Transform grasp = Pose(Vec3(-0.028, 0.045, 0.09), R);
    const auto closed = Hand(0.05, 1.2, 1.0, 0.9, 0.0, 0.6, 0.6, 0.6);
    const auto fingers_only = WithThumbOf(closed, open);
    Transform turned = Lifted(grasp, 0.10);
    turned.linear() = ExpSO3(Vec3(0, 0, 0.4)) * turned.linear();
    s.keys = {Key(0.0, Back(grasp, 0.06), open),
              Key(1.0, grasp, open),
              Key(1.2, grasp, open),
              Key(1.9, grasp, fingers_only, 0.7),
              Key(2.4, grasp, closed, 0.7),
              Key(2.6, grasp, closed, 0.7),
              Key(4.0, Lifted(grasp, 0.10), closed, 0.7),
              Key(5.2, turned, closed, 0.7),
              Key(6.0, turned, closed, 0.7)};
    s.close_start = 1.2;
    s.grasp_closed = 2.6;
    all.push_back(s);
  }
  {  // Exp. V: fingertip grasp of a pen lying on a book, rolled twice back and forth.
    Scenario s;
    s.name = "pen-fingertip";
    s.description =
        "fingertip grasp of a pen lying on a book, its end over the edge; lift, roll it twice back "
        "and forth";
    s.object = "pen";
    // A book, its edge at x = -0.03.
    s.props.push_back(Box(Vec3(0.07, 0.0, 0.0125), Vec3(0.10, 0.075, 0.0125),
                          Eigen::Vector4d(0.15, 0.35, 0.55, 1.0)));
    s.T_WO = MakeTransform(Vec3(0.005, 0.0, 0.025 + 0.0055),
                           Mat3::Identity());  // along x, 3.75 cm over the edge
    // Palm down, fingers along -y across the pen, 1.75 cm from its end: the index curls under
    // the overhanging end, the thumb comes down on top, and the two squeeze it.
    // Targets from the hand's inverse kinematics (index flex3 = flex2; thumb flex3 = 0.8 flex2),
    // for a pen axis at z = 31 mm: the index pad touches it from below-left with its contact
    // normal 31 deg from the vertical (the palm is too high for a fingertip contact), so the
    // thumb tip is placed on the same line from above-right, or the squeeze would push the pen
    // out sideways. Each aims 2.5 mm inside the pen; the index first stops 2.6 mm short of it.
    // Rolled: both tips moved 2.5 mm along the tangent, in opposite directions.
    const Transform grasp =
        Pose(Vec3(-0.077, 0.097, 0.0825), PalmAxes(Vec3(1, 0, 0), Vec3(0, -1, 0)));
    const Pinch p{
        With(relaxed, "index", 1.039, 0.647, 0.647),
        WithThumb(With(relaxed, "index", 0.994, 0.757, 0.757), 0.943, 0.23, 1.107, 0.886),
        WithThumb(With(relaxed, "index", 0.978, 0.807, 0.807), 0.855, 0.511, 0.801, 0.64),
        WithThumb(With(relaxed, "index", 1.025, 0.777, 0.777), 0.873, 0.5, 0.778, 0.623),
        WithThumb(With(relaxed, "index", 0.932, 0.835, 0.835), 0.835, 0.524, 0.821, 0.657)};
    constexpr double kGrip = 0.6;
    const Transform up = Lifted(grasp, 0.07);
    s.keys = PinchApproach(grasp, open, p, kGrip);
    s.keys.insert(s.keys.end(), {Key(3.9, up, p.pinch, kGrip), Key(4.5, up, p.roll_a, kGrip),
                                 Key(5.1, up, p.roll_b, kGrip), Key(5.7, up, p.roll_a, kGrip),
                                 Key(6.3, up, p.roll_b, kGrip), Key(6.7, up, p.pinch, kGrip)});
    s.close_start = 1.2;
    s.grasp_closed = 3.1;
    s.camera_target = Vec3(-0.03, 0.0, 0.06);
    s.start = Scenario::Start::kByHand;  // too small for markers: "manually set"
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
    if (t <= s.keys[i + 1].t)
      return {i, Smooth((t - s.keys[i].t) / (s.keys[i + 1].t - s.keys[i].t))};
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
