#include <gtest/gtest.h>

#include "inhand/core/error.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

// An ASCII STL unit-ish tetrahedron, for files the tests write themselves.
constexpr const char* kTetraStl = R"(solid t
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 0 1 0
  vertex 1 0 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 0 1
 endloop
endfacet
facet normal -1 0 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 0 1 0
 endloop
endfacet
facet normal 1 1 1
 outer loop
  vertex 1 0 0
  vertex 0 1 0
  vertex 0 0 1
 endloop
endfacet
endsolid t
)";

std::string OneLinkUrdf(const std::string& geometry) {
  return "<robot name='r'><link name='palm'/><link name='f'><visual><geometry>" + geometry +
         "</geometry></visual></link><joint name='j' type='revolute'><parent link='palm'/>"
         "<child link='f'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='1' velocity='1'/>"
         "</joint></robot>";
}

// Expects InputError whose message contains every fragment.
template <typename F>
void ExpectInputError(F&& f, const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    for (const std::string& frag : fragments)
      EXPECT_NE(std::string(e.what()).find(frag), std::string::npos)
          << "message: " << e.what() << "\nmissing: " << frag;
  }
}

TEST(Urdf, MalformedXmlNamesTheLine) {
  ExpectInputError(
      [] { ParseHandModel("<robot name='r'>\n<link name='a'>\n</robot>", ".", "bad.urdf"); },
      {"bad.urdf:", "malformed XML"});
}

TEST(Urdf, RevoluteWithoutLimitNamesTheJointAndLine) {
  const std::string xml =
      "<robot name='r'>\n<link name='a'/><link name='b'/>\n<joint name='knee' type='revolute'>"
      "<parent link='a'/><child link='b'/></joint></robot>";
  ExpectInputError([&] { ParseHandModel(xml, ".", "r.urdf"); }, {"r.urdf:3", "knee", "<limit>"});
}

TEST(Urdf, UnsupportedJointTypeAndZeroAxis) {
  const std::string floating =
      "<robot name='r'><link name='a'/><link name='b'/><joint name='free' type='floating'>"
      "<parent link='a'/><child link='b'/></joint></robot>";
  ExpectInputError([&] { ParseHandModel(floating, ".", "r.urdf"); }, {"free", "floating"});
  const std::string zero_axis =
      "<robot name='r'><link name='a'/><link name='b'/><joint name='z' type='continuous'>"
      "<parent link='a'/><child link='b'/><axis xyz='0 0 0'/></joint></robot>";
  ExpectInputError([&] { ParseHandModel(zero_axis, ".", "r.urdf"); }, {"'z'", "no direction"});
}

TEST(Urdf, InvalidUrdfStructureCarriesUrdfdomsReason) {
  const std::string no_root = "<robot name='r'></robot>";
  ExpectInputError([&] { ParseHandModel(no_root, ".", "empty.urdf"); },
                   {"empty.urdf", "invalid URDF"});
  const std::string bad_parent =
      "<robot name='r'><link name='a'/><link name='b'/><joint name='j' type='fixed'>"
      "<parent link='nowhere'/><child link='b'/></joint></robot>";
  ExpectInputError([&] { ParseHandModel(bad_parent, ".", "p.urdf"); }, {"p.urdf", "invalid URDF"});
}

TEST(Urdf, MissingMeshAndUnknownPackage) {
  test::TempDir dir;
  ExpectInputError(
      [&] {
        ParseHandModel(OneLinkUrdf("<mesh filename='meshes/nope.stl'/>"), dir.path(), "h.urdf");
      },
      {"h.urdf", "meshes/nope.stl", "not found"});
  ExpectInputError(
      [&] {
        ParseHandModel(OneLinkUrdf("<mesh filename='package://ghost_pkg/m.stl'/>"), dir.path(),
                       "h.urdf");
      },
      {"unknown package 'ghost_pkg'", "--package ghost_pkg=DIR"});
  EXPECT_THROW(LoadHandModel(dir / "does_not_exist.urdf"), InputError);
}

TEST(Urdf, MeshPathsRelativeAbsoluteFileAndPackage) {
  test::TempDir dir;
  dir.Write("my_pkg/meshes/tetra.stl", kTetraStl);
  dir.Write("my_pkg/urdf/rel.urdf",
            OneLinkUrdf("<mesh filename='../meshes/tetra.stl' scale='2 2 2'/>"));
  dir.Write("my_pkg/urdf/abs.urdf",
            OneLinkUrdf("<mesh filename='" + (dir / "my_pkg/meshes/tetra.stl") + "'/>"));
  dir.Write("my_pkg/urdf/file.urdf",
            OneLinkUrdf("<mesh filename='file://" + (dir / "my_pkg/meshes/tetra.stl") + "'/>"));
  // Default package search: a parent folder named like the package.
  dir.Write("my_pkg/urdf/pkg.urdf",
            OneLinkUrdf("<mesh filename='package://my_pkg/meshes/tetra.stl'/>"));
  // Explicit map for a package whose folder has another name.
  dir.Write("elsewhere/meshes/tetra.stl", kTetraStl);
  dir.Write("my_pkg/urdf/mapped.urdf",
            OneLinkUrdf("<mesh filename='package://other/meshes/tetra.stl'/>"));

  for (const char* name : {"rel", "abs", "file", "pkg"}) {
    const HandModel h = LoadHandModel(dir / ("my_pkg/urdf/" + std::string(name) + ".urdf"));
    ASSERT_EQ(h.mesh_files.size(), 1u) << name;
    const Aabb box = h.links[h.LinkIndex("f")].visual.at(0).Bounds();
    EXPECT_NEAR(box.Size().x(), std::string(name) == "rel" ? 2.0 : 1.0, 1e-12) << name;
    // No collision element: the visual's hull stands in.
    EXPECT_TRUE(h.links[h.LinkIndex("f")].collision_from_visual);
  }
  EXPECT_THROW(LoadHandModel(dir / "my_pkg/urdf/mapped.urdf"), InputError);
  HandLoadOptions options;
  options.packages.AddSpec("other=" + (dir / "elsewhere"));
  const HandModel mapped = LoadHandModel(dir / "my_pkg/urdf/mapped.urdf", options);
  EXPECT_EQ(mapped.mesh_files.at(0), dir / "elsewhere/meshes/tetra.stl");
  EXPECT_THROW(options.packages.AddSpec("no_equals_sign"), InputError);
  EXPECT_THROW(options.packages.AddSpec("x=" + (dir / "not_a_dir")), InputError);
}

TEST(Urdf, GeometryFallbacksAndCapsuleMerge) {
  // Collision only → visual from collision; cylinder + end spheres → one capsule.
  const std::string xml =
      "<robot name='r'><link name='palm'><collision><geometry><box size='0.1 0.2 0.03'/></geometry>"
      "</collision></link><link name='f'>"
      "<collision><origin xyz='0 0 0.02'/><geometry><cylinder radius='0.01' "
      "length='0.04'/></geometry></collision>"
      "<collision><origin xyz='0 0 0'/><geometry><sphere radius='0.01'/></geometry></collision>"
      "<collision><origin xyz='0 0 0.04'/><geometry><sphere radius='0.01'/></geometry></collision>"
      "</link><joint name='j' type='revolute'><parent link='palm'/><child link='f'/>"
      "<axis xyz='1 0 0'/><limit lower='0' upper='1' effort='1' velocity='1'/></joint></robot>";
  const HandModel h = ParseHandModel(xml, ".", "r.urdf");
  const Link& palm = h.links[h.LinkIndex("palm")];
  EXPECT_TRUE(palm.visual_from_collision);
  EXPECT_NEAR(palm.visual.at(0).Bounds().Size().y(), 0.2, 1e-12);
  const Link& f = h.links[h.LinkIndex("f")];
  ASSERT_EQ(f.collision.size(), 1u);
  EXPECT_EQ(f.collision[0].kind, ConvexPiece::Kind::kCapsule);
  EXPECT_NEAR(f.collision[0].half_length, 0.02, 1e-15);
  EXPECT_NEAR(f.collision[0].T_BS.translation().z(), 0.02, 1e-15);
}

TEST(Urdf, MimicChainsCompose) {
  const std::string xml =
      "<robot name='r'><link name='a'/><link name='b'/><link name='c'/><link name='d'/>"
      "<joint name='j1' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
      "<joint name='j2' type='revolute'><parent link='b'/><child link='c'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='j1' multiplier='2' "
      "offset='0.1'/></joint>"
      "<joint name='j3' type='revolute'><parent link='c'/><child link='d'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='j2' multiplier='3' "
      "offset='0.2'/></joint>"
      "</robot>";
  const HandModel h = ParseHandModel(xml, ".", "m.urdf");
  ASSERT_EQ(h.num_q(), 1);
  const Joint& j3 = h.joints[h.JointIndex("j3")];
  EXPECT_EQ(j3.q_index, 0);
  EXPECT_NEAR(j3.multiplier, 6.0, 1e-15);        // 3 * 2
  EXPECT_NEAR(j3.offset, 3 * 0.1 + 0.2, 1e-15);  // 3 * (2 q + 0.1) + 0.2
  const std::string cycle =
      "<robot name='r'><link name='a'/><link name='b'/><link name='c'/>"
      "<joint name='j1' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='j2'/></joint>"
      "<joint name='j2' type='revolute'><parent link='b'/><child link='c'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='j1'/></joint></robot>";
  ExpectInputError([&] { ParseHandModel(cycle, ".", "c.urdf"); }, {"mimic cycle"});
}

TEST(Urdf, ProjectHand) {
  const HandModel h = LoadHandModel(test::ProjectAsset("hands/inhand_hand/inhand_hand.urdf"));
  EXPECT_EQ(h.num_q(), 16);
  EXPECT_EQ(h.links[h.root_link].name, "palm");
  // Every phalanx collides as one capsule (GJK-friendly).
  for (const char* f : {"index", "middle", "ring", "thumb"})
    for (const char* s : {"_proximal", "_middle", "_distal"}) {
      const Link& l = h.links[h.LinkIndex(std::string(f) + s)];
      ASSERT_EQ(l.collision.size(), 1u) << f << s;
      EXPECT_EQ(l.collision[0].kind, ConvexPiece::Kind::kCapsule) << f << s;
      EXPECT_FALSE(l.visual.empty());
    }
}

TEST(Urdf, SharedHandsJointCounts) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string hands = test::SharedAssets() + "/hands/";
  const std::vector<std::pair<std::string, int>> expected = {
      {"allegro_hand/allegro_hand_right.urdf", 16},
      {"allegro_hand/allegro_hand_left_glb.urdf", 16},
      {"allegro_hand_description/allegro_hand_description_left.urdf", 16},
      {"barrett_hand/bhand_model.urdf", 8},
      {"barrett_hand/bhand_model_glb.urdf", 8},
      {"shadow_hand/shadow_hand_right.urdf", 24},
      {"shadow_hand/shadow_hand_left_glb.urdf", 24}};
  for (const auto& [urdf, joints] : expected) {
    const HandModel h = LoadHandModel(hands + urdf);
    EXPECT_EQ(h.num_q(), joints) << urdf;
    EXPECT_GT(h.NumVisualTriangles(), 1000u) << urdf;
    EXPECT_GT(h.NumCollisionPieces(), 0u) << urdf;
  }
}

TEST(Urdf, ShadowMillimetreMeshesAreScaledToMetres) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel h =
      LoadHandModel(test::SharedAssets() + "/hands/shadow_hand/shadow_hand_right.urdf");
  // A distal phalanx is a few centimetres long, whatever unit its file is in.
  for (const char* name : {"ffdistal", "thdistal", "palm"}) {
    const Link& l = h.links[h.LinkIndex(name)];
    Aabb visual, collision;
    for (const TriangleMesh& m : l.visual) visual.Extend(m.Bounds());
    for (const ConvexPiece& p : l.collision)
      for (const Vec3& v : p.hull_vertices) collision.Extend(v);
    EXPECT_GT(visual.Size().maxCoeff(), 0.01) << name;
    EXPECT_LT(visual.Size().maxCoeff(), 0.15) << name;
    // Visual (mm file, scaled) and collision (m file) describe the same body.
    EXPECT_LT((visual.Center() - collision.Center()).norm(), 0.02) << name;
  }
}

TEST(Urdf, AllegroGlbAndObjMeshesAgree) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const std::string dir = test::SharedAssets() + "/hands/allegro_hand/";
  const HandModel obj = LoadHandModel(dir + "allegro_hand_right.urdf");
  const HandModel glb = LoadHandModel(dir + "allegro_hand_right_glb.urdf");
  ASSERT_EQ(obj.links.size(), glb.links.size());
  for (std::size_t l = 0; l < obj.links.size(); ++l) {
    Aabb a, b;
    for (const TriangleMesh& m : obj.links[l].visual) a.Extend(m.Bounds());
    for (const TriangleMesh& m : glb.links[glb.LinkIndex(obj.links[l].name)].visual)
      b.Extend(m.Bounds());
    if (a.Empty()) continue;
    EXPECT_LT((a.min - b.min).norm() + (a.max - b.max).norm(), 1e-4) << obj.links[l].name;
  }
}

TEST(Urdf, OriginalAllegroStlMeshesResolveThroughPackage) {
  INHAND_REQUIRE_SHARED_ASSETS();
  const HandModel h = LoadHandModel(
      test::SharedAssets() + "/hands/allegro_hand_description/allegro_hand_description_right.urdf");
  ASSERT_FALSE(h.mesh_files.empty());
  for (const std::string& f : h.mesh_files)
    EXPECT_NE(f.find("allegro_hand_description/meshes/"), std::string::npos);
  // URDF colour wins when the mesh file has none (binary STL).
  const Link& base = h.links[h.LinkIndex("base_link")];
  ASSERT_FALSE(base.visual.empty());
  EXPECT_NEAR(base.visual[0].material.rgba[0], 0.2, 1e-6);  // urdfdom stores floats
}

}  // namespace
}  // namespace inhand
