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

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

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
  return btTransform(
      btMatrix3x3(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
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
      auto cyl = std::make_unique<btCylinderShapeZ>(
          btVector3(piece.radius, piece.radius, piece.half_length));
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

// A link piece seen by the object's distance field: a sphere or a capsule by its core (centre
// or segment) and radius, anything else by points on its surface, grouped into patches with a
// bounding sphere each so that the field's 1-Lipschitz bound skips most of them.
struct FieldProbe {
  enum class Kind { kSphere, kSegment, kPoints } kind = Kind::kPoints;
  double radius = 0.0;           // sphere / capsule radius
  Vec3 a_B = Vec3::Zero();       // centre, or segment end
  Vec3 b_B = Vec3::Zero();       // segment end
  Vec3 center_B = Vec3::Zero();  // bounding sphere of the piece
  double bound = 0.0;
  struct Patch {
    Vec3 center_B;
    double radius;
    int first, count;  // points_B (clusters: patches)
  };
  std::vector<Patch> patches;
  std::vector<Patch> clusters;  // patches by cells of kClusterCells^3 patch cells, contiguous
  std::vector<Vec3> points_B;
};

constexpr double kSampleSpacing = 1.5e-3;  // [m] between surface samples of boxes and hulls
constexpr double kPatchSize = 6e-3;        // [m] patch cell
constexpr long long kClusterCells = 4;     // patch cells per cluster cell along each axis

FieldProbe MakeProbe(const ConvexPiece& piece) {
  FieldProbe p;
  p.center_B = piece.bounding_center;
  p.bound = piece.bounding_radius;
  if (piece.kind == ConvexPiece::Kind::kSphere) {
    p.kind = FieldProbe::Kind::kSphere;
    p.radius = piece.radius;
    p.a_B = piece.T_BS.translation();
    return p;
  }
  if (piece.kind == ConvexPiece::Kind::kCapsule) {
    p.kind = FieldProbe::Kind::kSegment;
    p.radius = piece.radius;
    p.a_B = piece.T_BS * Vec3(0, 0, -piece.half_length);
    p.b_B = piece.T_BS * Vec3(0, 0, piece.half_length);
    return p;
  }
  // Points on every face at kSampleSpacing (barycentric grid per triangle, shared edges
  // deduplicated), then patches by a grid of kPatchSize cells in the body frame.
  std::map<std::array<long long, 3>, Vec3> unique;
  for (const auto& t : piece.hull_triangles) {
    const Vec3& A = piece.hull_vertices[t[0]];
    const Vec3& B = piece.hull_vertices[t[1]];
    const Vec3& C = piece.hull_vertices[t[2]];
    const double longest = std::max({(B - A).norm(), (C - B).norm(), (A - C).norm()});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / kSampleSpacing)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Vec3 x = A + (B - A) * (double(i) / n) + (C - A) * (double(j) / n);
        const std::array<long long, 3> key{std::llround(x.x() * 1e7), std::llround(x.y() * 1e7),
                                           std::llround(x.z() * 1e7)};
        unique.emplace(key, x);
      }
  }
  std::map<std::array<long long, 3>, std::vector<Vec3>> cells;
  for (const auto& [key, x] : unique) {
    const std::array<long long, 3> cell{static_cast<long long>(std::floor(x.x() / kPatchSize)),
                                        static_cast<long long>(std::floor(x.y() / kPatchSize)),
                                        static_cast<long long>(std::floor(x.z() / kPatchSize))};
    cells[cell].push_back(x);
  }
  // Clusters of patches (their points' bounding sphere), so that a far part of a palm costs one
  // bound instead of one per patch.
  const auto floor_div = [](long long a, long long b) {
    return a >= 0 ? a / b : -((-a + b - 1) / b);
  };
  std::map<std::array<long long, 3>, std::vector<const std::vector<Vec3>*>> clusters;
  for (const auto& [cell, pts] : cells)
    clusters[{floor_div(cell[0], kClusterCells), floor_div(cell[1], kClusterCells),
              floor_div(cell[2], kClusterCells)}]
        .push_back(&pts);
  for (const auto& [key, members] : clusters) {
    FieldProbe::Patch cluster;
    cluster.first = static_cast<int>(p.patches.size());
    cluster.count = static_cast<int>(members.size());
    Aabb cluster_box;
    for (const std::vector<Vec3>* pts : members) {
      FieldProbe::Patch patch;
      patch.first = static_cast<int>(p.points_B.size());
      patch.count = static_cast<int>(pts->size());
      Aabb box;
      for (const Vec3& x : *pts) box.Extend(x), cluster_box.Extend(x), p.points_B.push_back(x);
      patch.center_B = box.Center();
      patch.radius = 0.5 * box.Size().norm();
      p.patches.push_back(patch);
    }
    cluster.center_B = cluster_box.Center();
    cluster.radius = 0.5 * cluster_box.Size().norm();
    p.clusters.push_back(cluster);
  }
  return p;
}

}  // namespace

struct BulletContactQuery::Impl {
  std::vector<std::pair<double, int>> patch_order;  // scratch: (lower bound, patch)
  std::vector<std::vector<Shape>> link_shapes;      // per link, possibly empty
  std::vector<Shape> object_shapes;
  std::shared_ptr<const DistanceField> field;
  std::vector<std::vector<FieldProbe>> link_probes;  // per link, when `field` is set
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

  // fn(patch, lower bound) for every patch of a points probe whose lower bound on the field
  // (at its centre less its radius, 1-Lipschitz) is at most `threshold`; clusters first.
  template <class Fn>
  void ForPatchesWithin(const FieldProbe& probe, const Transform& T_OL, double threshold,
                        Fn&& fn) const {
    for (const FieldProbe::Patch& cluster : probe.clusters) {
      if (field->Distance(T_OL * cluster.center_B) - cluster.radius > threshold) continue;
      for (int c = cluster.first; c < cluster.first + cluster.count; ++c) {
        const FieldProbe::Patch& patch = probe.patches[static_cast<std::size_t>(c)];
        const double lower = field->Distance(T_OL * patch.center_B) - patch.radius;
        if (!(lower > threshold)) fn(c, lower);
      }
    }
  }

  // The deepest (or nearest) point of one link piece against the field, in the object frame.
  // Returns the signed distance; `x_O` is the point of the probe's core (sphere centre, segment
  // point or surface sample) where it is reached.
  double FieldDistance(const FieldProbe& probe, const Transform& T_OL, double prune, Vec3& x_O) {
    const DistanceField& f = *field;
    switch (probe.kind) {
      case FieldProbe::Kind::kSphere:
        ++stats.pairs_tested;
        x_O = T_OL * probe.a_B;
        return f.Distance(x_O) - probe.radius;
      case FieldProbe::Kind::kSegment: {
        ++stats.pairs_tested;
        // Samples every half grid step along the segment, the least one found coarse to fine
        // (every 8th first; a run between two is searched only if the field's 1-Lipschitz bound
        // lets it hold a smaller value; ties go to the first sample, as in a plain scan), then a
        // golden-section refinement around it.
        const Vec3 a = T_OL * probe.a_B, b = T_OL * probe.b_B;
        const int n = std::clamp(static_cast<int>((b - a).norm() / (0.5 * f.spacing)), 1, 128);
        const double step = (b - a).norm() / n;
        const auto at = [&](int i) { return f.Distance(a + (b - a) * (double(i) / n)); };
        constexpr int kCoarse = 8;
        double coarse[128 / kCoarse + 2];
        int num_coarse = 0;
        double best = std::numeric_limits<double>::infinity();
        int best_i = 0;
        const auto offer = [&](double d, int i) {
          if (d < best || (d == best && i < best_i)) best = d, best_i = i;
        };
        for (int i = 0; i <= n; i += kCoarse) offer(coarse[num_coarse++] = at(i), i);
        if (n % kCoarse != 0) offer(coarse[num_coarse++] = at(n), n);
        for (int c = 0; c + 1 < num_coarse; ++c) {
          const int i0 = c * kCoarse, i1 = std::min(n, i0 + kCoarse);
          // Between samples i0 and i1 the field is at least the larger of the two cones.
          for (int i = i0 + 1; i < i1; ++i)
            if (std::max(coarse[c] - (i - i0) * step, coarse[c + 1] - (i1 - i) * step) <= best)
              offer(at(i), i);
        }
        double lo = std::max(0.0, (best_i - 1.0) / n), hi = std::min(1.0, (best_i + 1.0) / n);
        constexpr double kGolden = 0.6180339887498949;
        double m1 = hi - kGolden * (hi - lo), m2 = lo + kGolden * (hi - lo);
        double f1 = f.Distance(a + (b - a) * m1), f2 = f.Distance(a + (b - a) * m2);
        for (int it = 0; it < 20; ++it) {  // one new value per iteration: the other is kept
          if (f1 < f2) {
            hi = m2, m2 = m1, f2 = f1;
            m1 = hi - kGolden * (hi - lo), f1 = f.Distance(a + (b - a) * m1);
          } else {
            lo = m1, m1 = m2, f1 = f2;
            m2 = lo + kGolden * (hi - lo), f2 = f.Distance(a + (b - a) * m2);
          }
        }
        const Vec3 x = a + (b - a) * (0.5 * (lo + hi));
        const double d = f.Distance(x);
        x_O = d < best ? x : Vec3(a + (b - a) * (double(best_i) / n));
        return std::min(d, best) - probe.radius;
      }
      case FieldProbe::Kind::kPoints: {
        // Branch and bound: the patches by their lower bound (the field at the centre less the
        // radius), nearest first, until the bound passes the best found (or the pruning
        // distance). Ties go to the first point in the probe's order, as in a plain scan.
        std::vector<std::pair<double, int>>& order = patch_order;
        order.clear();
        ForPatchesWithin(probe, T_OL, prune,
                         [&](int c, double lower) { order.emplace_back(lower, c); });
        stats.pairs_skipped += static_cast<long>(probe.patches.size() - order.size());
        std::sort(order.begin(), order.end());
        double best = std::numeric_limits<double>::infinity();
        int best_index = -1;
        std::size_t c = 0;
        for (; c < order.size() && !(order[c].first > std::min(best, prune)); ++c) {
          ++stats.pairs_tested;
          const FieldProbe::Patch& patch = probe.patches[static_cast<std::size_t>(order[c].second)];
          for (int i = patch.first; i < patch.first + patch.count; ++i) {
            const Vec3 x = T_OL * probe.points_B[static_cast<std::size_t>(i)];
            const double d = f.Distance(x);
            if (d < best || (d == best && i < best_index)) best = d, best_index = i, x_O = x;
          }
        }
        stats.pairs_skipped += static_cast<long>(order.size() - c);
        return best;
      }
    }
    return std::numeric_limits<double>::infinity();
  }

  void RunField(const std::vector<Transform>& T_PL, const Transform& T_PO, double max_distance,
                bool broad_phase, std::vector<ContactPair>& out) {
    const Transform T_OP = T_PO.inverse();
    for (std::size_t l = 0; l < link_probes.size(); ++l) {
      const Transform T_OL = T_OP * T_PL[l];
      double best = std::numeric_limits<double>::infinity();
      Vec3 best_x = Vec3::Zero();
      double best_radius = 0.0;
      for (const FieldProbe& probe : link_probes[l]) {
        const double prune = std::max(std::min(best, max_distance), 0.0);
        if (broad_phase && field->Distance(T_OL * probe.center_B) - probe.bound > prune) {
          ++stats.pairs_skipped;
          continue;
        }
        Vec3 x;
        const double d = FieldDistance(
            probe, T_OL, broad_phase ? prune : std::numeric_limits<double>::infinity(), x);
        if (d < best) {
          best = d;
          best_x = x;
          best_radius = probe.kind == FieldProbe::Kind::kPoints ? 0.0 : probe.radius;
        }
      }
      if (!(best <= max_distance || best < 0.0)) continue;
      Vec3 n_O;
      const double core = field->Distance(best_x, &n_O);  // n_O: outward normal of the object
      if (best < 0.0) {
        // A box or hull in the object: the normal is the depth-weighted mean of the field's
        // gradient over every surface sample inside (the direction that pushes the penetrating
        // patch out as a whole). The deepest sample's own gradient alone turns sideways where the
        // link reaches the object's medial axis (a palm across a marker 9 mm thick).
        Vec3 sum = Vec3::Zero();
        for (const FieldProbe& probe : link_probes[l]) {
          if (probe.kind != FieldProbe::Kind::kPoints) continue;
          if (field->Distance(T_OL * probe.center_B) - probe.bound > 0.0) continue;
          ForPatchesWithin(probe, T_OL, 0.0, [&](int c, double) {
            const FieldProbe::Patch& patch = probe.patches[static_cast<std::size_t>(c)];
            for (int i = patch.first; i < patch.first + patch.count; ++i) {
              const Vec3 x = T_OL * probe.points_B[static_cast<std::size_t>(i)];
              const double d = field->Distance(x);
              if (!(d < 0.0)) continue;
              Vec3 g;
              field->Distance(x, &g);  // the gradient only where it counts
              sum -= d * g;
            }
          });
        }
        if (sum.norm() > 1e-12 && best_radius == 0.0) n_O = sum.normalized();
      }
      ContactPair pair;
      pair.link = static_cast<int>(l);
      pair.piece = -1;
      pair.distance = best;
      pair.c_o_P = T_PO * Vec3(best_x - core * n_O);
      pair.c_f_P = T_PO * Vec3(best_x - best_radius * n_O);
      pair.normal_P = T_PO.linear() * (-n_O);
      out.push_back(pair);
    }
  }

  void Run(const std::vector<Transform>& T_PL, const Transform& T_PO, double max_distance,
           bool broad_phase, std::vector<ContactPair>& out) {
    INHAND_CHECK(T_PL.size() == link_shapes.size(), "link poses do not match the hand model");
    out.clear();
    if (field) {
      RunField(T_PL, T_PO, max_distance, broad_phase, out);
      return;
    }
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
    for (const ConvexPiece& p : hand.links[l].collision)
      impl_->link_shapes[l].push_back(MakeShape(p));
  for (const ConvexPiece& p : object.pieces) impl_->object_shapes.push_back(MakeShape(p));
  if (object.field && !object.field->empty()) {
    impl_->field = object.field;
    impl_->link_probes.resize(hand.links.size());
    for (std::size_t l = 0; l < hand.links.size(); ++l)
      for (const ConvexPiece& p : hand.links[l].collision)
        impl_->link_probes[l].push_back(MakeProbe(p));
  }
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
