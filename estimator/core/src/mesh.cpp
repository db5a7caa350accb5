#include "inhand/core/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "inhand/core/error.hpp"

namespace inhand {

Aabb TriangleMesh::Bounds() const {
  Aabb box;
  for (const Vec3& v : vertices) box.Extend(v);
  return box;
}

void TriangleMesh::Apply(const Transform& T) {
  for (Vec3& v : vertices) v = T * v;
  for (Vec3& n : normals) n = T.linear() * n;
}

void TriangleMesh::ScaleBy(const Vec3& scale) {
  for (Vec3& v : vertices) v = v.cwiseProduct(scale);
  // Normals transform with the inverse transpose; a negative determinant flips winding.
  const Vec3 inv = scale.cwiseInverse();
  for (Vec3& n : normals) {
    n = n.cwiseProduct(inv);
    const double len = n.norm();
    if (len > 0.0) n /= len;
  }
  if (scale.prod() < 0.0)
    for (auto& t : triangles) std::swap(t[1], t[2]);
}

void TriangleMesh::ComputeNormals() {
  normals.assign(vertices.size(), Vec3::Zero());
  for (const auto& t : triangles) {
    const Vec3 n = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (Vec3& n : normals) {
    const double len = n.norm();
    n = len > 0.0 ? Vec3(n / len) : Vec3::UnitZ();
  }
}

void TriangleMesh::Validate(const std::string& context) const {
  if (!normals.empty() && normals.size() != vertices.size())
    throw InputError(context + ": " + std::to_string(normals.size()) + " normals for " +
                     std::to_string(vertices.size()) + " vertices");
  if (!uvs.empty() && uvs.size() != vertices.size())
    throw InputError(context + ": " + std::to_string(uvs.size()) + " texture coordinates for " +
                     std::to_string(vertices.size()) + " vertices");
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite())
      throw InputError(context + ": vertex " + std::to_string(i) + " is not finite");
  const int n = static_cast<int>(vertices.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (triangles[i][k] < 0 || triangles[i][k] >= n)
        throw InputError(context + ": triangle " + std::to_string(i) + " refers to vertex " +
                         std::to_string(triangles[i][k]) + " of " + std::to_string(n));
}

MassProperties ComputeMassProperties(const std::vector<const TriangleMesh*>& meshes) {
  double volume = 0.0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();  // ∫ x xᵀ dV
  for (const TriangleMesh* mesh : meshes) {
    for (const auto& t : mesh->triangles) {
      const Vec3& a = mesh->vertices[t[0]];
      const Vec3& b = mesh->vertices[t[1]];
      const Vec3& c = mesh->vertices[t[2]];
      const double v = a.dot(b.cross(c)) / 6.0;  // signed tetrahedron (0, a, b, c)
      const Vec3 s = a + b + c;
      volume += v;
      first += v * s / 4.0;
      second += v / 20.0 *
                (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
    }
  }
  MassProperties mp;
  mp.volume = volume;
  if (std::abs(volume) < 1e-18) return mp;
  mp.com = first / volume;
  const Mat3 second_com = second - volume * mp.com * mp.com.transpose();
  mp.inertia_com = second_com.trace() * Mat3::Identity() - second_com;
  return mp;
}

namespace {

// Welds vertices by position on a grid of size `tol`; returns the welded id of each vertex.
std::vector<int> WeldVertices(const std::vector<Vec3>& vertices, double tol) {
  struct KeyHash {
    std::size_t operator()(const std::array<long long, 3>& k) const {
      return std::hash<long long>()(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<long long, 3>, int, KeyHash> ids;
  std::vector<int> out(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const std::array<long long, 3> key{std::llround(vertices[i].x() / tol),
                                       std::llround(vertices[i].y() / tol),
                                       std::llround(vertices[i].z() / tol)};
    auto [it, inserted] = ids.emplace(key, static_cast<int>(ids.size()));
    out[i] = it->second;
  }
  return out;
}

int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

bool IsClosed(const TriangleMesh& mesh, double weld_tolerance) {
  if (mesh.triangles.empty()) return false;
  const std::vector<int> id = WeldVertices(mesh.vertices, weld_tolerance);
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = id[t[k]], b = id[t[(k + 1) % 3]];
      if (a == b) return false;  // degenerate triangle
      ++directed[{a, b}];
    }
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    auto it = directed.find({edge.second, edge.first});
    if (it == directed.end() || it->second != 1) return false;
  }
  return true;
}

bool IsWatertightForParity(const std::vector<const TriangleMesh*>& meshes, double weld_tolerance) {
  std::vector<Vec3> vertices;
  for (const TriangleMesh* m : meshes)
    vertices.insert(vertices.end(), m->vertices.begin(), m->vertices.end());
  const std::vector<int> id = WeldVertices(vertices, weld_tolerance);
  std::map<std::pair<int, int>, std::array<int, 2>>
      edges;  // (min, max) -> uses (forward, backward)
  std::size_t base = 0;
  bool any = false;
  for (const TriangleMesh* m : meshes) {
    for (const auto& t : m->triangles) {
      any = true;
      for (int k = 0; k < 3; ++k) {
        const int a = id[base + t[k]], b = id[base + t[(k + 1) % 3]];
        if (a == b) continue;
        ++edges[{std::min(a, b), std::max(a, b)}][a < b ? 0 : 1];
      }
    }
    base += m->vertices.size();
  }
  if (!any) return false;
  for (const auto& [edge, uses] : edges)
    if (uses[0] != uses[1]) return false;
  return true;
}

std::vector<TriangleMesh> ConnectedComponents(const TriangleMesh& mesh, double weld_tolerance) {
  const std::vector<int> id = WeldVertices(mesh.vertices, weld_tolerance);
  // Triangles join across manifold edges only (edges with exactly two triangles): convex hulls
  // stored in one file that touch at a vertex or share an edge stay apart.
  const int num_tris = static_cast<int>(mesh.triangles.size());
  std::map<std::pair<int, int>, std::vector<int>> edge_tris;
  for (int t = 0; t < num_tris; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = id[mesh.triangles[t][k]], b = id[mesh.triangles[t][(k + 1) % 3]];
      edge_tris[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  std::vector<int> parent(num_tris);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [edge, tris] : edge_tris)
    if (tris.size() == 2) parent[FindRoot(parent, tris[1])] = FindRoot(parent, tris[0]);
  std::vector<TriangleMesh> out;
  std::vector<std::vector<int>> remap;
  std::map<int, int> component_of_root;  // first triangle order: deterministic
  for (int ti = 0; ti < num_tris; ++ti) {
    const Eigen::Vector3i& t = mesh.triangles[ti];
    const int root = FindRoot(parent, ti);
    auto [it, inserted] = component_of_root.emplace(root, static_cast<int>(out.size()));
    if (inserted) {
      out.emplace_back();
      out.back().material = mesh.material;
      remap.emplace_back(mesh.vertices.size(), -1);
    }
    TriangleMesh& part = out[it->second];
    std::vector<int>& map = remap[it->second];
    Eigen::Vector3i nt;
    for (int k = 0; k < 3; ++k) {
      int& m = map[t[k]];
      if (m < 0) {
        m = static_cast<int>(part.vertices.size());
        part.vertices.push_back(mesh.vertices[t[k]]);
        if (!mesh.normals.empty()) part.normals.push_back(mesh.normals[t[k]]);
        if (!mesh.uvs.empty()) part.uvs.push_back(mesh.uvs[t[k]]);
      }
      nt[k] = m;
    }
    part.triangles.push_back(nt);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Convex pieces

namespace {

constexpr int kSegments = 24;  // tessellation of round primitives (drawing and bounds only)

// Appends a ring of kSegments vertices at height z with radius r (shape frame).
void AppendRing(std::vector<Vec3>& v, double r, double z) {
  for (int i = 0; i < kSegments; ++i) {
    const double a = 2.0 * M_PI * i / kSegments;
    v.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
}

// Triangulates stacked rings (ring 0 at the bottom) plus optional bottom/top pole vertices.
void StitchRings(int num_rings, int bottom_pole, int top_pole, std::vector<Eigen::Vector3i>& tris) {
  for (int r = 0; r + 1 < num_rings; ++r) {
    for (int i = 0; i < kSegments; ++i) {
      const int j = (i + 1) % kSegments;
      const int a = r * kSegments + i, b = r * kSegments + j;
      const int c = (r + 1) * kSegments + i, d = (r + 1) * kSegments + j;
      tris.emplace_back(a, b, d);
      tris.emplace_back(a, d, c);
    }
  }
  for (int i = 0; i < kSegments; ++i) {
    const int j = (i + 1) % kSegments;
    if (bottom_pole >= 0) tris.emplace_back(bottom_pole, j, i);
    if (top_pole >= 0) {
      const int base = (num_rings - 1) * kSegments;
      tris.emplace_back(top_pole, base + i, base + j);
    }
  }
}

// Rings of a sphere-swept segment: hemisphere caps at ±half_length.
void RoundShape(double radius, double half_length, std::vector<Vec3>& v,
                std::vector<Eigen::Vector3i>& tris) {
  constexpr int kCapRings = 6;
  int rings = 0;
  for (int k = 1; k <= kCapRings; ++k) {  // bottom cap, from the pole upwards
    const double phi = -M_PI / 2 + M_PI / 2 * k / kCapRings;
    AppendRing(v, radius * std::cos(phi), -half_length + radius * std::sin(phi));
    ++rings;
  }
  // A sphere (half_length 0) shares the equator ring between both caps.
  for (int k = half_length > 0.0 ? 0 : 1; k < kCapRings; ++k) {  // top cap, upwards
    const double phi = M_PI / 2 * k / kCapRings;
    AppendRing(v, radius * std::cos(phi), half_length + radius * std::sin(phi));
    ++rings;
  }
  const int bottom = static_cast<int>(v.size());
  v.emplace_back(0.0, 0.0, -half_length - radius);
  const int top = static_cast<int>(v.size());
  v.emplace_back(0.0, 0.0, half_length + radius);
  StitchRings(rings, bottom, top, tris);
}

}  // namespace

TriangleMesh MergedGeometry(const std::vector<TriangleMesh>& meshes) {
  TriangleMesh merged;
  for (const TriangleMesh& m : meshes) {
    const int base = static_cast<int>(merged.vertices.size());
    merged.vertices.insert(merged.vertices.end(), m.vertices.begin(), m.vertices.end());
    for (const auto& t : m.triangles) merged.triangles.emplace_back(t.array() + base);
  }
  return merged;
}

TriangleMesh SimplifyMesh(const TriangleMesh& mesh, std::size_t target_triangles,
                          double max_error) {
  mesh.Validate("SimplifyMesh");
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  std::vector<Eigen::Vector3i> tris = mesh.triangles;
  std::vector<bool> tri_alive(nt, true), vert_alive(nv, true), locked(nv, false);
  std::vector<std::vector<int>> incident(nv);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      incident[static_cast<std::size_t>(tris[t][k])].push_back(static_cast<int>(t));
  std::map<std::pair<int, int>, int> edge_uses;
  for (const Eigen::Vector3i& t : tris)
    for (int k = 0; k < 3; ++k) ++edge_uses[std::minmax(t[k], t[(k + 1) % 3])];
  for (const auto& [e, uses] : edge_uses)
    if (uses != 2)
      locked[static_cast<std::size_t>(e.first)] = locked[static_cast<std::size_t>(e.second)] = true;
  // Plane quadrics, one per triangle, summed at its vertices.
  std::vector<Eigen::Matrix4d> Q(nv, Eigen::Matrix4d::Zero());
  const auto normal_of = [&](const Eigen::Vector3i& t) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    return Vec3((mesh.vertices[static_cast<std::size_t>(t[1])] - a)
                    .cross(mesh.vertices[static_cast<std::size_t>(t[2])] - a));
  };
  for (const Eigen::Vector3i& t : tris) {
    const Vec3 n = normal_of(t);
    if (!(n.norm() > 0.0)) continue;
    Eigen::Vector4d plane;
    plane << n.normalized(), -n.normalized().dot(mesh.vertices[static_cast<std::size_t>(t[0])]);
    for (int k = 0; k < 3; ++k) Q[static_cast<std::size_t>(t[k])] += plane * plane.transpose();
  }
  const auto neighbours = [&](int v) {
    std::set<int> out;
    for (int t : incident[static_cast<std::size_t>(v)])
      if (tri_alive[static_cast<std::size_t>(t)])
        for (int k = 0; k < 3; ++k)
          if (tris[static_cast<std::size_t>(t)][k] != v)
            out.insert(tris[static_cast<std::size_t>(t)][k]);
    return out;
  };
  struct Candidate {
    double cost;
    int u, v;  // u collapses onto v
    unsigned stamp_u, stamp_v;
    bool operator<(const Candidate& o) const {  // min-heap; ties by index (deterministic)
      if (cost != o.cost) return cost > o.cost;
      return std::tie(u, v) > std::tie(o.u, o.v);
    }
  };
  std::vector<unsigned> stamp(nv, 0);
  std::priority_queue<Candidate> heap;
  const auto push = [&](int u, int v) {
    if (locked[static_cast<std::size_t>(u)]) return;
    Eigen::Vector4d x;
    x << mesh.vertices[static_cast<std::size_t>(v)], 1.0;
    const double cost =
        x.dot((Q[static_cast<std::size_t>(u)] + Q[static_cast<std::size_t>(v)]) * x);
    heap.push({std::max(cost, 0.0), u, v, stamp[static_cast<std::size_t>(u)],
               stamp[static_cast<std::size_t>(v)]});
  };
  for (const auto& [e, uses] : edge_uses) push(e.first, e.second), push(e.second, e.first);
  std::size_t alive = nt;
  const double limit = max_error * max_error;
  while (alive > target_triangles && !heap.empty()) {
    const Candidate c = heap.top();
    heap.pop();
    const std::size_t u = static_cast<std::size_t>(c.u), v = static_cast<std::size_t>(c.v);
    if (!vert_alive[u] || !vert_alive[v] || stamp[u] != c.stamp_u || stamp[v] != c.stamp_v)
      continue;  // stale
    if (c.cost > limit) break;
    // Link condition: the two vertices share exactly the neighbours across their edge.
    const std::set<int> nu = neighbours(c.u), nvs = neighbours(c.v);
    int shared = 0, across = 0;
    for (int w : nu) shared += nvs.count(w) ? 1 : 0;
    for (int t : incident[u])
      if (tri_alive[static_cast<std::size_t>(t)] &&
          (tris[static_cast<std::size_t>(t)].array() == c.v).any())
        ++across;
    if (across != 2 || shared != 2) continue;
    // No triangle may flip or flatten.
    bool ok = true;
    for (int t : incident[u]) {
      const Eigen::Vector3i& tri = tris[static_cast<std::size_t>(t)];
      if (!tri_alive[static_cast<std::size_t>(t)] || (tri.array() == c.v).any()) continue;
      Eigen::Vector3i moved = tri;
      for (int k = 0; k < 3; ++k)
        if (moved[k] == c.u) moved[k] = c.v;
      const Vec3 before = normal_of(tri), after = normal_of(moved);
      if (!(after.norm() > 1e-3 * before.norm()) ||
          after.normalized().dot(before.normalized()) < 0.2)
        ok = false;
    }
    if (!ok) continue;
    for (int t : incident[u]) {
      Eigen::Vector3i& tri = tris[static_cast<std::size_t>(t)];
      if (!tri_alive[static_cast<std::size_t>(t)]) continue;
      if ((tri.array() == c.v).any()) {
        tri_alive[static_cast<std::size_t>(t)] = false;
        --alive;
        continue;
      }
      for (int k = 0; k < 3; ++k)
        if (tri[k] == c.u) tri[k] = c.v;
      incident[v].push_back(t);
    }
    vert_alive[u] = false;
    Q[v] += Q[u];
    const std::set<int> around = neighbours(c.v);
    ++stamp[v];
    for (int w : around) ++stamp[static_cast<std::size_t>(w)];
    // Every candidate that names a vertex whose stamp changed is stale: push its edges again.
    for (int w : around)
      for (int x : neighbours(w)) push(w, x), push(x, w);
  }
  TriangleMesh out;
  out.material = mesh.material;
  std::vector<int> index(nv, -1);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!tri_alive[t]) continue;
    Eigen::Vector3i tri;
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = static_cast<std::size_t>(tris[t][k]);
      if (index[i] < 0) {
        index[i] = static_cast<int>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[i]);
        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[i]);
        if (!mesh.uvs.empty()) out.uvs.push_back(mesh.uvs[i]);
      }
      tri[k] = index[i];
    }
    out.triangles.push_back(tri);
  }
  return out;
}

ConvexPiece ConvexPiece::Box(const Vec3& h, const Transform& T_BS) {
  ConvexPiece p;
  p.kind = Kind::kBox;
  p.T_BS = T_BS;
  p.half_extents = h;
  for (int i = 0; i < 8; ++i)
    p.hull_vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(),
                                 (i & 4) ? h.z() : -h.z());
  // Faces as quads (outward), split into two triangles each.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    p.hull_triangles.emplace_back(q[0], q[1], q[2]);
    p.hull_triangles.emplace_back(q[0], q[2], q[3]);
  }
  for (Vec3& v : p.hull_vertices) v = T_BS * v;
  p.UpdateBounds();
  return p;
}

ConvexPiece ConvexPiece::Sphere(double radius, const Transform& T_BS) {
  ConvexPiece p = Capsule(radius, 0.0, T_BS);
  p.kind = Kind::kSphere;
  return p;
}

ConvexPiece ConvexPiece::Capsule(double radius, double half_length, const Transform& T_BS) {
  ConvexPiece p;
  p.kind = Kind::kCapsule;
  p.T_BS = T_BS;
  p.radius = radius;
  p.half_length = half_length;
  RoundShape(radius, half_length, p.hull_vertices, p.hull_triangles);
  for (Vec3& v : p.hull_vertices) v = T_BS * v;
  p.UpdateBounds();
  return p;
}

ConvexPiece ConvexPiece::Cylinder(double radius, double half_length, const Transform& T_BS) {
  ConvexPiece p;
  p.kind = Kind::kCylinder;
  p.T_BS = T_BS;
  p.radius = radius;
  p.half_length = half_length;
  AppendRing(p.hull_vertices, radius, -half_length);
  AppendRing(p.hull_vertices, radius, half_length);
  const int bottom = static_cast<int>(p.hull_vertices.size());
  p.hull_vertices.emplace_back(0.0, 0.0, -half_length);
  const int top = static_cast<int>(p.hull_vertices.size());
  p.hull_vertices.emplace_back(0.0, 0.0, half_length);
  StitchRings(2, bottom, top, p.hull_triangles);
  for (Vec3& v : p.hull_vertices) v = T_BS * v;
  p.UpdateBounds();
  return p;
}

ConvexPiece ConvexPiece::Hull(std::vector<Vec3> vertices, std::vector<Eigen::Vector3i> triangles) {
  ConvexPiece p;
  p.kind = Kind::kHull;
  p.hull_vertices = std::move(vertices);
  p.hull_triangles = std::move(triangles);
  p.UpdateBounds();
  return p;
}

Vec3 ConvexPiece::Support(const Vec3& dir_B) const {
  const Vec3 d = T_BS.linear().transpose() * dir_B;  // in the shape frame
  Vec3 s;
  switch (kind) {
    case Kind::kBox:
      s = Vec3(d.x() >= 0 ? half_extents.x() : -half_extents.x(),
               d.y() >= 0 ? half_extents.y() : -half_extents.y(),
               d.z() >= 0 ? half_extents.z() : -half_extents.z());
      return T_BS * s;
    case Kind::kSphere:
    case Kind::kCapsule: {
      const double n = d.norm();
      s = Vec3(0.0, 0.0, d.z() >= 0 ? half_length : -half_length);
      if (n > 0.0) s += radius * d / n;
      return T_BS * s;
    }
    case Kind::kCylinder: {
      const double r = std::hypot(d.x(), d.y());
      s = Vec3(0.0, 0.0, d.z() >= 0 ? half_length : -half_length);
      if (r > 0.0) s.head<2>() += radius * d.head<2>() / r;
      return T_BS * s;
    }
    case Kind::kHull:
      break;
  }
  double best = -std::numeric_limits<double>::infinity();
  Vec3 arg = Vec3::Zero();
  for (const Vec3& v : hull_vertices) {
    const double dot = v.dot(dir_B);
    if (dot > best) {
      best = dot;
      arg = v;
    }
  }
  return arg;
}

TriangleMesh ConvexPiece::ToMesh() const {
  TriangleMesh m;
  m.vertices = hull_vertices;
  m.triangles = hull_triangles;
  m.ComputeNormals();
  return m;
}

void ConvexPiece::Apply(const Transform& T) {
  T_BS = T * T_BS;
  for (Vec3& v : hull_vertices) v = T * v;
  UpdateBounds();
}

void ConvexPiece::UpdateBounds() {
  Aabb box;
  for (const Vec3& v : hull_vertices) box.Extend(v);
  bounding_center = box.Center();
  bounding_radius = 0.0;
  for (const Vec3& v : hull_vertices)
    bounding_radius = std::max(bounding_radius, (v - bounding_center).norm());
  if (kind != Kind::kHull && kind != Kind::kBox) {
    // Tessellated round shapes lie inside the true surface: grow to the exact bound.
    bounding_center = T_BS.translation();
    bounding_radius = radius + half_length;
    if (kind == Kind::kCylinder) bounding_radius = std::hypot(radius, half_length);
  }
}

const char* ConvexPiece::KindName(Kind kind) {
  switch (kind) {
    case Kind::kBox:
      return "box";
    case Kind::kSphere:
      return "sphere";
    case Kind::kCylinder:
      return "cylinder";
    case Kind::kCapsule:
      return "capsule";
    case Kind::kHull:
      return "hull";
  }
  return "?";
}

}  // namespace inhand
