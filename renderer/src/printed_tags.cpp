#include "inhand/renderer/printed_tags.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>

#include <algorithm>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand {
namespace {

// AprilTag's family tables, for the bitmaps of the tags as printed (the detector in features/
// holds its own: the two modules do not see each other).
struct Family {
  apriltag_family_t* family = nullptr;
  void (*destroy)(apriltag_family_t*) = nullptr;
};

Family CreateFamily(const std::string& f) {
  if (f == "tag36h11") return {tag36h11_create(), tag36h11_destroy};
  if (f == "tag25h9") return {tag25h9_create(), tag25h9_destroy};
  if (f == "tag16h5") return {tag16h5_create(), tag16h5_destroy};
  if (f == "tagStandard41h12") return {tagStandard41h12_create(), tagStandard41h12_destroy};
  if (f == "tagCircle21h7") return {tagCircle21h7_create(), tagCircle21h7_destroy};
  throw InputError(
      "tag family '" + f +
      "' is unknown, expected tag36h11, tag25h9, tag16h5, tagStandard41h12 or tagCircle21h7");
}

}  // namespace

TriangleMesh MakeTagMesh(const TagPlacement& tag) {
  const Family fam = CreateFamily(tag.family);
  if (tag.id < 0 || static_cast<unsigned>(tag.id) >= fam.family->ncodes) {
    fam.destroy(fam.family);
    throw InputError("tag id " + std::to_string(tag.id) + " is not in family " + tag.family);
  }
  image_u8_t* im = apriltag_to_image(fam.family, tag.id);
  const int w = im->width;
  // The outer black border sits width_at_border modules across, centred in the bitmap.
  const double border_modules = static_cast<double>(fam.family->width_at_border);
  fam.destroy(fam.family);
  constexpr int kScale = 24;  // nearest-neighbour upscaling keeps the edges sharp when sampled
  Image8 big(w * kScale, w * kScale, 3);
  for (int y = 0; y < big.height; ++y)
    for (int x = 0; x < big.width; ++x)
      std::fill_n(big.pixel(x, y), 3, im->buf[(y / kScale) * im->stride + x / kScale]);
  image_u8_destroy(im);
  std::vector<std::uint8_t> png = EncodePng(big);
  const double half = 0.5 * tag.size * w / border_modules;
  TriangleMesh m;
  m.vertices = {Vec3(-half, -half, 0), Vec3(half, -half, 0), Vec3(half, half, 0),
                Vec3(-half, half, 0)};
  m.normals.assign(4, Vec3::UnitZ());
  m.uvs = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  m.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  m.material.name = tag.family + ":" + std::to_string(tag.id);
  m.material.rgba = Eigen::Vector4d(1, 1, 1, 1);
  m.material.texture_blob = png;
  return m;
}

std::vector<TriangleMesh> PrintedTagMeshes(const ObjectModel& object) {
  std::vector<TriangleMesh> out;
  for (const TagPlacement& tag : object.tags) {
    out.push_back(MakeTagMesh(tag));
    out.back().Apply(tag.T_OT * MakeTransform(Vec3(0, 0, 0.0002), Mat3::Identity()));
  }
  return out;
}

}  // namespace inhand
