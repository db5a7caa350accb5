#pragma once
// Internal: the Bullet dynamics world of the simulator (hand links as kinematic bodies, the
// object as a dynamic body, a static table).
#include <memory>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand::sim {

struct LinkContact {
  int link = -1;
  Vec3 point_W = Vec3::Zero();   // on the link
  Vec3 force_W = Vec3::Zero();   // applied by the link to the object [N]
  double distance = 0.0;         // Bullet's (with margins)
};

class World {
 public:
  World(const HandModel& hand, const ObjectModel& object, const Transform& T_WO, double friction_links);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // Places the hand's links (kinematic: Bullet derives their velocities from the motion).
  void SetLinkPoses(const std::vector<Transform>& T_WL);
  void Step(double dt);
  Transform ObjectPose() const;  // T_WO
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
};

}  // namespace inhand::sim
