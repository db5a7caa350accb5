#include <gtest/gtest.h>

#include <iostream>
#include <map>
#include <set>
#include <tuple>

#include "inhand/core/error.hpp"
#include "inhand/core/mesh.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

Vec3 RandomDir() {
  std::normal_distribution<double> n(0.0, 1.0);
  auto& rng = test::Rng();
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

Transform SomePose() { return MakeTransform(Vec3(0.1, -0.2, 0.3), ExpSO3(Vec3(0.4, -0.3, 1.1))); }

TEST(Mesh, BoxMassPropertiesAreAnalytic) {
  const Vec3 h(0.03, 0.05, 0.11);
  const TriangleMesh box = ConvexPiece::Box(h, SomePose()).ToMesh();
  ASSERT_TRUE(IsClosed(box));
  const MassProperties mp = ComputeMassProperties({&box});
  const double V = 8 * h.prod();
  EXPECT_NEAR(mp.volume, V, 1e-15);
  EXPECT_LT((mp.com - SomePose().translation()).norm(), 1e-14);
  // Inertia in the box frame per unit density: V/3 (b² + c²) with half extents.
  const Mat3 R = SomePose().linear();
  const Mat3 I_box = R.transpose() * mp.inertia_com * R;
  EXPECT_NEAR(I_box(0, 0), V / 3 * (h.y() * h.y() + h.z() * h.z()), 1e-15);
  EXPECT_NEAR(I_box(1, 1), V / 3 * (h.x() * h.x() + h.z() * h.z()), 1e-15);
  EXPECT_NEAR(I_box(2, 2), V / 3 * (h.x() * h.x() + h.y() * h.y()), 1e-15);
  EXPECT_NEAR(I_box(0, 1), 0.0, 1e-16);
}

TEST(Mesh, RoundPrimitivesAreClosedAndCloseToAnalyticVolume) {
  const double r = 0.02, hl = 0.05;
  const TriangleMesh cyl = ConvexPiece::Cylinder(r, hl, SomePose()).ToMesh();
  const TriangleMesh cap = ConvexPiece::Capsule(r, hl, SomePose()).ToMesh();
  const TriangleMesh sph = ConvexPiece::Sphere(r, SomePose()).ToMesh();
  for (const TriangleMesh* m : {&cyl, &cap, &sph}) EXPECT_TRUE(IsClosed(*m));
  // 24-gon tessellation: inscribed, a little below the true volume.
  const double v_cyl = M_PI * r * r * 2 * hl;
  const double v_sph = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(ComputeMassProperties({&cyl}).volume / v_cyl, 1.0, 0.02);
  EXPECT_NEAR(ComputeMassProperties({&sph}).volume / v_sph, 1.0, 0.05);
  EXPECT_NEAR(ComputeMassProperties({&cap}).volume / (v_cyl + v_sph), 1.0, 0.04);
}

TEST(Mesh, OpenMeshIsNotClosed) {
  TriangleMesh box = ConvexPiece::Box(Vec3(1, 1, 1), Transform::Identity()).ToMesh();
  box.triangles.pop_back();
  EXPECT_FALSE(IsClosed(box));
  TriangleMesh flipped = ConvexPiece::Box(Vec3(1, 1, 1), Transform::Identity()).ToMesh();
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);  // inconsistent winding
  EXPECT_FALSE(IsClosed(flipped));
}

TEST(Mesh, ConnectedComponentsSeparateDisjointParts) {
  TriangleMesh a = ConvexPiece::Box(Vec3(1, 1, 1), Transform::Identity()).ToMesh();
  const TriangleMesh b =
      ConvexPiece::Box(Vec3(1, 1, 1), MakeTransform(Vec3(5, 0, 0), Mat3::Identity())).ToMesh();
  const int base = static_cast<int>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  for (const auto& t : b.triangles) a.triangles.emplace_back(t.array() + base);
  const auto parts = ConnectedComponents(a);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].num_triangles(), 12u);
  EXPECT_NEAR(parts[1].Bounds().Center().x(), 5.0, 1e-12);
}

TEST(Mesh, SupportOfPrimitivesIsAnalytic) {
  const Transform T = SomePose();
  const double r = 0.015, hl = 0.04;
  const Vec3 h(0.01, 0.02, 0.03);
  const ConvexPiece box = ConvexPiece::Box(h, T);
  const ConvexPiece cap = ConvexPiece::Capsule(r, hl, T);
  const ConvexPiece cyl = ConvexPiece::Cylinder(r, hl, T);
  const ConvexPiece sph = ConvexPiece::Sphere(r, T);
  const Vec3 a = T * Vec3(0, 0, -hl), b = T * Vec3(0, 0, hl), axis = T.linear().col(2);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = RandomDir();
    // Box: the support value equals the maximum over its 8 corners.
    double best = -1e9;
    for (const Vec3& v : box.hull_vertices) best = std::max(best, v.dot(d));
    EXPECT_NEAR(box.Support(d).dot(d), best, 1e-14);
    // Capsule: max over the segment end points, plus r.
    EXPECT_NEAR(cap.Support(d).dot(d), std::max(a.dot(d), b.dot(d)) + r, 1e-14);
    EXPECT_NEAR(sph.Support(d).dot(d), T.translation().dot(d) + r, 1e-14);
    // Cylinder: end point plus r times the radial part of d.
    const double radial = (d - d.dot(axis) * axis).norm();
    EXPECT_NEAR(cyl.Support(d).dot(d), std::max(a.dot(d), b.dot(d)) + r * radial, 1e-14);
    // The tessellated hull lies inside the exact shape.
    for (const ConvexPiece* p : {&cap, &cyl, &sph}) {
      double hull_best = -1e9;
      for (const Vec3& v : p->hull_vertices) hull_best = std::max(hull_best, v.dot(d));
      EXPECT_LE(hull_best, p->Support(d).dot(d) + 1e-12);
      // ...and the bounding sphere contains it.
      EXPECT_LE((p->Support(d) - p->bounding_center).norm(), p->bounding_radius + 1e-12);
    }
  }
}

TEST(Mesh, ValidateRejectsBadIndicesAndNonFiniteVertices) {
  TriangleMesh m = ConvexPiece::Box(Vec3(1, 1, 1), Transform::Identity()).ToMesh();
  m.triangles.emplace_back(0, 1, 99);
  EXPECT_THROW(m.Validate("m.obj"), InputError);
  TriangleMesh n = ConvexPiece::Box(Vec3(1, 1, 1), Transform::Identity()).ToMesh();
  n.vertices[2].x() = std::nan("");
  try {
    n.Validate("n.obj");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("n.obj: vertex 2"), std::string::npos);
  }
}

}  // namespace
}  // namespace inhand

namespace inhand {
namespace {

// A closed box whose faces are n x n grids, vertices shared by index across faces.
TriangleMesh GridBox(const Vec3& h, int n) {
  TriangleMesh m;
  std::map<std::tuple<long, long, long>, int> index;
  const auto vertex = [&](const Vec3& p) {
    const auto key = std::make_tuple(std::lround(p.x() * 1e9), std::lround(p.y() * 1e9),
                                     std::lround(p.z() * 1e9));
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    m.vertices.push_back(p);
    return index[key] = static_cast<int>(m.vertices.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (const double side : {-1.0, 1.0}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const auto at = [&](int i, int j) {
        Vec3 p;
        p[axis] = side * h[axis];
        p[u] = h[u] * (-1.0 + 2.0 * i / n);
        p[v] = h[v] * (-1.0 + 2.0 * j / n);
        return vertex(p);
      };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const int a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          // (u, v, axis) is right-handed: counter-clockwise from outside on the + side.
          if (side > 0)
            m.triangles.emplace_back(a, b, c), m.triangles.emplace_back(a, c, d);
          else
            m.triangles.emplace_back(a, c, b), m.triangles.emplace_back(a, d, c);
        }
    }
  return m;
}

// A UV sphere with a seam: the vertices at longitude 0 and 2π are separate (u = 0 and 1).
TriangleMesh UvSphere(double r, int stacks, int slices) {
  TriangleMesh m;
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const double th = M_PI * i / stacks, ph = 2 * M_PI * j / slices;
      m.vertices.emplace_back(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph),
                              r * std::cos(th));
      m.uvs.emplace_back(double(j) / slices, double(i) / stacks);
    }
  const auto id = [&](int i, int j) { return i * (slices + 1) + j; };
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      if (i > 0) m.triangles.emplace_back(id(i, j), id(i + 1, j), id(i, j + 1));
      if (i < stacks - 1) m.triangles.emplace_back(id(i, j + 1), id(i + 1, j), id(i + 1, j + 1));
    }
  return m;
}

TEST(SimplifyMesh, FlatFacesCollapseAndTheBoxStaysExact) {
  const Vec3 h(0.03, 0.05, 0.02);
  const TriangleMesh box = GridBox(h, 8);
  ASSERT_TRUE(IsClosed(box));
  ASSERT_EQ(box.num_triangles(), 6u * 8 * 8 * 2);
  const TriangleMesh s = SimplifyMesh(box, 0, 1e-9);
  EXPECT_TRUE(IsClosed(s));
  EXPECT_LE(s.num_triangles(), 48u) << "flat faces need few triangles";
  EXPECT_NEAR(ComputeMassProperties({&s}).volume, 8 * h.prod(), 1e-12 * 8 * h.prod());
  EXPECT_LT((s.Bounds().min - box.Bounds().min).norm() + (s.Bounds().max - box.Bounds().max).norm(),
            1e-12);
}

TEST(SimplifyMesh, KeepsSeamsAndStopsAtItsError) {
  const double r = 0.05;
  const TriangleMesh sphere = UvSphere(r, 24, 48);
  // Vertices on edges not shared by two triangles: the seam's two copies, the poles' copies (one
  // per slice) and the rings next to them.
  std::map<std::pair<int, int>, int> uses;
  for (const auto& t : sphere.triangles)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
  std::set<int> seam;
  for (const auto& [e, n] : uses)
    if (n != 2) seam.insert(e.first), seam.insert(e.second);
  ASSERT_GE(seam.size(), 2u * 23 + 2u * 49);

  // A curved surface: an error bound of 1 µm allows no collapse at all.
  EXPECT_EQ(SimplifyMesh(sphere, 0, 1e-6).num_triangles(), sphere.num_triangles());

  // One of 1 mm stops early: the quadric sums the squared distances of every merged plane.
  const std::size_t target = sphere.num_triangles() * 4 / 10;
  const TriangleMesh early = SimplifyMesh(sphere, target, 0.001);
  EXPECT_GT(early.num_triangles(), target);
  EXPECT_LT(early.num_triangles(), sphere.num_triangles());
  // One of 5 mm reaches the target.
  const TriangleMesh s = SimplifyMesh(sphere, target, 0.005);
  EXPECT_LE(s.num_triangles(), target + 2);
  EXPECT_GT(s.num_triangles(), 0u);
  // Every kept vertex is an original one with its uv; every seam vertex is kept.
  std::set<std::pair<long, long>> kept;
  for (std::size_t i = 0; i < s.vertices.size(); ++i) {
    bool found = false;
    for (std::size_t j = 0; j < sphere.vertices.size() && !found; ++j)
      if ((s.vertices[i] - sphere.vertices[j]).norm() == 0.0 &&
          (s.uvs[i] - sphere.uvs[j]).norm() == 0.0)
        found = true;
    EXPECT_TRUE(found) << "vertex " << i << " is not an original vertex with its uv";
  }
  for (int v : seam) {
    bool found = false;
    for (std::size_t i = 0; i < s.vertices.size() && !found; ++i)
      found = (s.vertices[i] - sphere.vertices[static_cast<std::size_t>(v)]).norm() == 0.0 &&
              (s.uvs[i] - sphere.uvs[static_cast<std::size_t>(v)]).norm() == 0.0;
    EXPECT_TRUE(found) << "seam vertex " << v << " was removed";
  }
  // The surface stays near the sphere: triangle centres within the error bound of it.
  double worst = 0.0;
  for (const auto& t : s.triangles) {
    const Vec3 c =
        (s.vertices[static_cast<std::size_t>(t[0])] + s.vertices[static_cast<std::size_t>(t[1])] +
         s.vertices[static_cast<std::size_t>(t[2])]) /
        3.0;
    worst = std::max(worst, r - c.norm());
  }
  EXPECT_LT(worst, 0.005);
  std::cout << "  sphere " << sphere.num_triangles() << " -> " << early.num_triangles()
            << " (1 mm) and " << s.num_triangles() << " triangles (5 mm), deepest centre "
            << worst * 1000 << " mm inside\n";
}

}  // namespace
}  // namespace inhand
