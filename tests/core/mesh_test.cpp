#include <gtest/gtest.h>

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
  const TriangleMesh b = ConvexPiece::Box(Vec3(1, 1, 1), MakeTransform(Vec3(5, 0, 0), Mat3::Identity())).ToMesh();
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
