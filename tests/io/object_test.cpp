#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "inhand/core/error.hpp"
#include "inhand/io/object_loader.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

struct Expected {
  std::string file;
  std::size_t pieces;
  std::size_t tags;
  double mass;
  double length;  // largest extent [m]
};

TEST(Objects, ProjectObjectsLoadWithPiecesMassAndTags) {
  const std::vector<Expected> objects = {{"ketchup_bottle", 3, 2, 0.62, 0.204},
                                         {"brush", 3, 1, 0.14, 0.214},
                                         {"water_bottle", 3, 2, 0.53, 0.232},
                                         {"shampoo_bottle", 6, 2, 0.30, 0.218},
                                         {"pen", 2, 0, 0.016, 0.145}};
  for (const Expected& e : objects) {
    const ObjectModel o = LoadObjectModel(test::ProjectAsset("objects/" + e.file + "/object.json"));
    EXPECT_EQ(o.name, e.file);
    EXPECT_EQ(o.pieces.size(), e.pieces) << e.file;
    EXPECT_EQ(o.tags.size(), e.tags) << e.file;
    EXPECT_DOUBLE_EQ(o.mass, e.mass);
    EXPECT_NEAR(o.Bounds().Size().maxCoeff(), e.length, 1e-3) << e.file;
    // Inertia: symmetric positive definite, obeying the triangle inequality of principal moments.
    Eigen::SelfAdjointEigenSolver<Mat3> eig(o.inertia_com);
    const Vec3 I = eig.eigenvalues();
    EXPECT_GT(I.minCoeff(), 0.0) << e.file;
    EXPECT_LE(I[2], I[0] + I[1] + 1e-12) << e.file;
    // Centre of mass inside the bounding box.
    const Aabb box = o.Bounds();
    EXPECT_TRUE((o.com_O.array() >= box.min.array()).all() &&
                (o.com_O.array() <= box.max.array()).all())
        << e.file;
    for (const TriangleMesh& m : o.visual)
      EXPECT_TRUE(IsClosed(m, 1e-7)) << e.file << " " << m.material.name;
  }
}

TEST(Objects, TagCornersFollowTheDetectorOrder) {
  const ObjectModel o = LoadObjectModel(test::ProjectAsset("objects/ketchup_bottle/object.json"));
  // Tag 0 is on the face looking towards -y, upright: seen from -y, x is to the right, z up.
  const TagPlacement& tag = o.tags.at(0);
  EXPECT_EQ(tag.id, 0);
  const auto c = tag.CornersO();
  EXPECT_LT(c[0].x(), c[1].x());  // bottom-left left of bottom-right
  EXPECT_LT(c[0].z(), c[3].z());  // bottom below top
  EXPECT_NEAR((c[1] - c[0]).norm(), tag.size, 1e-12);
  EXPECT_NEAR((c[2] - c[0]).norm(), tag.size * std::sqrt(2.0), 1e-12);
  EXPECT_LT(tag.T_OT.linear().col(2).y(), -0.99);  // normal out of the face
  // The tag lies on the bottle's surface, within a millimetre.
  EXPECT_NEAR(c[0].y(), o.Bounds().min.y(), 1e-3);
}

TEST(Objects, BrushIsNonConvex) {
  const ObjectModel o = LoadObjectModel(test::ProjectAsset("objects/brush/object.json"));
  // The union of the pieces is clearly smaller than the hull of the whole: not one convex body.
  double pieces_volume = 0.0;
  std::vector<Vec3> all;
  for (const ConvexPiece& p : o.pieces) {
    const TriangleMesh m = p.ToMesh();
    pieces_volume += ComputeMassProperties({&m}).volume;
    all.insert(all.end(), p.hull_vertices.begin(), p.hull_vertices.end());
  }
  const Aabb box = [&] {
    Aabb b;
    for (const Vec3& v : all) b.Extend(v);
    return b;
  }();
  EXPECT_LT(pieces_volume, 0.5 * box.Size().prod());
}

TEST(Objects, BadDescriptionsNameFileAndField) {
  test::TempDir dir;
  dir.Write("cube.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const auto expect = [&](const std::string& json, const std::string& fragment) {
    dir.Write("o.json", json);
    try {
      LoadObjectModel(dir / "o.json");
      ADD_FAILURE() << "accepted: " << json;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect(
      "{\"name\": \"x\", \"visual\": [{\"mesh\": \"cube.obj\"}], \"collision\": [{\"mesh\": "
      "\"cube.obj\"}], "
      "\"mass\": -1}",
      "field 'mass'");
  expect(
      "{\"name\": \"x\", \"visual\": [{\"mesh\": \"gone.obj\"}], \"collision\": [], \"mass\": 1}",
      "gone.obj");
  expect("{\"name\": \"x\",\n \"visual\": [,]}", "o.json:2");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"mesh\": \"cube.obj\", \"method\": "
      "\"magic\"}], "
      "\"mass\": 1}",
      "'magic'");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"tags\": [{\"id\": 1, \"size\": 0.02}]}",
      "tags[0].pose");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"tags\": [{\"id\": 1, \"size\": 0.02, \"pose\": {\"quat_wxyz\": [2, 0, 0, 0]}}]}",
      "unit quaternion");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"inertia\": {\"ixx\": 1, \"iyy\": 1, \"izz\": 1, \"ixy\": 2}}",
      "field 'inertia' is not positive definite");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"symmetry\": {\"axis\": [0, 0, 0]}}",
      "field 'symmetry.axis'");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"symmetry\": {\"axis\": [1, 0, 0], \"centre\": [0, 0, 0]}}",
      "unknown key 'centre'");
  expect(
      "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
      "\"symmetry\": {\"axis\": [0, 0, 1]}, \"tags\": [{\"id\": 1, \"size\": 0.02, \"pose\": "
      "{\"xyz\": [0, 0, 0.5]}}]}",
      "no symmetry on an object with tags");
  EXPECT_THROW(LoadObjectModel(dir / "cube.obj"), InputError);  // not a description
}

// A declared continuous symmetry: the pen's own axis; an axis of any length, and its point.
TEST(Objects, ASymmetryIsItsUnitAxisThroughItsPoint) {
  const ObjectModel pen = LoadObjectModel(test::ProjectAsset("objects/pen/object.json"));
  EXPECT_EQ(pen.symmetry_axis_O, Vec3::UnitX());
  EXPECT_EQ(pen.symmetry_point_O, Vec3::Zero());
  for (const char* bottle : {"ketchup_bottle", "water_bottle", "shampoo_bottle", "brush"})
    EXPECT_TRUE(
        LoadObjectModel(test::ProjectAsset(std::string("objects/") + bottle + "/object.json"))
            .symmetry_axis_O.isZero())
        << bottle << " carries tags";
  test::TempDir dir;
  dir.Write("o.json",
            "{\"name\": \"x\", \"visual\": [], \"collision\": [{\"box\": [1, 1, 1]}], \"mass\": 1, "
            "\"symmetry\": {\"axis\": [0, 3, 4], \"point\": [0.1, 0, 0]}}");
  const ObjectModel o = LoadObjectModel(dir / "o.json");
  EXPECT_NEAR((o.symmetry_axis_O - Vec3(0, 0.6, 0.8)).norm(), 0.0, 1e-15);
  EXPECT_EQ(o.symmetry_point_O, Vec3(0.1, 0, 0));
}

TEST(Objects, YcbUrdfObjectsUseTheirStoredDecomposition) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string ycb = test::SharedAssets() + "/objects/ycb/";
  for (const char* name : {"mustard_bottle", "bleach_cleanser", "large_marker"}) {
    const ObjectModel o = LoadObjectModel(ycb + name + ".urdf");
    EXPECT_GT(o.pieces.size(), 1u) << name;  // textured_vhacd.stl holds several hulls
    EXPECT_GT(o.mass, 0.0);
    ASSERT_FALSE(o.visual.empty());
    // The .mtl's texture line ends in a space: trimmed and resolved.
    EXPECT_TRUE(o.visual[0].material.HasTexture()) << name;
    EXPECT_NE(o.visual[0].material.texture_file.find("texture_map.jpg"), std::string::npos);
    EXPECT_EQ(o.visual[0].uvs.size(), o.visual[0].vertices.size());
    // Pieces and the visual scan describe the same object (within a centimetre).
    Aabb pieces;
    for (const ConvexPiece& p : o.pieces)
      for (const Vec3& v : p.hull_vertices) pieces.Extend(v);
    EXPECT_LT((pieces.Center() - o.Bounds().Center()).norm(), 0.01) << name;
  }
}

}  // namespace
}  // namespace inhand
