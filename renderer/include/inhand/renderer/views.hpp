#pragma once
// Building scenes from hand and object models: meshes uploaded once, items placed per frame.
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/renderer/renderer.hpp"

namespace inhand {

// Label image values: 0 background, kObjectLabel the object, kHandLabelBase + link index the
// hand's links, kExtraLabelBase + i anything else a caller adds.
constexpr std::uint16_t kObjectLabel = 1;
constexpr std::uint16_t kHandLabelBase = 100;
constexpr std::uint16_t kExtraLabelBase = 1000;

struct HandMeshes {
  std::vector<std::vector<int>> link_meshes;  // per link, renderer mesh ids
  // Per link and mesh: the colour the explanatory views (the external 3-D view, model previews)
  // draw it in when its own is too dark to show its shape (LegibleColour), else empty.
  std::vector<std::vector<std::optional<Eigen::Vector4d>>> legible_rgba;
};
HandMeshes UploadHand(Renderer& renderer, const HandModel& hand);
// A material darker than kLegibleBelow (linear luminance, no texture) shows as a flat black
// silhouette: the Allegro hand's black anodised links (Kd 0.004) hide every finger in front of
// the palm. Its colour with grey added up to kLegibleLuminance (our hand's darkest links), hue
// and opacity kept; empty for a material that shows its shape already.
constexpr double kLegibleBelow = 0.05;
constexpr double kLegibleLuminance = 0.16;
std::optional<Eigen::Vector4d> LegibleColour(const Material& material);
// The object's visual meshes, then `printed` (meshes already in the object frame: its printed
// tags, printed_tags.hpp), all placed together by AddObject.
std::vector<int> UploadObject(Renderer& renderer, const ObjectModel& object,
                              const std::vector<TriangleMesh>& printed = {});

// `legible`: very dark links in their LegibleColour (views that explain; a camera's virtual view
// keeps the materials).
void AddHand(Scene& scene, const HandMeshes& meshes, const std::vector<Transform>& T_PL,
             double opacity = 1.0, bool legible = false);
struct ObjectStyle {
  std::optional<Eigen::Vector4d> rgba;  // flat colour instead of the materials
  double opacity = 1.0;
  bool unlit = false;
  std::uint16_t label = kObjectLabel;
};
void AddObject(Scene& scene, const std::vector<int>& meshes, const Transform& T_PO,
               const ObjectStyle& style = {});

// The hand (links at T_PL) and the object (at T_PO) seen from a camera at T_PC: the scene as an
// estimate believes it, e.g. the virtual image of the extracted-feature step.
Scene CameraScene(const HandMeshes& hand, const std::vector<Transform>& T_PL,
                  const std::vector<int>& object, const Transform& T_PO, const Transform& T_PC,
                  const Intrinsics& K, const Vec3& background);

// Camera pose (OpenCV axes: z towards the target, y down on screen) looking from eye at
// target, with `up` pointing up on screen.
Transform LookAt(const Vec3& eye, const Vec3& target, const Vec3& up);
// On a sphere around `center`: azimuth about `up`, elevation above the plane normal to it.
Transform OrbitCamera(const Vec3& center, double distance, double azimuth, double elevation,
                      const Vec3& up = Vec3::UnitZ());
Intrinsics IntrinsicsFromFov(int width, int height, double vertical_fov_deg);

}  // namespace inhand
