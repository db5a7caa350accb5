#pragma once
// Offscreen OpenGL rendering (OSMesa, llvmpipe; no window, no display) of a plain Scene into
// colour, metric depth and a label image. The projection is the estimator's pinhole model
// exactly (core/intrinsics.hpp: pixel centres at integers, OpenCV camera frame), so a vertex
// projected with Intrinsics::Project lands where the renderer draws it.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/mesh.hpp"

namespace inhand {

struct SceneItem {
  int mesh = -1;                           // id from Renderer::AddMesh
  Transform T_PM = Transform::Identity();  // mesh pose in the palm frame
  std::uint16_t label = 0;                 // written to the label image (0: background)
  std::optional<Eigen::Vector4d> rgba;     // replaces the material colour (texture kept)
  double opacity = 1.0;                    // multiplies the material's alpha
  bool unlit = false;                      // flat colour (silhouettes, markers)
};

struct Scene {
  std::vector<SceneItem> items;
  Transform T_PC = Transform::Identity();  // camera pose in the palm frame (OpenCV axes)
  Intrinsics K;
  Eigen::Vector3d background{0.0, 0.0, 0.0};
  double near = 0.01;  // [m] clipping planes along the optical axis
  double far = 20.0;
  // Not empty: only these pixels are drawn (clipped to the image); they are the whole render's
  // to the bit, and every other pixel is the background (depth +inf, label 0). What costs is
  // the pixels drawn and read back: a view that a step reads only around the object renders
  // only there.
  PixelRect region;
};

struct RenderOutput {
  Image8 colour;                     // RGB
  std::vector<float> depth;          // z along the optical axis [m]; +inf where nothing
  std::vector<std::uint16_t> label;  // row-major, top row first
  int width = 0, height = 0;
  float depth_at(int x, int y) const { return depth[std::size_t(y) * width + x]; }
  std::uint16_t label_at(int x, int y) const { return label[std::size_t(y) * width + x]; }
};

class Renderer {
 public:
  // Creates an OSMesa OpenGL 3.3 core context, loading OSMesa on the first renderer of the
  // process (osmesa.hpp). Throws InputError without the library, std::runtime_error when the
  // context cannot be made.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Uploads a mesh (and its texture) once; returns its id for SceneItem::mesh.
  int AddMesh(const TriangleMesh& mesh);
  std::size_t num_meshes() const;

  // Opaque items first, then translucent ones (opacity or material alpha < 1) back to front,
  // blended into the colour only: depth and labels belong to the opaque surfaces.
  void Render(const Scene& scene, RenderOutput& out, bool with_depth_and_labels = true);

  // Coverage masks of many items in one pass: every pixel gets the bitwise OR of the labels of
  // the items covering it, occluded or not (no depth test; give each item its own bit). Only
  // this mask is read back (width x height, top row first): the silhouettes of up to 16 objects
  // for the price of one render.
  void RenderMasks(const Scene& scene, std::vector<std::uint16_t>& bits);

  // "OSMesa" with the GL renderer string, for logs.
  std::string Description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The OpenGL projection matrix (column-major 4x4) for pinhole intrinsics, OpenCV camera axes,
// pixel centres at integer coordinates. Exposed for tests.
Eigen::Matrix4d ProjectionMatrix(const Intrinsics& K, double near, double far);

}  // namespace inhand
