#include "sim_world.hpp"

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "inhand/core/error.hpp"

namespace inhand::sim {

namespace {

constexpr double kMargin = 0.0005;  // [m] collision margin of hulls and boxes
constexpr int kArmDofs = 6;         // x, y, z, then rotations about z, x, y

// R = Rz(a) Rx(b) Ry(c): singular only when the fingers (palm y) point straight up or down,
// which no scenario needs (side grasps have the thumb up, top grasps the palm down).
Vec3 ZxyAngles(const Mat3& R) {
  const double b = std::asin(std::clamp(R(2, 1), -1.0, 1.0));
  return Vec3(std::atan2(-R(0, 1), R(1, 1)), b, std::atan2(-R(2, 0), R(2, 2)));
}
Mat3 ZxyRotation(const Vec3& abc) {
  return (Eigen::AngleAxisd(abc[0], Vec3::UnitZ()) * Eigen::AngleAxisd(abc[1], Vec3::UnitX()) *
          Eigen::AngleAxisd(abc[2], Vec3::UnitY()))
      .toRotationMatrix();
}

btVector3 Bt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }
Vec3 Ei(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }
btQuaternion BtQ(const Mat3& R) {
  const Quat q(R);
  return btQuaternion(q.x(), q.y(), q.z(), q.w());
}
btTransform Bt(const Transform& T) { return btTransform(BtQ(T.linear()), Bt(T.translation())); }
Transform Ei(const btTransform& T) {
  const btQuaternion q = T.getRotation();
  return MakeTransform(Ei(T.getOrigin()), Quat(q.w(), q.x(), q.y(), q.z()));
}

// A convex piece as a Bullet child shape and its transform in the body frame.
std::pair<btCollisionShape*, btTransform> MakeChild(const ConvexPiece& p,
                                                    const Transform& T_body_frame_inv) {
  btCollisionShape* shape = nullptr;
  Transform T = T_body_frame_inv * p.T_BS;
  switch (p.kind) {
    case ConvexPiece::Kind::kSphere:
      shape = new btSphereShape(p.radius);
      break;
    case ConvexPiece::Kind::kCapsule:
      shape = new btCapsuleShapeZ(p.radius, 2.0 * p.half_length);
      break;
    case ConvexPiece::Kind::kCylinder: {
      auto* c = new btCylinderShapeZ(btVector3(p.radius, p.radius, p.half_length));
      c->setMargin(kMargin);
      shape = c;
      break;
    }
    case ConvexPiece::Kind::kBox: {
      auto* b = new btBoxShape(Bt(p.half_extents));
      b->setMargin(kMargin);
      shape = b;
      break;
    }
    case ConvexPiece::Kind::kHull: {
      auto* h = new btConvexHullShape();
      // Shrunk by the margin, so that the inflated hull is the true surface.
      Vec3 c = Vec3::Zero();
      for (const Vec3& v : p.hull_vertices) c += v;
      c /= static_cast<double>(p.hull_vertices.size());
      const Vec3 cl = T_body_frame_inv * c;
      for (const Vec3& v : p.hull_vertices) {
        const Vec3 local = T_body_frame_inv * v;
        const double len = (local - cl).norm();
        h->addPoint(Bt(len > kMargin ? Vec3(cl + (local - cl) * (1.0 - kMargin / len)) : local),
                    false);
      }
      h->recalcLocalAabb();
      h->setMargin(kMargin);
      shape = h;
      T = Transform::Identity();
      break;
    }
  }
  return {shape, Bt(T)};
}

double Unwrap(double angle, double reference) {
  while (angle - reference > M_PI) angle -= 2 * M_PI;
  while (angle - reference < -M_PI) angle += 2 * M_PI;
  return angle;
}

}  // namespace

struct World::Impl {
  const HandModel& hand;
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  btMultiBodyDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::unique_ptr<btDefaultMotionState> object_state, table_state;
  std::unique_ptr<btRigidBody> object, table;
  std::vector<std::unique_ptr<btDefaultMotionState>> prop_states;
  std::vector<std::unique_ptr<btRigidBody>> props;
  std::unique_ptr<btMultiBody> mb;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
  std::vector<std::unique_ptr<btMultiBodyJointMotor>> motors;  // arm first, then hand q order
  std::vector<std::unique_ptr<btMultiBodyJointLimitConstraint>> limits;
  std::vector<int> q_link;   // multibody link of each hand q entry
  std::vector<int> link_of;  // multibody link of each hand link (-1: the palm is link 5)
  Transform T_OB = Transform::Identity();
  Vec3 last_rpy = Vec3::Zero();  // last arm rotation angles, for unwrapping
  explicit Impl(const HandModel& h) : hand(h) {}
};

World::World(const HandModel& hand, const ObjectModel& object, const Transform& T_WO,
             double friction_links, const Transform& T_WP0, const Eigen::VectorXd& q0,
             const std::vector<std::pair<Transform, Vec3>>& props, double pad_stiffness,
             double pad_damping)
    : impl_(std::make_unique<Impl>(hand)) {
  Impl& w = *impl_;
  w.world.setGravity(btVector3(0, 0, -9.81));
  btContactSolverInfo& si = w.world.getSolverInfo();
  si.m_numIterations = 80;
  si.m_splitImpulse = true;
  si.m_erp = 0.2;
  si.m_erp2 = 0.4;

  // Table: top face at z = 0.
  auto* table_shape = new btBoxShape(btVector3(0.6, 0.4, 0.025));
  table_shape->setMargin(kMargin);
  w.shapes.emplace_back(table_shape);
  w.table_state = std::make_unique<btDefaultMotionState>(
      btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -0.025)));
  w.table = std::make_unique<btRigidBody>(
      btRigidBody::btRigidBodyConstructionInfo(0.0, w.table_state.get(), table_shape));
  w.table->setFriction(0.5);
  w.table->setUserIndex(-2);
  w.world.addRigidBody(w.table.get());

  for (const auto& [T, half] : props) {
    auto* box = new btBoxShape(Bt(half));
    box->setMargin(kMargin);
    w.shapes.emplace_back(box);
    w.prop_states.push_back(std::make_unique<btDefaultMotionState>(Bt(T)));
    w.props.push_back(std::make_unique<btRigidBody>(
        btRigidBody::btRigidBodyConstructionInfo(0.0, w.prop_states.back().get(), box)));
    w.props.back()->setFriction(0.6);
    w.props.back()->setUserIndex(-2);
    w.world.addRigidBody(w.props.back().get());
  }

  // Object: body frame at the centre of mass along the principal axes.
  Eigen::SelfAdjointEigenSolver<Mat3> eig(object.inertia_com);
  Mat3 axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  w.T_OB = MakeTransform(object.com_O, axes);
  auto* compound = new btCompoundShape();
  w.shapes.emplace_back(compound);
  for (const ConvexPiece& p : object.pieces) {
    auto [shape, T] = MakeChild(p, w.T_OB.inverse());
    w.shapes.emplace_back(shape);
    compound->addChildShape(T, shape);
  }
  w.object_state = std::make_unique<btDefaultMotionState>(Bt(T_WO * w.T_OB));
  w.object = std::make_unique<btRigidBody>(btRigidBody::btRigidBodyConstructionInfo(
      object.mass, w.object_state.get(), compound, Bt(eig.eigenvalues().cwiseMax(1e-9))));
  w.object->setFriction(object.friction);
  w.object->setRollingFriction(0.001);
  w.object->setSpinningFriction(0.001);
  w.object->setActivationState(DISABLE_DEACTIVATION);
  w.object->setCcdMotionThreshold(
      0.002);  // thin objects (the pen) must not tunnel through the table
  w.object->setCcdSweptSphereRadius(0.002);
  w.object->setUserIndex(-1);
  w.world.addRigidBody(w.object.get());

  // The multibody: 6 arm joints, the palm as the last arm link, then the hand's links.
  const int hand_links = static_cast<int>(hand.links.size()) - 1;  // all but the root
  const int num_links = kArmDofs + hand_links;
  w.mb = std::make_unique<btMultiBody>(num_links, 0.0, btVector3(0, 0, 0), true, false);
  w.mb->setHasSelfCollision(false);
  const btQuaternion id = btQuaternion::getIdentity();
  const btVector3 zero(0, 0, 0), small(1e-3, 1e-3, 1e-3);
  w.mb->setupPrismatic(0, 2.0, small, -1, id, btVector3(1, 0, 0), zero, zero, true);
  w.mb->setupPrismatic(1, 2.0, small, 0, id, btVector3(0, 1, 0), zero, zero, true);
  w.mb->setupPrismatic(2, 2.0, small, 1, id, btVector3(0, 0, 1), zero, zero, true);
  w.mb->setupRevolute(3, 1.0, small, 2, id, btVector3(0, 0, 1), zero, zero, true);
  w.mb->setupRevolute(4, 1.0, small, 3, id, btVector3(1, 0, 0), zero, zero, true);
  w.mb->setupRevolute(5, 0.5, Bt(Vec3(4e-4, 4e-4, 6e-4)), 4, id, btVector3(0, 1, 0), zero, zero,
                      true);
  w.link_of.assign(hand.links.size(), -1);
  w.link_of[static_cast<std::size_t>(hand.root_link)] = 5;
  int next = kArmDofs;
  for (const Joint& joint : hand.joints) {  // topological: parents first
    const int link = next++;
    w.link_of[static_cast<std::size_t>(joint.child_link)] = link;
    const int parent = w.link_of[static_cast<std::size_t>(joint.parent_link)];
    const double mass = kLinkMass;
    const btQuaternion rot = BtQ(joint.T_LJ.linear().transpose());
    const btVector3 offset = Bt(joint.T_LJ.translation());
    if (joint.type == JointType::kFixed) {
      w.mb->setupFixed(link, mass, Bt(Vec3::Constant(2e-6)), parent, rot, offset, zero, true);
    } else if (joint.type == JointType::kPrismatic) {
      w.mb->setupPrismatic(link, mass, Bt(Vec3::Constant(2e-6)), parent, rot, Bt(joint.axis),
                           offset, zero, true);
    } else {
      w.mb->setupRevolute(link, mass, Bt(Vec3::Constant(2e-6)), parent, rot, Bt(joint.axis), offset,
                          zero, true);
    }
  }
  w.mb->finalizeMultiDof();
  w.world.addMultiBody(w.mb.get());

  // Colliders: the palm on arm link 5, every hand link with geometry on its multibody link.
  for (std::size_t l = 0; l < hand.links.size(); ++l) {
    if (hand.links[l].collision.empty()) continue;
    const int link = w.link_of[l];
    auto* c = new btCompoundShape();
    w.shapes.emplace_back(c);
    for (const ConvexPiece& p : hand.links[l].collision) {
      auto [shape, T] = MakeChild(p, Transform::Identity());
      w.shapes.emplace_back(shape);
      c->addChildShape(T, shape);
    }
    auto collider = std::make_unique<btMultiBodyLinkCollider>(w.mb.get(), link);
    collider->setCollisionShape(c);
    collider->setFriction(friction_links);
    collider->setUserIndex(static_cast<int>(l));
    const bool fingertip = std::none_of(
        hand.joints.begin(), hand.joints.end(),
        [&](const Joint& j) { return j.parent_link == static_cast<int>(l) && j.moves(); });
    if (pad_stiffness > 0 && fingertip)
      collider->setContactStiffnessAndDamping(pad_stiffness, pad_damping);
    w.world.addCollisionObject(collider.get(), btBroadphaseProxy::DefaultFilter,
                               btBroadphaseProxy::AllFilter);
    w.mb->getLink(link).m_collider = collider.get();
    w.colliders.push_back(std::move(collider));
  }

  // Constraints are solved per simulation island, found through link colliders: links without
  // geometry get a collider that collides with nothing, or their motors would be ignored.
  auto* ghost_shape = new btSphereShape(0.001);
  w.shapes.emplace_back(ghost_shape);
  for (int link = 0; link < num_links; ++link) {
    if (w.mb->getLink(link).m_collider != nullptr) continue;
    auto collider = std::make_unique<btMultiBodyLinkCollider>(w.mb.get(), link);
    collider->setCollisionShape(ghost_shape);
    collider->setUserIndex(-3);
    w.world.addCollisionObject(collider.get(), 0, 0);
    w.mb->getLink(link).m_collider = collider.get();
    w.colliders.push_back(std::move(collider));
  }

  // Motors and joint limits.
  for (int i = 0; i < kArmDofs; ++i) {
    w.motors.push_back(std::make_unique<btMultiBodyJointMotor>(w.mb.get(), i, 0.0, 500.0));
    w.motors.back()->setErp(1.0);
    w.world.addMultiBodyConstraint(w.motors.back().get());
  }
  for (int j : hand.q_joints)
    w.q_link.push_back(
        w.link_of[static_cast<std::size_t>(hand.joints[static_cast<std::size_t>(j)].child_link)]);
  for (int i = 0; i < hand.num_q(); ++i) {
    const Joint& joint = hand.QJoint(i);
    w.motors.push_back(std::make_unique<btMultiBodyJointMotor>(
        w.mb.get(), w.q_link[static_cast<std::size_t>(i)], 0.0, 0.001));
    w.motors.back()->setErp(1.0);
    w.world.addMultiBodyConstraint(w.motors.back().get());
    if (joint.has_limits) {
      w.limits.push_back(std::make_unique<btMultiBodyJointLimitConstraint>(
          w.mb.get(), w.q_link[static_cast<std::size_t>(i)], joint.lower, joint.upper));
      w.world.addMultiBodyConstraint(w.limits.back().get());
    }
  }

  // Initial state.
  const Vec3 abc = ZxyAngles(T_WP0.linear());
  w.last_rpy = abc;
  const double arm[kArmDofs] = {T_WP0.translation().x(),
                                T_WP0.translation().y(),
                                T_WP0.translation().z(),
                                abc[0],
                                abc[1],
                                abc[2]};
  for (int i = 0; i < kArmDofs; ++i) w.mb->setJointPos(i, arm[i]);
  for (int i = 0; i < hand.num_q(); ++i)
    w.mb->setJointPos(w.q_link[static_cast<std::size_t>(i)], q0[i]);
  btAlignedObjectArray<btQuaternion> scratch_q;
  btAlignedObjectArray<btVector3> scratch_m;
  w.mb->forwardKinematics(scratch_q, scratch_m);
  w.mb->updateCollisionObjectWorldTransforms(scratch_q, scratch_m);
  SetTargets(T_WP0, q0, Eigen::VectorXd::Constant(hand.num_q(), 0.1));
}

World::~World() {
  Impl& w = *impl_;
  for (auto& m : w.motors) w.world.removeMultiBodyConstraint(m.get());
  for (auto& l : w.limits) w.world.removeMultiBodyConstraint(l.get());
  for (auto& c : w.colliders) w.world.removeCollisionObject(c.get());
  w.world.removeMultiBody(w.mb.get());
  w.world.removeRigidBody(w.object.get());
  w.world.removeRigidBody(w.table.get());
  for (auto& p : w.props) w.world.removeRigidBody(p.get());
}

void World::SetTargets(const Transform& T_WP, const Eigen::VectorXd& q_target,
                       const Eigen::VectorXd& tau_max) {
  Impl& w = *impl_;
  Vec3 abc = ZxyAngles(T_WP.linear());
  for (int k = 0; k < 3; ++k) abc[k] = Unwrap(abc[k], w.last_rpy[k]);
  w.last_rpy = abc;
  const double arm[kArmDofs] = {T_WP.translation().x(),
                                T_WP.translation().y(),
                                T_WP.translation().z(),
                                abc[0],
                                abc[1],
                                abc[2]};
  for (int i = 0; i < kArmDofs; ++i) {
    w.motors[static_cast<std::size_t>(i)]->setPositionTarget(arm[i], 0.5);
    w.motors[static_cast<std::size_t>(i)]->setVelocityTarget(0.0, 0.5);
  }
  last_tau_max_ = tau_max;
  for (int i = 0; i < w.hand.num_q(); ++i) {
    btMultiBodyJointMotor& m = *w.motors[static_cast<std::size_t>(kArmDofs + i)];
    m.setPositionTarget(q_target[i], 0.2);
    m.setVelocityTarget(0.0, 0.3);
  }
}

void World::Step(double dt) {
  Impl& w = *impl_;
  for (int i = 0; i < w.hand.num_q(); ++i)
    w.motors[static_cast<std::size_t>(kArmDofs + i)]->setMaxAppliedImpulse(last_tau_max_[i] * dt);
  w.world.stepSimulation(dt, 0, dt);
  contacts_.clear();
  touches_table_ = false;
  const int n = w.dispatcher.getNumManifolds();
  for (int i = 0; i < n; ++i) {
    btPersistentManifold* m = w.dispatcher.getManifoldByIndexInternal(i);
    const btCollisionObject* a = m->getBody0();
    const btCollisionObject* b = m->getBody1();
    const bool a_obj = a == w.object.get(), b_obj = b == w.object.get();
    if (!a_obj && !b_obj) continue;
    const btCollisionObject* other = a_obj ? b : a;
    if (other == w.table.get() || other->getUserIndex() == -2) {
      for (int k = 0; k < m->getNumContacts(); ++k)
        if (m->getContactPoint(k).getDistance() < 0.001) touches_table_ = true;
      continue;
    }
    const int link = other->getUserIndex();
    if (link < 0) continue;
    for (int k = 0; k < m->getNumContacts(); ++k) {
      const btManifoldPoint& pt = m->getContactPoint(k);
      // Impulses the solver applied to body 0 (the normal points from body 1 to body 0).
      const Vec3 impulse_on_0 = Ei(pt.m_normalWorldOnB) * pt.m_appliedImpulse +
                                Ei(pt.m_lateralFrictionDir1) * pt.m_appliedImpulseLateral1 +
                                Ei(pt.m_lateralFrictionDir2) * pt.m_appliedImpulseLateral2;
      LinkContact c;
      c.link = link;
      c.distance = pt.getDistance();
      c.point_W = Ei(a_obj ? pt.getPositionWorldOnB() : pt.getPositionWorldOnA());
      c.force_W = (a_obj ? impulse_on_0 : Vec3(-impulse_on_0)) / dt;
      contacts_.push_back(c);
    }
  }
}

Eigen::VectorXd World::JointPositions() const {
  Eigen::VectorXd q(impl_->hand.num_q());
  for (int i = 0; i < q.size(); ++i)
    q[i] = impl_->mb->getJointPos(impl_->q_link[static_cast<std::size_t>(i)]);
  return q;
}

Transform World::PalmPose() const {
  const btMultiBody& mb = *impl_->mb;
  const Vec3 p(mb.getJointPos(0), mb.getJointPos(1), mb.getJointPos(2));
  return MakeTransform(p,
                       ZxyRotation(Vec3(mb.getJointPos(3), mb.getJointPos(4), mb.getJointPos(5))));
}

Transform World::ObjectPose() const {
  btTransform T;
  impl_->object->getMotionState()->getWorldTransform(T);
  return Ei(T) * impl_->T_OB.inverse();
}

Vec3 World::ObjectLinearVelocity() const { return Ei(impl_->object->getLinearVelocity()); }

}  // namespace inhand::sim
