#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "inhand/core/error.hpp"
#include "inhand/io/mesh_io.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

// Binary STL of a closed box [0,a]x[0,b]x[0,c] (outward winding).
std::string BinaryStlBox(double a, double b, double c) {
  const TriangleMesh box =
      ConvexPiece::Box(Vec3(a / 2, b / 2, c / 2),
                       MakeTransform(Vec3(a / 2, b / 2, c / 2), Mat3::Identity()))
          .ToMesh();
  std::string out(80, ' ');
  const auto put_u32 = [&out](std::uint32_t v) {
    out.append(reinterpret_cast<const char*>(&v), 4);
  };
  const auto put_f = [&out](float v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put_u32(static_cast<std::uint32_t>(box.triangles.size()));
  for (const auto& t : box.triangles) {
    const Vec3 n = (box.vertices[t[1]] - box.vertices[t[0]])
                       .cross(box.vertices[t[2]] - box.vertices[t[0]])
                       .normalized();
    for (int k = 0; k < 3; ++k) put_f(static_cast<float>(n[k]));
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) put_f(static_cast<float>(box.vertices[t[v]][k]));
    out.append(2, '\0');
  }
  return out;
}

TEST(MeshIo, BinaryStlWithScale) {
  test::TempDir dir;
  dir.Write("box.stl", BinaryStlBox(1.0, 2.0, 3.0));
  const auto meshes = LoadMeshFile(dir / "box.stl", Vec3(0.001, 0.001, 0.001));
  ASSERT_EQ(meshes.size(), 1u);
  EXPECT_LT((meshes[0].Bounds().Size() - Vec3(0.001, 0.002, 0.003)).norm(), 1e-9);
  EXPECT_EQ(meshes[0].num_triangles(), 12u);
  EXPECT_TRUE(IsClosed(meshes[0], 1e-9));
  EXPECT_NEAR(ComputeMassProperties({&meshes[0]}).volume, 6e-9, 1e-15);
  // Non-uniform and mirroring scales keep the solid's volume positive (winding flipped).
  const auto mirrored = LoadMeshFile(dir / "box.stl", Vec3(-1.0, 1.0, 1.0));
  EXPECT_NEAR(ComputeMassProperties({&mirrored[0]}).volume, 6.0, 1e-9);
}

TEST(MeshIo, ObjWithMaterialsTextureAndTrailingSpace) {
  test::TempDir dir;
  dir.Write("tex.png", "not really a png, the loader only checks that it exists");
  // The texture line ends with a space, like YCB's .mtl files.
  dir.Write("m.mtl",
            "newmtl red\nKd 1 0 0\nd 0.5\nnewmtl textured\nKd 0.8 0.8 0.8\nmap_Kd tex.png \n");
  dir.Write("m.obj",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
            "usemtl red\nf 1 3 2\nf 1 2 4\nusemtl textured\nf 1/1 4/4 3/3\nf 2/2 3/3 4/4\n");
  const auto meshes = LoadMeshFile(dir / "m.obj");
  ASSERT_EQ(meshes.size(), 2u);
  const TriangleMesh* red = meshes[0].material.name == "red" ? &meshes[0] : &meshes[1];
  const TriangleMesh* tex = red == &meshes[0] ? &meshes[1] : &meshes[0];
  EXPECT_NEAR(red->material.rgba[0], 1.0, 1e-6);
  EXPECT_NEAR(red->material.rgba[3], 0.5, 1e-6);
  EXPECT_FALSE(red->material.HasTexture());
  EXPECT_EQ(tex->material.texture_file,
            std::filesystem::weakly_canonical(dir / "tex.png").string());
  EXPECT_EQ(tex->uvs.size(), tex->vertices.size());

  dir.Write("missing.mtl", "newmtl t\nmap_Kd nowhere.png\n");
  dir.Write("missing.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl t\nf 1 2 3\n");
  try {
    LoadMeshFile(dir / "missing.obj");
    FAIL() << "missing texture accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere.png"), std::string::npos) << e.what();
  }
}

// What MeshesObjText writes, assimp reads back: positions, uvs, colours, opacity, texture.
TEST(MeshIo, WrittenObjReadsBackThroughAssimp) {
  test::TempDir dir;
  dir.Write("tex.png", "a texture file");
  TriangleMesh a =
      ConvexPiece::Box(Vec3(0.01, 0.02, 0.03), MakeTransform(Vec3(0.1, 0, 0), Mat3::Identity()))
          .ToMesh();
  a.uvs.clear();
  for (const Vec3& v : a.vertices)
    a.uvs.emplace_back(v.y() > 0 ? 1.0 : 0.0, v.z() > 0 ? 0.75 : 0.25);
  a.material.rgba = Eigen::Vector4d(0.9, 0.2, 0.1, 1.0);
  TriangleMesh b = ConvexPiece::Sphere(0.02, Transform::Identity()).ToMesh();
  b.material.rgba = Eigen::Vector4d(0.1, 0.3, 0.8, 0.5);
  const ObjText text = MeshesObjText({a, b}, "parts.mtl", {"tex.png", ""});
  dir.Write("parts.obj", text.obj);
  dir.Write("parts.mtl", text.mtl);
  const auto back = LoadMeshFile(dir / "parts.obj");
  ASSERT_EQ(back.size(), 2u);
  const TriangleMesh& ta = back[0].material.HasTexture() ? back[0] : back[1];
  const TriangleMesh& tb = &ta == &back[0] ? back[1] : back[0];
  EXPECT_EQ(ta.material.texture_file, std::filesystem::weakly_canonical(dir / "tex.png").string());
  EXPECT_EQ(ta.num_triangles(), a.num_triangles());
  EXPECT_EQ(tb.num_triangles(), b.num_triangles());
  EXPECT_LT((ta.material.rgba - a.material.rgba).norm(), 1e-6);
  EXPECT_LT((tb.material.rgba - b.material.rgba).norm(), 1e-6);
  // Every written vertex is read with its uv (assimp may flip v; ours are symmetric about 0.5).
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    bool found = false;
    for (std::size_t j = 0; j < ta.vertices.size() && !found; ++j)
      found = (ta.vertices[j] - a.vertices[i]).norm() < 1e-8 &&
              std::abs(ta.uvs[j].x() - a.uvs[i].x()) < 1e-8;
    EXPECT_TRUE(found) << "vertex " << i;
  }
  EXPECT_NEAR(ComputeMassProperties({&tb}).volume, ComputeMassProperties({&b}).volume, 1e-12);
}

// Slabs of a convex solid are exact pieces of it: a cylinder 100 mm long in 20 mm slabs is five
// hulls whose volumes add up to the cylinder's (0.03 % lost to the hull computer's rounding);
// at most max_slabs are cut.
TEST(MeshIo, SlabHullsCutASolidAcrossItsLongestAxis) {
  const TriangleMesh cyl =
      ConvexPiece::Cylinder(0.015, 0.05, MakeTransform(Vec3::Zero(), ExpSO3(Vec3(0, M_PI / 2, 0))))
          .ToMesh();
  const double v = ComputeMassProperties({&cyl}).volume;
  const std::vector<ConvexPiece> five = SlabHulls({cyl}, 0.02, 8, "cylinder");
  ASSERT_EQ(five.size(), 5u);
  double sum = 0.0;
  for (const ConvexPiece& p : five) {
    const TriangleMesh hull = p.ToMesh();
    sum += ComputeMassProperties({&hull}).volume;
    const Aabb box = hull.Bounds();
    EXPECT_NEAR(box.Size().x(), 0.02, 1e-9) << "cut across x, the longest axis";
  }
  EXPECT_NEAR(sum / v, 1.0, 1e-3);  // Bullet's hull computer rounds its vertices a little
  EXPECT_EQ(SlabHulls({cyl}, 0.005, 8, "cylinder").size(), 8u);
  // A flat mesh encloses nothing.
  TriangleMesh flat;
  flat.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  flat.triangles = {Eigen::Vector3i(0, 1, 2)};
  EXPECT_THROW(SlabHulls({flat}, 0.02, 8, "flat"), InputError);
}

TEST(MeshIo, ColladaUnitScaleAppliedAndUpAxisIgnored) {
  test::TempDir dir;
  // One triangle in millimetres, Z_UP: metres out, axes unchanged.
  dir.Write("tri.dae", R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="millimeter" meter="0.001"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 100 0 0 0 0 200</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)");
  const auto meshes = LoadMeshFile(dir / "tri.dae");
  ASSERT_EQ(meshes.size(), 1u);
  EXPECT_LT((meshes[0].Bounds().max - Vec3(0.1, 0.0, 0.2)).norm(), 1e-7);  // float file data
}

TEST(MeshIo, MissingUnreadableAndEmptyFiles) {
  test::TempDir dir;
  EXPECT_THROW(LoadMeshFile(dir / "none.stl"), InputError);
  dir.Write("garbage.stl", "this is not a mesh");
  EXPECT_THROW(LoadMeshFile(dir / "garbage.stl"), InputError);
  dir.Write("empty.obj", "# nothing\n");
  EXPECT_THROW(LoadMeshFile(dir / "empty.obj"), InputError);
}

TEST(MeshIo, ConvexHullOfACubeWithInteriorPoints) {
  std::vector<Vec3> points;
  for (int i = 0; i < 8; ++i) points.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  for (int i = 0; i < 100; ++i) points.emplace_back(u(test::Rng()), u(test::Rng()), u(test::Rng()));
  const ConvexPiece hull = ComputeConvexHull(points, "cube");
  EXPECT_EQ(hull.hull_vertices.size(), 8u);
  const TriangleMesh m = hull.ToMesh();
  EXPECT_TRUE(IsClosed(m));
  EXPECT_NEAR(ComputeMassProperties({&m}).volume, 1.0, 1e-12);  // positive: outward winding
  const std::vector<Vec3> flat = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  EXPECT_THROW(ComputeConvexHull(flat, "flat"), InputError);
  EXPECT_THROW(ComputeConvexHull({Vec3(0, 0, 0)}, "one"), InputError);
}

// A closed L-shaped solid built from 2 cm voxels (a grid-like surface, as scanned meshes are):
// a 4x4x2 block of voxels without its 2x2x2 corner. Volume 24 voxels.
TriangleMesh VoxelL() {
  const double h = 0.02;
  const auto occupied = [](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < 4 && j < 4 && k < 2 && !(i >= 2 && j >= 2);
  };
  TriangleMesh m;
  std::map<std::array<int, 3>, int> index;
  const auto vertex = [&](int x, int y, int z) {
    auto [it, inserted] = index.try_emplace({x, y, z}, static_cast<int>(m.vertices.size()));
    if (inserted) m.vertices.emplace_back(x * h, y * h, z * h);
    return it->second;
  };
  // Each exposed voxel face as two outward triangles; corners listed counter-clockwise.
  const auto quad = [&](std::array<std::array<int, 3>, 4> c) {
    const int a = vertex(c[0][0], c[0][1], c[0][2]), b = vertex(c[1][0], c[1][1], c[1][2]);
    const int d = vertex(c[2][0], c[2][1], c[2][2]), e = vertex(c[3][0], c[3][1], c[3][2]);
    m.triangles.emplace_back(a, b, d);
    m.triangles.emplace_back(a, d, e);
  };
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 2; ++k) {
        if (!occupied(i, j, k)) continue;
        if (!occupied(i + 1, j, k))
          quad({{{i + 1, j, k}, {i + 1, j + 1, k}, {i + 1, j + 1, k + 1}, {i + 1, j, k + 1}}});
        if (!occupied(i - 1, j, k))
          quad({{{i, j, k}, {i, j, k + 1}, {i, j + 1, k + 1}, {i, j + 1, k}}});
        if (!occupied(i, j + 1, k))
          quad({{{i, j + 1, k}, {i, j + 1, k + 1}, {i + 1, j + 1, k + 1}, {i + 1, j + 1, k}}});
        if (!occupied(i, j - 1, k))
          quad({{{i, j, k}, {i + 1, j, k}, {i + 1, j, k + 1}, {i, j, k + 1}}});
        if (!occupied(i, j, k + 1))
          quad({{{i, j, k + 1}, {i + 1, j, k + 1}, {i + 1, j + 1, k + 1}, {i, j + 1, k + 1}}});
        if (!occupied(i, j, k - 1))
          quad({{{i, j, k}, {i, j + 1, k}, {i + 1, j + 1, k}, {i + 1, j, k}}});
      }
  return m;
}

TEST(MeshIo, HacdSplitsANonConvexSolidAndCachesIt) {
  const TriangleMesh L = VoxelL();
  ASSERT_TRUE(IsClosed(L));
  const double volume_L = 24 * std::pow(0.02, 3);
  ASSERT_NEAR(ComputeMassProperties({&L}).volume, volume_L, 1e-12);
  test::TempDir cache;
  HacdParams params;
  params.cache_dir = cache.path();
  params.concavity = 0.001;
  const auto pieces = DecomposeHacd(L, params, "L");
  EXPECT_GE(pieces.size(), 2u);
  EXPECT_LE(pieces.size(), 4u);
  double volume = 0.0;
  for (const ConvexPiece& p : pieces) {
    const TriangleMesh m = p.ToMesh();
    volume += ComputeMassProperties({&m}).volume;
  }
  // The pieces cover the L without much more than its volume (the L's hull would be 7/6).
  EXPECT_NEAR(volume / volume_L, 1.0, 0.05);
  // The second call reads the cache: identical pieces, one cache file.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(cache.path()), {}), 1);
  const auto again = DecomposeHacd(L, params, "L");
  ASSERT_EQ(again.size(), pieces.size());
  for (std::size_t i = 0; i < pieces.size(); ++i)
    EXPECT_LT((again[i].bounding_center - pieces[i].bounding_center).norm(), 1e-12);
}

}  // namespace
}  // namespace inhand
