#pragma once
// Internal: the Bullet dynamics world of the simulator. The arm and the hand form one
// Featherstone multibody on a fixed base: three prismatic and three revolute arm joints carry
// the palm along its scripted trajectory (stiff motors), and every hand joint has a motor with a
// position target and a bounded impulse (torque limit × Δt): a torque-limited position-controlled
// hand. The object is a dynamic rigid body, the table static.
#include <memory>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand::sim {

constexpr double kLinkMass = 0.02;  // [kg] of every hand link in the simulation

struct LinkContact {
  int link = -1;
  Vec3 point_W = Vec3::Zero();  // on the link
  Vec3 force_W = Vec3::Zero();  // applied by the link to the object [N]
  double distance = 0.0;        // Bullet's (with margins)
};

class World {
 public:
  // `props`: static boxes (pose, half extents) on the table. `pad_stiffness` > 0: the fingertip
  // links (those without moving child joints) touch through a compliant pad of that stiffness [N/m]
  // and damping [N s/m] instead of rigidly.
  World(const HandModel& hand, const ObjectModel& object, const Transform& T_WO,
        double friction_links, const Transform& T_WP0, const Eigen::VectorXd& q0,
        const std::vector<std::pair<Transform, Vec3>>& props = {}, double pad_stiffness = 0.0,
        double pad_damping = 0.0);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // Motor targets for the next step: palm pose (reached stiffly) and hand joints (reached
  // within the torque limits).
  void SetTargets(const Transform& T_WP, const Eigen::VectorXd& q_target,
                  const Eigen::VectorXd& tau_max);
  void Step(double dt);
  Eigen::VectorXd JointPositions() const;  // hand joints, model order
  Transform PalmPose() const;              // T_WP as simulated
  Transform ObjectPose() const;            // T_WO
  Vec3 ObjectLinearVelocity() const;
  // Contacts between links and the object after the last step, with the forces the links
  // applied to the object (normal and friction impulses over dt).
  const std::vector<LinkContact>& contacts() const { return contacts_; }
  bool ObjectTouchesTable() const { return touches_table_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<LinkContact> contacts_;
  bool touches_table_ = false;
  Eigen::VectorXd last_tau_max_;
};

}  // namespace inhand::sim
