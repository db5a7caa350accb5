#include "inhand/core/distance_field.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <thread>

#include "inhand/core/error.hpp"

namespace inhand {

void DistanceFieldParams::Validate(const std::string& where) const {
  if (!(spacing >= 1e-5 && spacing <= 0.1))
    throw InputError(where + ": contact field 'spacing' is " + std::to_string(spacing) +
                     ", expected in [1e-5, 0.1] m");
  if (!(padding >= 0.0 && padding <= 1.0))
    throw InputError(where + ": contact field 'padding' is " + std::to_string(padding) +
                     ", expected in [0, 1] m");
  if (max_nodes < 8 || max_nodes > 400'000'000)
    throw InputError(where + ": contact field 'max_nodes' is " + std::to_string(max_nodes) +
                     ", expected in [8, 4e8]");
}

double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                             Vec3* closest) {
  // Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions of the triangle.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  Vec3 q;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0.0 && d2 <= 0.0) {
    q = a;
  } else if (d3 >= 0.0 && d4 <= d3) {
    q = b;
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    q = a + ab * (d1 / (d1 - d3));
  } else if (d6 >= 0.0 && d5 <= d6) {
    q = c;
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    q = a + ac * (d2 / (d2 - d6));
  } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    q = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  } else {
    const double denom = va + vb + vc;
    if (!(std::abs(denom) > 0.0)) {
      q = a;  // degenerate triangle: its vertices are as close as it gets
    } else {
      q = a + ab * (vb / denom) + ac * (vc / denom);
    }
  }
  if (closest) *closest = q;
  return (p - q).norm();
}

namespace {

using Tri = std::array<Vec3, 3>;

// Bounding-volume hierarchy over triangles for nearest-point queries.
class TriangleBvh {
 public:
  explicit TriangleBvh(std::vector<Tri> tris) : tris_(std::move(tris)) {
    INHAND_CHECK(!tris_.empty(), "a distance field needs at least one triangle");
    order_.resize(tris_.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
    nodes_.reserve(2 * tris_.size() / kLeaf + 2);
    Build(0, static_cast<int>(order_.size()));
  }

  // Distance to the nearest triangle, searching only below `bound` (returns `bound` if none
  // is nearer).
  double Nearest(const Vec3& p, double bound) const {
    double best2 = bound * bound;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (BoxDistance2(n.box, p) >= best2) continue;
      if (n.count > 0) {
        for (int i = n.first; i < n.first + n.count; ++i) {
          const Tri& t = tris_[order_[i]];
          const double d = PointTriangleDistance(p, t[0], t[1], t[2]);
          best2 = std::min(best2, d * d);
        }
        continue;
      }
      const double dl = BoxDistance2(nodes_[n.left].box, p);
      const double dr = BoxDistance2(nodes_[n.right].box, p);
      INHAND_CHECK(top + 2 <= 128, "BVH deeper than its stack");
      if (dl < dr) {
        stack[top++] = n.right;
        stack[top++] = n.left;
      } else {
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
    return std::sqrt(best2);
  }

 private:
  static constexpr int kLeaf = 4;
  struct Node {
    Aabb box;
    int left = -1, right = -1;
    int first = 0, count = 0;  // leaf range in order_
  };

  static double BoxDistance2(const Aabb& b, const Vec3& p) {
    const Vec3 d = (b.min - p).cwiseMax(p - b.max).cwiseMax(0.0);
    return d.squaredNorm();
  }

  int Build(int first, int last) {
    const int index = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Aabb box, centres;
    for (int i = first; i < last; ++i) {
      const Tri& t = tris_[order_[i]];
      for (const Vec3& v : t) box.Extend(v);
      centres.Extend((t[0] + t[1] + t[2]) / 3.0);
    }
    nodes_[index].box = box;
    if (last - first <= kLeaf) {
      nodes_[index].first = first;
      nodes_[index].count = last - first;
      return index;
    }
    int axis = 0;
    centres.Size().maxCoeff(&axis);
    const int mid = (first + last) / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + last,
                     [&](int a, int b) {
                       const double ca = tris_[a][0][axis] + tris_[a][1][axis] + tris_[a][2][axis];
                       const double cb = tris_[b][0][axis] + tris_[b][1][axis] + tris_[b][2][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const int left = Build(first, mid);
    const int right = Build(mid, last);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }

  std::vector<Tri> tris_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

struct Grid {
  Vec3 origin;
  double h = 0.0;
  Eigen::Vector3i dims;
  long size() const { return static_cast<long>(dims[0]) * dims[1] * dims[2]; }
  Vec3 Node(int i, int j, int k) const { return origin + h * Vec3(i, j, k); }
};

Grid MakeGrid(const Aabb& surface_box, const DistanceFieldParams& params) {
  Grid g;
  const Vec3 lo = surface_box.min - Vec3::Constant(params.padding);
  const Vec3 size = surface_box.Size() + Vec3::Constant(2.0 * params.padding);
  g.h = params.spacing;
  for (;;) {
    for (int a = 0; a < 3; ++a) g.dims[a] = static_cast<int>(std::ceil(size[a] / g.h)) + 1;
    if (g.size() <= params.max_nodes) break;
    g.h *= 1.1;
  }
  // Centre the grid on the surface's box.
  g.origin = lo - 0.5 * (g.h * (g.dims.cast<double>() - Vec3::Ones()) - size);
  return g;
}

// Ray parity along `axis` for every node: 1 where the line through the node (offset by a tiny
// fixed amount so that it misses edges and vertices) crosses the surface an odd number of
// times before reaching it.
void ParityVotes(const std::vector<Tri>& tris, const Grid& g, int axis,
                 std::vector<std::uint8_t>& votes) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  const double db = g.h * 3.1e-4, dc = g.h * 4.7e-4;
  const int nb = g.dims[b], nc = g.dims[c];
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(nb) * nc);
  for (const Tri& t : tris) {
    double minb = t[0][b], maxb = minb, minc = t[0][c], maxc = minc;
    for (int v = 1; v < 3; ++v) {
      minb = std::min(minb, t[v][b]), maxb = std::max(maxb, t[v][b]);
      minc = std::min(minc, t[v][c]), maxc = std::max(maxc, t[v][c]);
    }
    const int j0 = std::max(0, static_cast<int>(std::ceil((minb - g.origin[b] - db) / g.h)));
    const int j1 = std::min(nb - 1, static_cast<int>(std::floor((maxb - g.origin[b] - db) / g.h)));
    const int k0 = std::max(0, static_cast<int>(std::ceil((minc - g.origin[c] - dc) / g.h)));
    const int k1 = std::min(nc - 1, static_cast<int>(std::floor((maxc - g.origin[c] - dc) / g.h)));
    for (int k = k0; k <= k1; ++k) {
      for (int j = j0; j <= j1; ++j) {
        const double qb = g.origin[b] + j * g.h + db, qc = g.origin[c] + k * g.h + dc;
        // Edge functions of the projected triangle.
        double w[3];
        for (int e = 0; e < 3; ++e) {
          const Vec3& p0 = t[(e + 1) % 3];
          const Vec3& p1 = t[(e + 2) % 3];
          w[e] = (p1[b] - p0[b]) * (qc - p0[c]) - (p1[c] - p0[c]) * (qb - p0[b]);
        }
        const bool pos = w[0] > 0.0 && w[1] > 0.0 && w[2] > 0.0;
        const bool neg = w[0] < 0.0 && w[1] < 0.0 && w[2] < 0.0;
        if (!pos && !neg) continue;
        const double sum = w[0] + w[1] + w[2];
        const double x = (w[0] * t[0][axis] + w[1] * t[1][axis] + w[2] * t[2][axis]) / sum;
        rows[static_cast<std::size_t>(k) * nb + j].push_back(x);
      }
    }
  }
  const int na = g.dims[axis];
  for (int k = 0; k < nc; ++k) {
    for (int j = 0; j < nb; ++j) {
      std::vector<double>& hits = rows[static_cast<std::size_t>(k) * nb + j];
      std::sort(hits.begin(), hits.end());
      std::size_t crossed = 0;
      for (int i = 0; i < na; ++i) {
        const double x = g.origin[axis] + i * g.h;
        while (crossed < hits.size() && hits[crossed] < x) ++crossed;
        if (crossed % 2 == 0) continue;
        Eigen::Vector3i n;
        n[axis] = i, n[b] = j, n[c] = k;
        ++votes[(static_cast<std::size_t>(n[2]) * g.dims[1] + n[1]) * g.dims[0] + n[0]];
      }
    }
  }
}

// Unsigned distances at every node (threads over z slices; each node is computed on its own,
// so the result does not depend on the thread count), then signed by `inside`.
template <typename InsideFn>
DistanceField Fill(const std::vector<Tri>& tris, const Grid& g, InsideFn&& inside,
                   std::string source) {
  const TriangleBvh bvh(tris);
  DistanceField f;
  f.origin = g.origin;
  f.spacing = g.h;
  f.dims = g.dims;
  f.values.assign(static_cast<std::size_t>(g.size()), 0.0f);
  f.source = std::move(source);
  const int threads =
      std::max(1, std::min(8, static_cast<int>(std::thread::hardware_concurrency())));
  auto work = [&](int t) {
    for (int k = t; k < g.dims[2]; k += threads) {
      for (int j = 0; j < g.dims[1]; ++j) {
        double prev = std::numeric_limits<double>::infinity();
        for (int i = 0; i < g.dims[0]; ++i) {
          // 1-Lipschitz: the neighbour's distance plus one step bounds the search.
          const double d = bvh.Nearest(g.Node(i, j, k), prev + 1.001 * g.h);
          prev = d;
          const std::size_t idx = (static_cast<std::size_t>(k) * g.dims[1] + j) * g.dims[0] + i;
          f.values[idx] = static_cast<float>(inside(idx, g.Node(i, j, k)) ? -d : d);
        }
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& th : pool) th.join();
  return f;
}

struct Planes {
  std::vector<Vec3> n;
  std::vector<double> d;
};

Planes HullPlanes(const ConvexPiece& piece) {
  Planes p;
  for (const auto& t : piece.hull_triangles) {
    const Vec3& a = piece.hull_vertices[t[0]];
    Vec3 n = (piece.hull_vertices[t[1]] - a).cross(piece.hull_vertices[t[2]] - a);
    const double len = n.norm();
    if (!(len > 0.0)) continue;
    n /= len;
    p.n.push_back(n);
    p.d.push_back(n.dot(a));
  }
  return p;
}

}  // namespace

double PieceSignedDistance(const ConvexPiece& piece, const Vec3& p) {
  const Vec3 s = piece.T_BS.inverse() * p;  // shape frame
  switch (piece.kind) {
    case ConvexPiece::Kind::kSphere:
      return s.norm() - piece.radius;
    case ConvexPiece::Kind::kCapsule: {
      const double z = std::clamp(s.z(), -piece.half_length, piece.half_length);
      return (s - Vec3(0, 0, z)).norm() - piece.radius;
    }
    case ConvexPiece::Kind::kCylinder: {
      const Vec2 d(Vec2(s.x(), s.y()).norm() - piece.radius, std::abs(s.z()) - piece.half_length);
      return std::min(std::max(d.x(), d.y()), 0.0) + d.cwiseMax(0.0).norm();
    }
    case ConvexPiece::Kind::kBox: {
      const Vec3 q = s.cwiseAbs() - piece.half_extents;
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case ConvexPiece::Kind::kHull: {
      const Planes planes = HullPlanes(piece);
      double inside = -std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < planes.n.size(); ++i)
        inside = std::max(inside, planes.n[i].dot(p) - planes.d[i]);
      if (inside <= 0.0) return inside;
      double best = std::numeric_limits<double>::infinity();
      for (const auto& t : piece.hull_triangles)
        best = std::min(
            best, PointTriangleDistance(p, piece.hull_vertices[t[0]], piece.hull_vertices[t[1]],
                                        piece.hull_vertices[t[2]]));
      return best;
    }
  }
  INHAND_CHECK(false, "unknown convex piece kind");
}

DistanceField BuildDistanceFieldFromMesh(const std::vector<const TriangleMesh*>& meshes,
                                         const DistanceFieldParams& params) {
  params.Validate("distance field");
  std::vector<Tri> tris;
  Aabb box;
  for (const TriangleMesh* m : meshes) {
    for (const auto& t : m->triangles) {
      tris.push_back({m->vertices[t[0]], m->vertices[t[1]], m->vertices[t[2]]});
      for (const Vec3& v : tris.back()) box.Extend(v);
    }
  }
  INHAND_CHECK(!tris.empty(), "a distance field needs triangles");
  const Grid g = MakeGrid(box, params);
  std::vector<std::uint8_t> votes(static_cast<std::size_t>(g.size()), 0);
  for (int axis = 0; axis < 3; ++axis) ParityVotes(tris, g, axis, votes);
  return Fill(
      tris, g, [&](std::size_t idx, const Vec3&) { return votes[idx] >= 2; },
      "closed mesh of " + std::to_string(tris.size()) + " triangles");
}

DistanceField BuildDistanceFieldFromPieces(const std::vector<ConvexPiece>& pieces,
                                           const DistanceFieldParams& params) {
  params.Validate("distance field");
  INHAND_CHECK(!pieces.empty(), "a distance field needs pieces");
  Aabb box;
  for (const ConvexPiece& p : pieces)
    for (const Vec3& v : p.hull_vertices) box.Extend(v);
  const Grid g = MakeGrid(box, params);
  // Primitives by their exact distance; hulls by their planes (cached).
  std::vector<Planes> planes;
  for (const ConvexPiece& p : pieces)
    planes.push_back(p.kind == ConvexPiece::Kind::kHull ? HullPlanes(p) : Planes{});
  auto inside_any = [&](const Vec3& x) {
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const ConvexPiece& p = pieces[i];
      if ((x - p.bounding_center).norm() > p.bounding_radius) continue;
      if (p.kind != ConvexPiece::Kind::kHull) {
        if (PieceSignedDistance(p, x) <= 0.0) return true;
        continue;
      }
      bool in = true;
      for (std::size_t f = 0; f < planes[i].n.size() && in; ++f)
        in = planes[i].n[f].dot(x) - planes[i].d[f] <= 0.0;
      if (in) return true;
    }
    return false;
  };
  // Surface = the parts of the pieces' faces with nothing of the union just outside them.
  const double max_edge = 2.0 * g.h;
  const double probe = 0.25 * g.h;
  std::vector<Tri> surface;
  std::vector<Tri> todo;
  for (const ConvexPiece& p : pieces) {
    for (const auto& t : p.hull_triangles)
      todo.push_back({p.hull_vertices[t[0]], p.hull_vertices[t[1]], p.hull_vertices[t[2]]});
    while (!todo.empty()) {
      const Tri t = todo.back();
      todo.pop_back();
      const double e0 = (t[1] - t[0]).norm(), e1 = (t[2] - t[1]).norm(), e2 = (t[0] - t[2]).norm();
      const double longest = std::max({e0, e1, e2});
      if (longest > max_edge) {
        // Split the longest edge.
        const int k = longest == e0 ? 0 : (longest == e1 ? 1 : 2);
        const Vec3 m = 0.5 * (t[k] + t[(k + 1) % 3]);
        todo.push_back({t[k], m, t[(k + 2) % 3]});
        todo.push_back({m, t[(k + 1) % 3], t[(k + 2) % 3]});
        continue;
      }
      const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
      if (!(n.norm() > 0.0)) continue;
      const Vec3 centre = (t[0] + t[1] + t[2]) / 3.0;
      if (!inside_any(centre + probe * n.normalized())) surface.push_back(t);
    }
  }
  INHAND_CHECK(!surface.empty(), "the union of the pieces has no surface");
  return Fill(
      surface, g, [&](std::size_t, const Vec3& x) { return inside_any(x); },
      "union of " + std::to_string(pieces.size()) + " pieces");
}

double DistanceField::Distance(const Vec3& p_O) const {
  // Grid coordinates, clamped into the grid; outside it, the distance to it is added (the
  // square root only then: inside is the common case).
  const double ux = (p_O.x() - origin.x()) / spacing, uy = (p_O.y() - origin.y()) / spacing,
               uz = (p_O.z() - origin.z()) / spacing;
  const double cx = std::min(std::max(ux, 0.0), dims[0] - 1.0);
  const double cy = std::min(std::max(uy, 0.0), dims[1] - 1.0);
  const double cz = std::min(std::max(uz, 0.0), dims[2] - 1.0);
  double outside = 0.0;
  if (cx != ux || cy != uy || cz != uz)
    outside =
        spacing * std::sqrt((ux - cx) * (ux - cx) + (uy - cy) * (uy - cy) + (uz - cz) * (uz - cz));
  const int i = std::min(static_cast<int>(cx), dims[0] - 2);
  const int j = std::min(static_cast<int>(cy), dims[1] - 2);
  const int k = std::min(static_cast<int>(cz), dims[2] - 2);
  const double fx = cx - i, fy = cy - j, fz = cz - k;
  const std::size_t sx = 1, sy = static_cast<std::size_t>(dims[0]),
                    sz = sy * static_cast<std::size_t>(dims[1]);
  const float* v = values.data() + k * sz + j * sy + i * sx;
  const double c00 = v[0] + fx * (v[sx] - v[0]);
  const double c10 = v[sy] + fx * (v[sy + sx] - v[sy]);
  const double c01 = v[sz] + fx * (v[sz + sx] - v[sz]);
  const double c11 = v[sz + sy] + fx * (v[sz + sy + sx] - v[sz + sy]);
  const double c0 = c00 + fy * (c10 - c00);
  const double c1 = c01 + fy * (c11 - c01);
  return c0 + fz * (c1 - c0) + outside;
}

double DistanceField::Distance(const Vec3& p_O, Vec3* unit_gradient) const {
  const double d = Distance(p_O);
  if (unit_gradient) {
    const double e = 0.5 * spacing;
    Vec3 g;
    for (int a = 0; a < 3; ++a) {
      const Vec3 step = e * Vec3::Unit(a);
      g[a] = Distance(p_O + step) - Distance(p_O - step);
    }
    const double len = g.norm();
    *unit_gradient = len > 0.0 ? Vec3(g / len) : Vec3::UnitZ();
  }
  return d;
}

Vec3 GrazingPoint(const DistanceField& field, const Vec3& x, const Vec3& eye, double max_travel) {
  const double step = 0.25 * field.spacing;
  const double level = field.Distance(x);
  const auto facing =
      [&](Vec3& p) {  // p onto the level set; returns n · v there (< 0: faces the eye)
        Vec3 n;
        for (int i = 0; i < 3; ++i) p -= (field.Distance(p, &n) - level) * n;
        return n.dot((p - eye).normalized());
      };
  Vec3 a = x;
  if (!(std::abs(level) < 4.0 * field.spacing) || !(facing(a) < 0.0)) return x;
  for (double travelled = 0.0; travelled < max_travel; travelled += step) {
    Vec3 n;
    field.Distance(a, &n);
    const Vec3 v = (a - eye).normalized();
    const Vec3 u = v - v.dot(n) * n;
    if (!(u.norm() > 1e-9)) return x;
    Vec3 b = a + step * u.normalized();
    if (facing(b) >= 0.0) {  // grazed between a and b
      for (int i = 0; i < 8; ++i) {
        Vec3 m = 0.5 * (a + b);
        const bool faces = facing(m) < 0.0;
        (faces ? a : b) = m;
      }
      return a;
    }
    a = b;
  }
  return x;
}

}  // namespace inhand
