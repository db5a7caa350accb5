#pragma once
// Mesh files (through assimp) and convex geometry computations (through Bullet), kept behind
// this header: callers see only core types.
#include <map>
#include <string>
#include <vector>

#include "inhand/core/mesh.hpp"

namespace inhand {

// Loads every triangle mesh of a file (STL binary/ASCII, OBJ + MTL, COLLADA, glTF/GLB, PLY, ...)
// with node transforms applied, in the file's units times `scale` (per axis). One TriangleMesh
// per material. Texture files are resolved relative to the mesh file; embedded textures are
// kept as encoded blobs. Throws InputError naming the file when it is missing, unreadable,
// holds no triangles, or names a texture file that does not exist.
enum class MeshGrouping {
  kByMaterial,  // one mesh per material (drawing)
  kByPart,      // one mesh per part of the file (OBJ object/group, glTF/COLLADA node mesh):
                // a convex decomposition stored as parts of one file
};
std::vector<TriangleMesh> LoadMeshFile(const std::string& path, const Vec3& scale = Vec3::Ones(),
                                       MeshGrouping grouping = MeshGrouping::kByMaterial);

// Memoises LoadMeshFile within one model load (hands reuse meshes across links).
class MeshCache {
 public:
  const std::vector<TriangleMesh>& Get(const std::string& path, const Vec3& scale,
                                       MeshGrouping grouping = MeshGrouping::kByMaterial);

 private:
  std::map<std::string, std::vector<TriangleMesh>> meshes_;
};

// Convex hull of a point set (Bullet's btConvexHullComputer): a kHull piece whose vertices are
// the hull's, with outward triangles. Throws InputError (naming `source`) for fewer than 4
// points or a degenerate (flat) set.
ConvexPiece ComputeConvexHull(const std::vector<Vec3>& points, const std::string& source);

// One convex hull per edge-connected component of each mesh: a convex decomposition stored in
// one file. Flat or tiny fragments (a few stray triangles, no volume) are dropped.
std::vector<ConvexPiece> ComponentHulls(const std::vector<TriangleMesh>& meshes,
                                        const std::string& source);

struct HacdParams {
  int min_pieces = 1;           // HACD stops merging at this many pieces
  double concavity = 0.002;     // [m] allowed concavity of a piece: decides the count
  int vertices_per_piece = 64;  // hull vertex budget of each piece
  std::string cache_dir;        // "" → $XDG_CACHE_HOME/inhand or ~/.cache/inhand
};
// Approximate convex decomposition with HACD (Bullet extras), cached on disk keyed by the mesh
// contents and parameters, since it takes about a second per thousand triangles.
std::vector<ConvexPiece> DecomposeHacd(const TriangleMesh& mesh, const HacdParams& params,
                                       const std::string& source);

// The folder of inhand's caches: `override` if set, else $XDG_CACHE_HOME/inhand, ~/.cache/inhand
// or the temporary folder's inhand-cache.
std::string CacheDirectory(const std::string& override_dir = "");

// Writes pieces as one OBJ with an object per piece (readable back with "components").
void WritePiecesObj(const std::vector<ConvexPiece>& pieces, const std::string& path);
std::string PiecesObjText(const std::vector<ConvexPiece>& pieces);  // what WritePiecesObj writes

// Meshes as OBJ text (positions, uvs, normals, one group and material per mesh) and its MTL
// (diffuse colour and opacity as the meshes hold them, the texture as `texture_names[i]`,
// relative to the OBJ; empty: none). The OBJ names its MTL `mtl_name`.
struct ObjText {
  std::string obj, mtl;
};
ObjText MeshesObjText(const std::vector<TriangleMesh>& meshes, const std::string& mtl_name,
                      const std::vector<std::string>& texture_names);

// A convex decomposition of closed meshes by slabs: the meshes' union split into solids
// (welded by position), each cut into slabs about `slab` [m] thick (at most `max_slabs`) across
// its longest axis; a piece is the convex hull of a slab's vertices and of the surface's
// crossings with its two planes. Slabs too thin to enclose a volume are dropped. Throws
// InputError naming `source` when no piece is left.
std::vector<ConvexPiece> SlabHulls(const std::vector<TriangleMesh>& meshes, double slab,
                                   int max_slabs, const std::string& source);

}  // namespace inhand
