#include "inhand/renderer/views.hpp"

#include <algorithm>
#include <cmath>

namespace inhand {

std::optional<Eigen::Vector4d> LegibleColour(const Material& material) {
  if (material.HasTexture()) return std::nullopt;
  const Eigen::Vector4d& c = material.rgba;
  const double luminance = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
  if (!(luminance < kLegibleBelow)) return std::nullopt;
  const double grey = kLegibleLuminance - std::max(0.0, luminance);
  return Eigen::Vector4d(std::max(0.0, c[0]) + grey, std::max(0.0, c[1]) + grey,
                         std::max(0.0, c[2]) + grey, c[3]);
}

HandMeshes UploadHand(Renderer& renderer, const HandModel& hand) {
  HandMeshes out;
  out.link_meshes.resize(hand.links.size());
  out.legible_rgba.resize(hand.links.size());
  for (std::size_t l = 0; l < hand.links.size(); ++l)
    for (const TriangleMesh& m : hand.links[l].visual) {
      out.link_meshes[l].push_back(renderer.AddMesh(m));
      out.legible_rgba[l].push_back(LegibleColour(m.material));
    }
  return out;
}

std::vector<int> UploadObject(Renderer& renderer, const ObjectModel& object,
                              const std::vector<TriangleMesh>& printed) {
  std::vector<int> ids;
  for (const TriangleMesh& m : object.visual) ids.push_back(renderer.AddMesh(m));
  for (const TriangleMesh& m : printed) ids.push_back(renderer.AddMesh(m));
  return ids;
}

void AddHand(Scene& scene, const HandMeshes& meshes, const std::vector<Transform>& T_PL,
             double opacity, bool legible) {
  for (std::size_t l = 0; l < meshes.link_meshes.size(); ++l)
    for (std::size_t k = 0; k < meshes.link_meshes[l].size(); ++k) {
      SceneItem item;
      item.mesh = meshes.link_meshes[l][k];
      if (legible && l < meshes.legible_rgba.size() && k < meshes.legible_rgba[l].size())
        item.rgba = meshes.legible_rgba[l][k];
      item.T_PM = T_PL.at(l);
      item.label = static_cast<std::uint16_t>(kHandLabelBase + l);
      item.opacity = opacity;
      scene.items.push_back(item);
    }
}

void AddObject(Scene& scene, const std::vector<int>& meshes, const Transform& T_PO,
               const ObjectStyle& style) {
  for (int id : meshes) {
    SceneItem item;
    item.mesh = id;
    item.T_PM = T_PO;
    item.label = style.label;
    item.rgba = style.rgba;
    item.opacity = style.opacity;
    item.unlit = style.unlit;
    scene.items.push_back(item);
  }
}

Scene CameraScene(const HandMeshes& hand, const std::vector<Transform>& T_PL,
                  const std::vector<int>& object, const Transform& T_PO, const Transform& T_PC,
                  const Intrinsics& K, const Vec3& background) {
  Scene scene;
  scene.K = K;
  scene.T_PC = T_PC;
  scene.background = background;
  AddHand(scene, hand, T_PL);
  AddObject(scene, object, T_PO);
  return scene;
}

Transform LookAt(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 z = (target - eye).normalized();
  Vec3 x = z.cross(up);
  if (x.norm() < 1e-9) x = z.unitOrthogonal();
  x.normalize();
  const Vec3 y = z.cross(x);  // down on screen
  Mat3 R;
  R << x, y, z;
  return MakeTransform(eye, R);
}

Transform OrbitCamera(const Vec3& center, double distance, double azimuth, double elevation,
                      const Vec3& up) {
  const Vec3 u = up.normalized();
  const Vec3 a = u.unitOrthogonal();
  const Vec3 b = u.cross(a);
  const Vec3 dir = std::cos(elevation) * (std::cos(azimuth) * a + std::sin(azimuth) * b) +
                   std::sin(elevation) * u;
  return LookAt(center + distance * dir, center, u);
}

Intrinsics IntrinsicsFromFov(int width, int height, double vertical_fov_deg) {
  Intrinsics K;
  K.width = width;
  K.height = height;
  K.fy = 0.5 * height / std::tan(0.5 * vertical_fov_deg * M_PI / 180.0);
  K.fx = K.fy;
  K.cx = 0.5 * width - 0.5;
  K.cy = 0.5 * height - 0.5;
  return K;
}

}  // namespace inhand
