#include "inhand/contacts/bullet_contact_query.hpp"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <limits>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

// Hulls are inflated by this margin for EPA's sake; results are deflated again.
constexpr double kHullMargin = 1e-3;      // [m]
constexpr double kCylinderMargin = 1e-4;  // [m] rim rounding of cylinders

struct Shape {
  std::unique_ptr<btConvexShape> shape;
  Transform T_BS = Transform::Identity();  // Bullet shape frame in the body frame
  double extra_margin = 0.0;               // inflation beyond the true surface
  Vec3 center_B = Vec3::Zero();            // bounding sphere, body frame
  double radius = 0.0;
};

btVector3 ToBt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }
Vec3 FromBt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

btTransform ToBt(const Transform& T) {
  const Mat3& R = T.linear();
  return btTransform(btMatrix3x3(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                     ToBt(T.translation()));
}

Shape MakeShape(const ConvexPiece& piece) {
  Shape s;
  s.center_B = piece.bounding_center;
  s.radius = piece.bounding_radius;
  switch (piece.kind) {
    case ConvexPiece::Kind::kSphere:
      s.shape = std::make_unique<btSphereShape>(piece.radius);
      s.T_BS = piece.T_BS;
      return s;
    case ConvexPiece::Kind::kCapsule:
      s.shape = std::make_unique<btCapsuleShapeZ>(piece.radius, 2.0 * piece.half_length);
      s.T_BS = piece.T_BS;
      return s;
    case ConvexPiece::Kind::kCylinder: {
      auto cyl = std::make_unique<btCylinderShapeZ>(btVector3(piece.radius, piece.radius, piece.half_length));
      cyl->setMargin(kCylinderMargin);
      s.shape = std::move(cyl);
      s.T_BS = piece.T_BS;
      return s;
    }
    case ConvexPiece::Kind::kBox:
    case ConvexPiece::Kind::kHull: {
      // Vertices in the body frame: the Bullet shape frame is the body frame.
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vec3& v : piece.hull_vertices) hull->addPoint(ToBt(v), false);
      hull->recalcLocalAabb();
      hull->setMargin(kHullMargin);
      s.shape = std::move(hull);
      s.extra_margin = kHullMargin;
      s.radius += kHullMargin;
      return s;
    }
  }
  INHAND_CHECK(false, "unknown convex piece kind");
}

}  // namespace

struct BulletContactQuery::Impl {
  std::vector<std::vector<Shape>> link_shapes;  // per link, possibly empty
  std::vector<Shape> object_shapes;
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver epa;
  Stats stats;

  // Signed distance between two placed shapes; A is the link's, B the object's.
  ContactPair Pair(const Shape& a, const Transform& T_PA, const Shape& b, const Transform& T_PB) {
    ++stats.pairs_tested;
    btGjkPairDetector detector(a.shape.get(), b.shape.get(), &simplex, &epa);
    btGjkPairDetector::ClosestPointInput input;
    input.m_transformA = ToBt(T_PA * a.T_BS);
    input.m_transformB = ToBt(T_PB * b.T_BS);
    btPointCollector collector;
    detector.getClosestPoints(input, collector, nullptr);
    ContactPair pair;
    if (!collector.m_hasResult) {
      pair.distance = std::numeric_limits<double>::infinity();
      return pair;
    }
    const Vec3 n = FromBt(collector.m_normalOnBInWorld);  // object → link
    const Vec3 p_b = FromBt(collector.m_pointInWorld);
    const double d = collector.m_distance;
    const Vec3 p_a = p_b + n * d;
    pair.distance = d + a.extra_margin + b.extra_margin;
    pair.c_f_P = p_a + n * a.extra_margin;
    pair.c_o_P = p_b - n * b.extra_margin;
    pair.normal_P = -n;
    return pair;
  }

  void Run(const std::vector<Transform>& T_PL, const Transform& T_PO, double max_distance,
           bool broad_phase, std::vector<ContactPair>& out) {
    INHAND_CHECK(T_PL.size() == link_shapes.size(), "link poses do not match the hand model");
    out.clear();
    for (std::size_t l = 0; l < link_shapes.size(); ++l) {
      ContactPair best;
      best.distance = std::numeric_limits<double>::infinity();
      for (const Shape& a : link_shapes[l]) {
        const Vec3 ca = T_PL[l] * a.center_B;
        for (std::size_t o = 0; o < object_shapes.size(); ++o) {
          const Shape& b = object_shapes[o];
          if (broad_phase) {
            const double lower = (ca - T_PO * b.center_B).norm() - a.radius - b.radius;
            if (lower > max_distance || lower > best.distance) {
              ++stats.pairs_skipped;
              continue;
            }
          }
          ContactPair pair = Pair(a, T_PL[l], b, T_PO);
          if (pair.distance < best.distance) {
            best = pair;
            best.piece = static_cast<int>(o);
          }
        }
      }
      if (best.distance <= max_distance || best.distance < 0.0) {
        best.link = static_cast<int>(l);
        out.push_back(best);
      }
    }
  }
};

BulletContactQuery::BulletContactQuery(const HandModel& hand, const ObjectModel& object)
    : impl_(std::make_unique<Impl>()) {
  impl_->link_shapes.resize(hand.links.size());
  for (std::size_t l = 0; l < hand.links.size(); ++l)
    for (const ConvexPiece& p : hand.links[l].collision) impl_->link_shapes[l].push_back(MakeShape(p));
  for (const ConvexPiece& p : object.pieces) impl_->object_shapes.push_back(MakeShape(p));
}

BulletContactQuery::~BulletContactQuery() = default;

void BulletContactQuery::Query(const std::vector<Transform>& T_PL, const Transform& T_PO,
                               double max_distance, std::vector<ContactPair>& out) {
  impl_->Run(T_PL, T_PO, max_distance, true, out);
}

void BulletContactQuery::QueryExhaustive(const std::vector<Transform>& T_PL, const Transform& T_PO,
                                         double max_distance, std::vector<ContactPair>& out) {
  impl_->Run(T_PL, T_PO, max_distance, false, out);
}

ContactPair BulletContactQuery::QueryPair(int link, int link_piece, int object_piece,
                                          const Transform& T_PL, const Transform& T_PO) {
  ContactPair pair = impl_->Pair(impl_->link_shapes.at(link).at(link_piece), T_PL,
                                 impl_->object_shapes.at(object_piece), T_PO);
  pair.link = link;
  pair.piece = object_piece;
  return pair;
}

ContactQuery::Stats BulletContactQuery::stats() const { return impl_->stats; }

}  // namespace inhand
