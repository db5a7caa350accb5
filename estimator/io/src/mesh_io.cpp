#include "inhand/io/mesh_io.hpp"

#include <HACD/hacdHACD.h>
#include <LinearMath/btConvexHullComputer.h>

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/fnv1a.hpp"

namespace fs = std::filesystem;

namespace inhand {

namespace {

std::string Trim(std::string s) {
  const auto not_space = [](unsigned char c) { return !std::isspace(c); };
  s.erase(s.begin(), std::find_if(s.begin(), s.end(), not_space));
  s.erase(std::find_if(s.rbegin(), s.rend(), not_space).base(), s.end());
  return s;
}

Material ReadMaterial(const aiScene& scene, const aiMaterial& ai, const fs::path& mesh_file) {
  Material m;
  aiString name;
  if (ai.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) m.name = name.C_Str();
  aiColor4D colour;
  if (ai.Get(AI_MATKEY_BASE_COLOR, colour) == AI_SUCCESS ||
      ai.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == AI_SUCCESS) {
    m.rgba = Eigen::Vector4d(colour.r, colour.g, colour.b, colour.a);
  }
  float opacity = 1.0f;
  if (ai.Get(AI_MATKEY_OPACITY, opacity) == AI_SUCCESS && opacity < 1.0f) m.rgba[3] = opacity;

  aiString tex;
  const bool has_tex = ai.GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
                       ai.GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS;
  if (has_tex) {
    const std::string ref = Trim(tex.C_Str());  // YCB's .mtl lines end with a space
    if (const aiTexture* embedded = scene.GetEmbeddedTexture(ref.c_str())) {
      if (embedded->mHeight == 0) {  // compressed (PNG/JPEG) bytes
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(embedded->pcData);
        m.texture_blob.assign(bytes, bytes + embedded->mWidth);
      }
    } else if (!ref.empty()) {
      fs::path p(ref);
      if (p.is_relative()) p = mesh_file.parent_path() / p;
      if (!fs::exists(p))
        throw InputError(mesh_file.string() + ": material '" + m.name + "' names texture '" + ref +
                         "', which does not exist (looked for " + p.string() + ")");
      m.texture_file = fs::weakly_canonical(p).string();
    }
  }
  // Diffuse colour is a multiplier on the texture; a black multiplier would hide it.
  if (m.HasTexture() && m.rgba.head<3>().isZero()) m.rgba.head<3>().setOnes();
  return m;
}

}  // namespace

std::vector<TriangleMesh> LoadMeshFile(const std::string& path, const Vec3& scale,
                                       MeshGrouping grouping) {
  if (!fs::exists(path)) throw InputError(path + ": mesh file does not exist");
  if (!fs::is_regular_file(path)) throw InputError(path + ": mesh path is not a file");
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Smooth normals across gentle bends only: box edges and caps stay sharp.
  importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, 60.0f);
  // Keep the file's meshes apart: the grouping below decides what to merge.
  importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                aiProcess_PreTransformVertices | aiProcess_GenSmoothNormals);
  if (scene == nullptr || scene->mRootNode == nullptr)
    throw InputError(path + ": cannot read mesh (" + importer.GetErrorString() + ")");

  // A sane limit: the YCB scans have ~16k-300k triangles; 5 million would take gigabytes.
  std::size_t triangles = 0;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) triangles += scene->mMeshes[mi]->mNumFaces;
  if (triangles > 5'000'000)
    throw InputError(path + ": " + std::to_string(triangles) +
                     " triangles, more than the 5,000,000 a model may have; simplify it");
  // One output mesh per material (merging the file's meshes that share it) or per part.
  std::map<unsigned, TriangleMesh> by_material;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh& am = *scene->mMeshes[mi];
    if (!(am.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const unsigned group = grouping == MeshGrouping::kByMaterial ? am.mMaterialIndex : mi;
    auto [it, inserted] = by_material.try_emplace(group);
    TriangleMesh& out = it->second;
    if (inserted && am.mMaterialIndex < scene->mNumMaterials)
      out.material = ReadMaterial(*scene, *scene->mMaterials[am.mMaterialIndex], fs::path(path));
    const int base = static_cast<int>(out.vertices.size());
    const bool has_uv = am.HasTextureCoords(0);
    // Keep per-vertex arrays aligned when meshes with and without uvs share a material.
    if (has_uv && out.uvs.size() < out.vertices.size())
      out.uvs.resize(out.vertices.size(), Vec2::Zero());
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      out.vertices.emplace_back(am.mVertices[v].x, am.mVertices[v].y, am.mVertices[v].z);
      if (am.HasNormals())
        out.normals.emplace_back(am.mNormals[v].x, am.mNormals[v].y, am.mNormals[v].z);
      if (has_uv)
        out.uvs.emplace_back(am.mTextureCoords[0][v].x, am.mTextureCoords[0][v].y);
      else if (!out.uvs.empty())
        out.uvs.emplace_back(0.0, 0.0);
    }
    for (unsigned f = 0; f < am.mNumFaces; ++f) {
      const aiFace& face = am.mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                                 base + static_cast<int>(face.mIndices[1]),
                                 base + static_cast<int>(face.mIndices[2]));
    }
  }
  std::vector<TriangleMesh> meshes;
  for (auto& [index, mesh] : by_material) {
    if (mesh.triangles.empty()) continue;
    if (mesh.normals.size() != mesh.vertices.size()) mesh.ComputeNormals();
    if (!mesh.uvs.empty() && !mesh.material.HasTexture()) mesh.uvs.clear();
    if (scale != Vec3::Ones()) mesh.ScaleBy(scale);
    mesh.Validate(path);
    meshes.push_back(std::move(mesh));
  }
  if (meshes.empty()) throw InputError(path + ": mesh file holds no triangles");
  return meshes;
}

const std::vector<TriangleMesh>& MeshCache::Get(const std::string& path, const Vec3& scale,
                                                MeshGrouping grouping) {
  std::ostringstream key;
  key << std::setprecision(17) << path << '|' << scale.x() << ',' << scale.y() << ',' << scale.z()
      << '|' << static_cast<int>(grouping);
  auto it = meshes_.find(key.str());
  if (it == meshes_.end())
    it = meshes_.emplace(key.str(), LoadMeshFile(path, scale, grouping)).first;
  return it->second;
}

ConvexPiece ComputeConvexHull(const std::vector<Vec3>& points, const std::string& source) {
  if (points.size() < 4)
    throw InputError(source + ": a convex piece needs at least 4 points, got " +
                     std::to_string(points.size()));
  std::vector<double> coords;
  coords.reserve(points.size() * 3);
  for (const Vec3& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  btConvexHullComputer hull;
  hull.compute(coords.data(), 3 * static_cast<int>(sizeof(double)), static_cast<int>(points.size()),
               0.0, 0.0);
  if (hull.faces.size() < 4)
    throw InputError(source + ": points are degenerate (flat or collinear), no 3-D convex hull");
  std::vector<Vec3> vertices;
  for (int i = 0; i < hull.vertices.size(); ++i)
    vertices.emplace_back(hull.vertices[i].x(), hull.vertices[i].y(), hull.vertices[i].z());
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& v : vertices) centroid += v;
  centroid /= static_cast<double>(vertices.size());
  std::vector<Eigen::Vector3i> triangles;
  for (int f = 0; f < hull.faces.size(); ++f) {
    const btConvexHullComputer::Edge* first = &hull.edges[hull.faces[f]];
    std::vector<int> polygon;
    const btConvexHullComputer::Edge* e = first;
    do {
      polygon.push_back(e->getSourceVertex());
      e = e->getNextEdgeOfFace();
    } while (e != first && polygon.size() <= static_cast<std::size_t>(hull.vertices.size()));
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
      Eigen::Vector3i t(polygon[0], polygon[k], polygon[k + 1]);
      const Vec3 n = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
      if (n.dot(vertices[t[0]] - centroid) < 0.0) std::swap(t[1], t[2]);
      triangles.push_back(t);
    }
  }
  ConvexPiece piece = ConvexPiece::Hull(std::move(vertices), std::move(triangles));
  piece.source = source;
  return piece;
}

std::vector<ConvexPiece> ComponentHulls(const std::vector<TriangleMesh>& meshes,
                                        const std::string& source) {
  std::vector<ConvexPiece> pieces;
  int index = 0;
  for (const TriangleMesh& mesh : meshes) {
    for (const TriangleMesh& part : ConnectedComponents(mesh, 1e-9)) {
      const std::string where = source + " (component " + std::to_string(index++) + ")";
      if (part.vertices.size() < 4) continue;
      try {
        pieces.push_back(ComputeConvexHull(part.vertices, where));
      } catch (const InputError&) {
        // flat fragment
      }
    }
  }
  if (pieces.empty()) throw InputError(source + ": no component encloses a volume");
  return pieces;
}

namespace {}  // namespace

std::string CacheDirectory(const std::string& override_dir) {
  if (!override_dir.empty()) return override_dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return (fs::path(xdg) / "inhand").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (fs::path(home) / ".cache" / "inhand").string();
  return (fs::temp_directory_path() / "inhand-cache").string();
}

namespace {

// FNV-1a over the mesh and the parameters: the cache key.
std::uint64_t HashMesh(const TriangleMesh& mesh, const HacdParams& params) {
  detail::Fnv1a h;
  for (const Vec3& v : mesh.vertices) h.Mix(v);
  for (const auto& t : mesh.triangles) h.Mix(t.data(), sizeof(int) * 3);
  h.Mix(&params.min_pieces, sizeof(params.min_pieces));
  h.Mix(params.concavity);
  h.Mix(&params.vertices_per_piece, sizeof(params.vertices_per_piece));
  return h.value();
}

std::vector<ConvexPiece> ReadPiecesObj(const std::string& path, const std::string& source) {
  std::ifstream in(path);
  std::vector<std::vector<Vec3>> groups;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "o") groups.emplace_back();
    if (tag == "v") {
      Vec3 v;
      ls >> v.x() >> v.y() >> v.z();
      if (groups.empty()) groups.emplace_back();
      groups.back().push_back(v);
    }
  }
  std::vector<ConvexPiece> pieces;
  for (std::size_t i = 0; i < groups.size(); ++i)
    pieces.push_back(
        ComputeConvexHull(groups[i], source + " (HACD piece " + std::to_string(i) + ")"));
  return pieces;
}

}  // namespace

std::string PiecesObjText(const std::vector<ConvexPiece>& pieces) {
  std::ostringstream out;
  out << std::setprecision(17) << "# convex pieces written by inhand\n";
  int base = 1;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    out << "o piece_" << i << "\n";
    for (const Vec3& v : pieces[i].hull_vertices)
      out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << "\n";
    for (const auto& t : pieces[i].hull_triangles)
      out << "f " << base + t[0] << ' ' << base + t[1] << ' ' << base + t[2] << "\n";
    base += static_cast<int>(pieces[i].hull_vertices.size());
  }
  return out.str();
}

void WritePiecesObj(const std::vector<ConvexPiece>& pieces, const std::string& path) {
  const fs::path tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(path + ": cannot write");
    out << PiecesObjText(pieces);
    if (!out) throw InputError(path + ": cannot write");
  }
  fs::rename(tmp, path);
}

ObjText MeshesObjText(const std::vector<TriangleMesh>& meshes, const std::string& mtl_name,
                      const std::vector<std::string>& texture_names) {
  INHAND_CHECK(texture_names.size() == meshes.size(), "one texture name per mesh");
  std::ostringstream obj, mtl;
  obj << std::setprecision(9) << "# written by inhand\nmtllib " << mtl_name << "\n";
  mtl << std::setprecision(9) << "# written by inhand\n";
  std::size_t base_v = 1, base_t = 1, base_n = 1;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const TriangleMesh& m = meshes[i];
    m.Validate("MeshesObjText");
    const std::string material = "material_" + std::to_string(i);
    mtl << "newmtl " << material << "\nKd " << m.material.rgba[0] << ' ' << m.material.rgba[1]
        << ' ' << m.material.rgba[2] << "\nd " << m.material.rgba[3] << "\n";
    if (!texture_names[i].empty()) mtl << "map_Kd " << texture_names[i] << "\n";
    obj << "g part_" << i << "\nusemtl " << material << "\n";
    for (const Vec3& v : m.vertices) obj << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << "\n";
    for (const Vec2& t : m.uvs) obj << "vt " << t.x() << ' ' << t.y() << "\n";
    for (const Vec3& n : m.normals) obj << "vn " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n";
    const bool uv = !m.uvs.empty(), normal = !m.normals.empty();
    for (const Eigen::Vector3i& t : m.triangles) {
      obj << "f";
      for (int k = 0; k < 3; ++k) {
        obj << ' ' << base_v + static_cast<std::size_t>(t[k]);
        if (uv || normal) obj << '/';
        if (uv) obj << base_t + static_cast<std::size_t>(t[k]);
        if (normal) obj << '/' << base_n + static_cast<std::size_t>(t[k]);
      }
      obj << "\n";
    }
    base_v += m.vertices.size(), base_t += m.uvs.size(), base_n += m.normals.size();
  }
  return {obj.str(), mtl.str()};
}

std::vector<ConvexPiece> SlabHulls(const std::vector<TriangleMesh>& meshes, double slab,
                                   int max_slabs, const std::string& source) {
  INHAND_CHECK(slab > 0.0 && max_slabs >= 1, "slab thickness and count must be positive");
  std::vector<ConvexPiece> pieces;
  int index = 0;
  for (const TriangleMesh& solid : ConnectedComponents(MergedGeometry(meshes), 1e-7)) {
    const Aabb box = solid.Bounds();
    int axis = 0;
    box.Size().maxCoeff(&axis);
    const double lo = box.min[axis], length = box.Size()[axis];
    const int count = std::clamp(static_cast<int>(std::lround(length / slab)), 1, max_slabs);
    for (int k = 0; k < count; ++k) {
      const double a = lo + length * k / count, b = lo + length * (k + 1) / count;
      const double eps = 1e-9 * std::max(1.0, length);
      std::vector<Vec3> points;
      for (const Vec3& v : solid.vertices)
        if (v[axis] >= a - eps && v[axis] <= b + eps) points.push_back(v);
      for (const Eigen::Vector3i& t : solid.triangles)
        for (int e = 0; e < 3; ++e) {
          const Vec3& p = solid.vertices[static_cast<std::size_t>(t[e])];
          const Vec3& q = solid.vertices[static_cast<std::size_t>(t[(e + 1) % 3])];
          for (const double plane : {a, b})
            if ((p[axis] - plane) * (q[axis] - plane) < 0.0)
              points.push_back(p + (q - p) * ((plane - p[axis]) / (q[axis] - p[axis])));
        }
      const std::string where =
          source + " (solid " + std::to_string(index) + ", slab " + std::to_string(k) + ")";
      if (points.size() < 4) continue;
      try {
        pieces.push_back(ComputeConvexHull(points, where));
        pieces.back().source = where;
      } catch (const InputError&) {
        // too thin to enclose a volume
      }
    }
    ++index;
  }
  if (pieces.empty()) throw InputError(source + ": no slab encloses a volume");
  return pieces;
}

std::vector<ConvexPiece> DecomposeHacd(const TriangleMesh& mesh, const HacdParams& params,
                                       const std::string& source) {
  if (params.min_pieces < 1 || params.vertices_per_piece < 4 || !(params.concavity > 0.0))
    throw InputError(source +
                     ": HACD parameters need min_pieces >= 1, vertices_per_piece >= 4, "
                     "concavity > 0");
  const fs::path dir = CacheDirectory(params.cache_dir);
  std::ostringstream name;
  name << "hacd-" << std::hex << std::setw(16) << std::setfill('0') << HashMesh(mesh, params)
       << ".obj";
  const fs::path cached = dir / name.str();
  if (fs::exists(cached)) return ReadPiecesObj(cached.string(), source);

  std::vector<HACD::Vec3<HACD::Real>> points;
  for (const Vec3& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<HACD::Vec3<long>> triangles;
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  HACD::HACD hacd;
  hacd.SetPoints(points.data());
  hacd.SetNPoints(points.size());
  hacd.SetTriangles(triangles.data());
  hacd.SetNTriangles(triangles.size());
  hacd.SetCompacityWeight(0.1);
  hacd.SetVolumeWeight(0.0);
  hacd.SetNClusters(static_cast<std::size_t>(params.min_pieces));
  hacd.SetNVerticesPerCH(static_cast<std::size_t>(params.vertices_per_piece));
  // HACD normalises the mesh so that its bounding-box diagonal spans 2 * scale (scale = 1000
  // by default): express the concavity in those units.
  const double diagonal = mesh.Bounds().Size().norm();
  hacd.SetConcavity(params.concavity * 2.0 * hacd.GetScaleFactor() / std::max(diagonal, 1e-12));
  hacd.SetAddExtraDistPoints(true);
  hacd.SetAddNeighboursDistPoints(false);
  hacd.SetAddFacesPoints(true);
  if (!hacd.Compute()) throw InputError(source + ": HACD decomposition failed");

  std::vector<ConvexPiece> pieces;
  for (std::size_t c = 0; c < hacd.GetNClusters(); ++c) {
    std::vector<HACD::Vec3<HACD::Real>> ch_points(hacd.GetNPointsCH(c));
    std::vector<HACD::Vec3<long>> ch_triangles(hacd.GetNTrianglesCH(c));
    hacd.GetCH(c, ch_points.data(), ch_triangles.data());
    std::vector<Vec3> pts;
    for (const auto& p : ch_points) pts.emplace_back(p.X(), p.Y(), p.Z());
    if (pts.size() < 4) continue;
    try {
      pieces.push_back(ComputeConvexHull(pts, source + " (HACD piece " + std::to_string(c) + ")"));
    } catch (const InputError&) {
      // A flat sliver carries no volume: GJK loses nothing without it.
    }
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!ec) {
    try {
      WritePiecesObj(pieces, cached.string());
    } catch (const InputError&) {
      // An unwritable cache only costs time.
    }
  }
  return pieces;
}

}  // namespace inhand
