#pragma once
// Geometry containers shared by every module: triangle meshes (for drawing and mass
// properties) and convex pieces (for GJK). Plain data; lengths in metres.
#include <cstdint>
#include <string>
#include <vector>

#include "inhand/core/so3.hpp"

namespace inhand {

struct Material {
  std::string name;
  Eigen::Vector4d rgba{0.7, 0.7, 0.7, 1.0};  // linear colour and opacity, each in [0, 1]
  std::string texture_file;                  // absolute path, empty when none
  std::vector<std::uint8_t> texture_blob;    // encoded image (PNG/JPEG) embedded in the file
  bool HasTexture() const { return !texture_file.empty() || !texture_blob.empty(); }
};

struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());
  bool Empty() const { return (min.array() > max.array()).any(); }
  void Extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void Extend(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  Vec3 Size() const { return Empty() ? Vec3::Zero() : Vec3(max - min); }
  Vec3 Center() const { return 0.5 * (min + max); }
};

// An indexed triangle mesh with one material. Normals and uvs are per vertex and either
// empty or of the vertices' size. Triangles wind counter-clockwise seen from outside.
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Vec3> normals;
  std::vector<Vec2> uvs;
  std::vector<Eigen::Vector3i> triangles;
  Material material;

  std::size_t num_triangles() const { return triangles.size(); }
  Aabb Bounds() const;
  void Apply(const Transform& T);   // moves vertices, rotates normals
  void ScaleBy(const Vec3& scale);  // per-axis scale; normals re-normalised
  void ComputeNormals();            // area-weighted vertex normals
  // Checks indices, sizes and finiteness; throws InputError naming `context`.
  void Validate(const std::string& context) const;
};

// Mass properties of a solid bounded by closed, consistently oriented meshes.
struct MassProperties {
  double volume = 0.0;              // [m³]
  Vec3 com = Vec3::Zero();          // centre of mass [m]
  Mat3 inertia_com = Mat3::Zero();  // about the centre of mass, per unit density [m⁵]
};
// Divergence theorem over signed tetrahedra; exact for closed meshes.
MassProperties ComputeMassProperties(const std::vector<const TriangleMesh*>& meshes);

// True when every edge (vertices welded by position within `weld_tolerance`) is shared by
// exactly two triangles with opposite orientation.
bool IsClosed(const TriangleMesh& mesh, double weld_tolerance = 1e-9);
// Weaker, over several meshes together: every edge (welded as above) is used by as many
// triangles in one direction as in the other, so ray parity is well defined (non-manifold edges
// shared by four triangles are fine, as in scans; holes are not). Degenerate triangles are
// ignored: they cross no ray.
bool IsWatertightForParity(const std::vector<const TriangleMesh*>& meshes,
                           double weld_tolerance = 1e-9);

// Splits a mesh into its edge-connected components (vertices welded by position; triangles
// connect across edges shared by exactly two triangles).
std::vector<TriangleMesh> ConnectedComponents(const TriangleMesh& mesh,
                                              double weld_tolerance = 1e-9);

// The positions and triangles of several meshes as one mesh (no normals, uvs or material), for
// geometry computed over all of them.
TriangleMesh MergedGeometry(const std::vector<TriangleMesh>& meshes);

// Quadric-error simplification (Garland & Heckbert) by half-edge collapses onto existing
// vertices, so that every kept vertex keeps its position, uv and normal. Vertices on open edges
// (the mesh's border, uv seams, material borders: edges not shared by exactly two triangles by
// index) stay, so seams do not open. A collapse that would flip or flatten a triangle or make
// the surface non-manifold is skipped. Stops at `target_triangles` or before a collapse whose
// quadric error (the sum of squared distances to the planes it had merged) exceeds
// max_error². Unused vertices are dropped.
TriangleMesh SimplifyMesh(const TriangleMesh& mesh, std::size_t target_triangles, double max_error);

// A convex shape for contact queries, placed in its body (link or object) frame.
// Primitives keep their exact parameters so GJK can use exact support functions; every piece
// also carries its convex hull as vertices + outward triangles (for drawing, bounds, inertia).
struct ConvexPiece {
  enum class Kind { kBox, kSphere, kCylinder, kCapsule, kHull };
  Kind kind = Kind::kHull;
  Transform T_BS = Transform::Identity();  // shape frame in the body frame (primitives: centred,
                                           // cylinder and capsule axes along shape z)
  Vec3 half_extents = Vec3::Zero();        // box
  double radius = 0.0;                     // sphere, cylinder, capsule
  double half_length = 0.0;                // cylinder, capsule: half of the straight segment
  std::vector<Vec3> hull_vertices;         // body frame
  std::vector<Eigen::Vector3i> hull_triangles;
  std::string source;  // where it came from, for messages and reports

  Vec3 bounding_center = Vec3::Zero();  // body frame
  double bounding_radius = 0.0;

  static ConvexPiece Box(const Vec3& half_extents, const Transform& T_BS);
  static ConvexPiece Sphere(double radius, const Transform& T_BS);
  static ConvexPiece Cylinder(double radius, double half_length, const Transform& T_BS);
  static ConvexPiece Capsule(double radius, double half_length, const Transform& T_BS);
  // `vertices` and `triangles` must already be a convex hull (see io/ for the computation).
  static ConvexPiece Hull(std::vector<Vec3> vertices, std::vector<Eigen::Vector3i> triangles);

  // Support point in the body frame: argmax over the shape of dir·x.
  Vec3 Support(const Vec3& dir_B) const;
  // The hull as a mesh (for drawing and mass properties).
  TriangleMesh ToMesh() const;
  void Apply(const Transform& T);  // moves the piece within its body frame
  void UpdateBounds();
  static const char* KindName(Kind kind);
};

}  // namespace inhand
