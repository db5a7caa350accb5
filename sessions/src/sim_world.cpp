#include "sim_world.hpp"

#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>

#include "inhand/core/error.hpp"

namespace inhand::sim {

namespace {

constexpr double kMargin = 0.0005;  // [m] collision margin of hulls and boxes

btVector3 Bt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }
Vec3 Ei(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }
btTransform Bt(const Transform& T) {
  const Quat q(T.linear());
  return btTransform(btQuaternion(q.x(), q.y(), q.z(), q.w()), Bt(T.translation()));
}
Transform Ei(const btTransform& T) {
  const btQuaternion q = T.getRotation();
  return MakeTransform(Ei(T.getOrigin()), Quat(q.w(), q.x(), q.y(), q.z()));
}

// A convex piece as a Bullet child shape and its transform in the body frame.
std::pair<btCollisionShape*, btTransform> MakeChild(const ConvexPiece& p, const Transform& T_body_frame_inv) {
  btCollisionShape* shape = nullptr;
  Transform T = T_body_frame_inv * p.T_BS;
  switch (p.kind) {
    case ConvexPiece::Kind::kSphere: shape = new btSphereShape(p.radius); break;
    case ConvexPiece::Kind::kCapsule: shape = new btCapsuleShapeZ(p.radius, 2.0 * p.half_length); break;
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
      // Shrink by the margin so the inflated hull matches the true surface.
      Vec3 c = Vec3::Zero();
      for (const Vec3& v : p.hull_vertices) c += v;
      c /= static_cast<double>(p.hull_vertices.size());
      for (const Vec3& v : p.hull_vertices) {
        const Vec3 local = T_body_frame_inv * v;
        const Vec3 cl = T_body_frame_inv * c;
        const double len = (local - cl).norm();
        h->addPoint(Bt(len > kMargin ? Vec3(cl + (local - cl) * (1.0 - kMargin / len)) : local), false);
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

}  // namespace

struct World::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::vector<int> link_body;  // body index per link, -1 without collision
  btRigidBody* object = nullptr;
  btRigidBody* table = nullptr;
  Transform T_OB = Transform::Identity();  // object body frame (COM, principal axes) in O
  double last_dt = 0.001;

  btRigidBody* AddBody(btCollisionShape* shape, double mass, const Vec3& inertia, const Transform& T, int index) {
    states.push_back(std::make_unique<btDefaultMotionState>(Bt(T)));
    btRigidBody::btRigidBodyConstructionInfo info(mass, states.back().get(), shape, Bt(inertia));
    bodies.push_back(std::make_unique<btRigidBody>(info));
    btRigidBody* b = bodies.back().get();
    b->setUserIndex(index);
    world.addRigidBody(b);
    return b;
  }
};

World::World(const HandModel& hand, const ObjectModel& object, const Transform& T_WO, double friction_links)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.world.setGravity(btVector3(0, 0, -9.81));
  btContactSolverInfo& si = w.world.getSolverInfo();
  si.m_numIterations = 60;
  si.m_splitImpulse = true;
  si.m_splitImpulsePenetrationThreshold = -0.0002;
  si.m_erp = 0.2;
  si.m_erp2 = 0.4;

  // Table: top face at z = 0.
  auto* table_shape = new btBoxShape(btVector3(0.6, 0.4, 0.025));
  table_shape->setMargin(kMargin);
  w.shapes.emplace_back(table_shape);
  w.table = w.AddBody(table_shape, 0.0, Vec3::Zero(), MakeTransform(Vec3(0, 0, -0.025), Mat3::Identity()), -2);
  w.table->setFriction(0.5);

  // Object: body frame at the centre of mass along the principal axes.
  Eigen::SelfAdjointEigenSolver<Mat3> eig(object.inertia_com);
  Mat3 axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  w.T_OB = MakeTransform(object.com_O, axes);
  auto* compound = new btCompoundShape();
  w.shapes.emplace_back(compound);
  const Transform T_BO = w.T_OB.inverse();
  for (const ConvexPiece& p : object.pieces) {
    auto [shape, T] = MakeChild(p, T_BO);
    w.shapes.emplace_back(shape);
    compound->addChildShape(T, shape);
  }
  w.object = w.AddBody(compound, object.mass, eig.eigenvalues().cwiseMax(1e-9), T_WO * w.T_OB, -1);
  w.object->setFriction(object.friction);
  w.object->setRollingFriction(0.0005);
  w.object->setSpinningFriction(0.0005);
  w.object->setActivationState(DISABLE_DEACTIVATION);
  w.object->setDamping(0.05, 0.1);
  w.object->setCcdMotionThreshold(0.005);
  w.object->setCcdSweptSphereRadius(0.005);

  // Hand links: kinematic compounds, poses set every step.
  w.link_body.assign(hand.links.size(), -1);
  for (std::size_t l = 0; l < hand.links.size(); ++l) {
    if (hand.links[l].collision.empty()) continue;
    auto* c = new btCompoundShape();
    w.shapes.emplace_back(c);
    for (const ConvexPiece& p : hand.links[l].collision) {
      auto [shape, T] = MakeChild(p, Transform::Identity());
      w.shapes.emplace_back(shape);
      c->addChildShape(T, shape);
    }
    btRigidBody* b = w.AddBody(c, 0.0, Vec3::Zero(), Transform::Identity(), static_cast<int>(l));
    b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    b->setActivationState(DISABLE_DEACTIVATION);
    b->setFriction(friction_links);
    w.link_body[l] = static_cast<int>(w.bodies.size()) - 1;
  }
}

World::~World() {
  for (auto& b : impl_->bodies) impl_->world.removeRigidBody(b.get());
}

void World::SetLinkPoses(const std::vector<Transform>& T_WL) {
  for (std::size_t l = 0; l < impl_->link_body.size(); ++l) {
    const int b = impl_->link_body[l];
    if (b < 0) continue;
    impl_->states[static_cast<std::size_t>(b)]->setWorldTransform(Bt(T_WL[l]));
  }
}

void World::Step(double dt) {
  Impl& w = *impl_;
  w.last_dt = dt;
  w.world.stepSimulation(dt, 0, dt);
  contacts_.clear();
  touches_table_ = false;
  const int n = w.dispatcher.getNumManifolds();
  for (int i = 0; i < n; ++i) {
    btPersistentManifold* m = w.dispatcher.getManifoldByIndexInternal(i);
    const btCollisionObject* a = m->getBody0();
    const btCollisionObject* b = m->getBody1();
    const bool a_obj = a == w.object, b_obj = b == w.object;
    if (!a_obj && !b_obj) continue;
    const btCollisionObject* other = a_obj ? b : a;
    if (other == w.table) {
      for (int k = 0; k < m->getNumContacts(); ++k)
        if (m->getContactPoint(k).getDistance() < 0.001) touches_table_ = true;
      continue;
    }
    const int link = other->getUserIndex();
    if (link < 0) continue;
    for (int k = 0; k < m->getNumContacts(); ++k) {
      const btManifoldPoint& pt = m->getContactPoint(k);
      // The solver applied these impulses to body 0 (normal points from body 1 to body 0).
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

Transform World::ObjectPose() const {
  btTransform T;
  impl_->object->getMotionState()->getWorldTransform(T);
  return Ei(T) * impl_->T_OB.inverse();
}

Vec3 World::ObjectLinearVelocity() const { return Ei(impl_->object->getLinearVelocity()); }

}  // namespace inhand::sim
