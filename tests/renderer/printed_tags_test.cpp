#include "inhand/renderer/printed_tags.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "inhand/core/error.hpp"

namespace inhand {
namespace {

TagPlacement Tag(int id, double size) {
  TagPlacement tag;
  tag.id = id;
  tag.size = size;
  return tag;
}

// The object's printed tags (its appearance in the virtual image): each quad lies 0.2 mm off the
// surface along the tag's normal, centred on the tag, and contains the tag's outer corners.
TEST(PrintedTags, MeshesSitOnTheirPlacements) {
  ObjectModel object;
  TagPlacement a = Tag(0, 0.03), b = Tag(5, 0.02);
  a.T_OT = MakeTransform(Vec3(0.01, 0.02, 0.05), ExpSO3(Vec3(0.3, -0.2, 0.5)));
  b.T_OT = MakeTransform(Vec3(-0.03, 0.0, 0.0), ExpSO3(Vec3(0.0, M_PI / 2, 0.0)));
  object.tags = {a, b};
  const std::vector<TriangleMesh> meshes = PrintedTagMeshes(object);
  ASSERT_EQ(meshes.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const TagPlacement& tag = object.tags[i];
    const Vec3 n = tag.T_OT.linear().col(2);
    Vec3 centre = Vec3::Zero();
    for (const Vec3& v : meshes[i].vertices) {
      EXPECT_NEAR(n.dot(v - tag.T_OT.translation()), 0.0002, 1e-9);
      centre += v / static_cast<double>(meshes[i].vertices.size());
    }
    EXPECT_LT((centre - (tag.T_OT.translation() + 0.0002 * n)).norm(), 1e-9);
    double half = 0.0;
    for (const Vec3& v : meshes[i].vertices)
      half = std::max(half, (tag.T_OT.inverse() * v).head<2>().cwiseAbs().maxCoeff());
    EXPECT_GE(half, tag.size / 2 - 1e-9);  // the white border lies outside the outer corners
  }
}

// An id beyond its family, or an unknown family: refused by name.
TEST(PrintedTags, UnknownFamiliesAndIdsAreRefused) {
  EXPECT_THROW(MakeTagMesh(Tag(100000, 0.03)), InputError);
  TagPlacement tag = Tag(0, 0.03);
  tag.family = "tag99h1";
  EXPECT_THROW(MakeTagMesh(tag), InputError);
  EXPECT_NO_THROW(MakeTagMesh(Tag(586, 0.03)));  // tag36h11's last id
}

}  // namespace
}  // namespace inhand
