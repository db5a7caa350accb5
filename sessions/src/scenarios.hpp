#pragma once
// Internal: the paper's five experiments as scripts for the simulator.
#include <map>
#include <string>
#include <vector>

#include "inhand/core/so3.hpp"

namespace inhand::sim {

struct Keyframe {
  double t = 0.0;                          // [s]
  Transform T_WP = Transform::Identity();  // palm pose (the arm)
  std::map<std::string, double> q;         // joint targets; absent joints keep their target
  double grip = 1.0;                       // scales every joint's torque limit
};

struct Scenario {
  std::string name;
  std::string description;
  std::string object;                      // folder under assets/objects
  Transform T_WO = Transform::Identity();  // object on the table at t = 0
  Vec3 camera_eye = Vec3(0.25, -0.36, 0.33);
  Vec3 camera_target = Vec3(0.0, 0.0, 0.1);
  std::vector<Keyframe> keys;
  double grasp_closed = 0.0;  // [s] when the fingers have closed (for checks)
  double record_start = 1.0;  // [s] the hand is in place: the session begins
  double close_start = 0.0;   // [s] when closing starts
  // Where the estimator starts, as in the paper's experiment: from the tracking system (Exp.
  // II-IV: "if not stated otherwise, the initial pose of the object was provided by the tracking
  // system"), purposely set too high (Exp. I: "20 mm higher"), or placed by hand (Exp. V: the
  // pen, "manually set ... roughly aligning it"). The noise profile says how far off each is.
  enum class Start { kTracked, kTooHigh, kByHand };
  Start start = Start::kTracked;
  struct Prop {  // a static box on the table (e.g. a book)
    Transform T_W = Transform::Identity();
    Vec3 half_extents = Vec3::Zero();
    Eigen::Vector4d rgba{0.5, 0.5, 0.5, 1.0};
  };
  std::vector<Prop> props;
  double duration() const { return keys.empty() ? 0.0 : keys.back().t; }
};

const std::vector<Scenario>& Scenarios();
const Scenario* FindScenario(const std::string& name);

// Palm pose and joint targets at time t: keys blended with a smoothstep in time.
Transform PalmAt(const Scenario& s, double t);
std::map<std::string, double> TargetsAt(const Scenario& s, double t, double* grip);

}  // namespace inhand::sim
