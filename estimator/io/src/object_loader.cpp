#include "inhand/io/object_loader.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <filesystem>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/mesh_io.hpp"

namespace fs = std::filesystem;

namespace inhand {

namespace {

// Convex pieces of a collision mesh by `method`: "hull" (one piece), "components" (one hull per
// part of the file and, within a part, per edge-connected component: a decomposition stored in
// one file), "hacd" (computed, cached).
void PiecesFromMesh(const std::vector<TriangleMesh>& meshes, const std::string& method,
                    const HacdParams& hacd, const std::string& where,
                    std::vector<ConvexPiece>& out) {
  if (method == "hull") {
    std::vector<Vec3> points;
    for (const TriangleMesh& m : meshes)
      points.insert(points.end(), m.vertices.begin(), m.vertices.end());
    out.push_back(ComputeConvexHull(points, where));
  } else if (method == "components") {
    for (ConvexPiece& p : ComponentHulls(meshes, where)) out.push_back(std::move(p));
  } else if (method == "hacd") {
    for (ConvexPiece& p : DecomposeHacd(MergedGeometry(meshes), hacd, where))
      out.push_back(std::move(p));
  } else {
    throw InputError(where + ": collision method '" + method +
                     "' is unknown, expected \"hull\", \"components\" or \"hacd\"");
  }
}

ObjectModel LoadObjectJson(const std::string& path, const PackageMap& packages,
                           const ContactFieldOptions* field_override) {
  const jsonf::Json doc = jsonf::ReadFile(path);
  const jsonf::Field root{doc, path, ""};
  if (root.Has("format") && root["format"].String() != "inhand-object")
    root["format"].Fail("\"inhand-object\"");
  if (root.Has("version") && root["version"].Integer() != 1) root["version"].Fail("1");

  ObjectModel obj;
  obj.source = path;
  obj.name = root["name"].String();
  MeshCache cache;

  const jsonf::Field visual = root["visual"];
  for (std::size_t i = 0; i < visual.Size(); ++i) {
    const jsonf::Field v = visual.At(i);
    const std::string file = ResolveResource(v["mesh"].String(), path, packages);
    if (std::find(obj.mesh_files.begin(), obj.mesh_files.end(), file) == obj.mesh_files.end())
      obj.mesh_files.push_back(file);
    const Vec3 scale = v.Has("scale") ? v["scale"].Vector3() : Vec3::Ones();
    const Transform T = v.Has("pose") ? v["pose"].Pose() : Transform::Identity();
    for (TriangleMesh mesh : cache.Get(file, scale)) {
      mesh.Apply(T);
      if (v.Has("rgba")) {
        const jsonf::Field c = v["rgba"];
        if (c.Size() != 4) c.Fail("an array of 4 numbers in [0, 1]");
        for (int k = 0; k < 4; ++k)
          mesh.material.rgba[k] = c.At(static_cast<std::size_t>(k)).Number();
      }
      if (v.Has("opacity")) {
        const double a = v["opacity"].Number();
        if (a < 0.0 || a > 1.0) v["opacity"].Fail("a number in [0, 1]");
        mesh.material.rgba[3] = a;
      }
      obj.visual.push_back(std::move(mesh));
    }
  }

  HacdParams hacd;
  if (root.Has("hacd")) {
    const jsonf::Field h = root["hacd"];
    if (h.Has("min_pieces")) hacd.min_pieces = h["min_pieces"].Integer();
    if (h.Has("concavity")) hacd.concavity = h["concavity"].PositiveNumber();
    if (h.Has("vertices_per_piece")) hacd.vertices_per_piece = h["vertices_per_piece"].Integer();
  }
  const jsonf::Field collision = root["collision"];
  std::vector<std::string> methods;
  for (std::size_t i = 0; i < collision.Size(); ++i) {
    const jsonf::Field c = collision.At(i);
    const Transform T = c.Has("pose") ? c["pose"].Pose() : Transform::Identity();
    const std::string where = c.Where();
    if (c.Has("mesh")) {
      const std::string file = ResolveResource(c["mesh"].String(), path, packages);
      if (std::find(obj.mesh_files.begin(), obj.mesh_files.end(), file) == obj.mesh_files.end())
        obj.mesh_files.push_back(file);
      const std::string method = c.Has("method") ? c["method"].String() : "components";
      std::vector<TriangleMesh> meshes = cache.Get(
          file, c.Has("scale") ? c["scale"].Vector3() : Vec3::Ones(), MeshGrouping::kByPart);
      for (TriangleMesh& m : meshes) m.Apply(T);
      PiecesFromMesh(meshes, method, hacd, file, obj.pieces);
      methods.push_back(method + " of " + fs::path(file).filename().string());
    } else if (c.Has("box")) {
      const Vec3 size = c["box"].Vector3();
      if (!(size.minCoeff() > 0.0)) c["box"].Fail("three sizes > 0 [m]");
      obj.pieces.push_back(ConvexPiece::Box(0.5 * size, T));
      methods.emplace_back("box");
    } else if (c.Has("sphere")) {
      obj.pieces.push_back(ConvexPiece::Sphere(c["sphere"].PositiveNumber(), T));
      methods.emplace_back("sphere");
    } else if (c.Has("cylinder") || c.Has("capsule")) {
      const bool capsule = c.Has("capsule");
      const jsonf::Field d = c[capsule ? "capsule" : "cylinder"];
      const double radius = d["radius"].PositiveNumber();
      const double length =
          capsule ? d["length"].NonNegativeNumber() : d["length"].PositiveNumber();
      obj.pieces.push_back(capsule ? ConvexPiece::Capsule(radius, 0.5 * length, T)
                                   : ConvexPiece::Cylinder(radius, 0.5 * length, T));
      methods.emplace_back(capsule ? "capsule" : "cylinder");
    } else {
      c.Fail("a collision element with \"mesh\", \"box\", \"sphere\", \"cylinder\" or \"capsule\"");
    }
    obj.pieces.back().source = obj.pieces.back().source.empty() ? where : obj.pieces.back().source;
  }
  for (std::size_t i = 0; i < methods.size(); ++i)
    obj.decomposition += (i ? ", " : "") + methods[i];
  if (obj.pieces.empty()) collision.Fail("at least one collision element");

  obj.mass = root["mass"].PositiveNumber();
  if (root.Has("friction")) obj.friction = root["friction"].NonNegativeNumber();

  // Mass properties: explicit, else from the closed visual meshes, else from the pieces.
  std::vector<const TriangleMesh*> solids;
  bool visual_closed = !obj.visual.empty();
  for (const TriangleMesh& m : obj.visual) visual_closed = visual_closed && IsClosed(m, 1e-7);
  std::vector<TriangleMesh> piece_meshes;
  if (visual_closed) {
    for (const TriangleMesh& m : obj.visual) solids.push_back(&m);
  } else {
    for (const ConvexPiece& p : obj.pieces) piece_meshes.push_back(p.ToMesh());
    for (const TriangleMesh& m : piece_meshes) solids.push_back(&m);
  }
  const MassProperties mp = ComputeMassProperties(solids);
  if (!(mp.volume > 0.0))
    throw InputError(path + ": the object's geometry encloses no volume (check triangle winding)");
  obj.com_O = mp.com;
  obj.inertia_com = mp.inertia_com * (obj.mass / mp.volume);
  if (root.Has("com")) obj.com_O = root["com"].Vector3();
  if (root.Has("inertia")) {
    const jsonf::Field I = root["inertia"];
    Mat3 M;
    const double ixy = I.Has("ixy") ? I["ixy"].Number() : 0.0;
    const double ixz = I.Has("ixz") ? I["ixz"].Number() : 0.0;
    const double iyz = I.Has("iyz") ? I["iyz"].Number() : 0.0;
    M << I["ixx"].PositiveNumber(), ixy, ixz, ixy, I["iyy"].PositiveNumber(), iyz, ixz, iyz,
        I["izz"].PositiveNumber();
    if (!M.allFinite() || Eigen::SelfAdjointEigenSolver<Mat3>(M).eigenvalues().minCoeff() <= 0.0)
      throw InputError(
          path +
          ": field 'inertia' is not positive definite (no rigid body has it: check ixy, ixz, iyz)");
    obj.inertia_com = M;
  }

  if (root.Has("tags")) {
    const jsonf::Field tags = root["tags"];
    for (std::size_t i = 0; i < tags.Size(); ++i) {
      const jsonf::Field t = tags.At(i);
      TagPlacement tag;
      tag.family = t.Has("family") ? t["family"].String() : "tag36h11";
      if (tag.family != "tag36h11" && tag.family != "tag25h9" && tag.family != "tag16h5" &&
          tag.family != "tagStandard41h12" && tag.family != "tagCircle21h7")
        t["family"].Fail("tag36h11, tag25h9, tag16h5, tagStandard41h12 or tagCircle21h7");
      tag.id = t["id"].Integer();
      if (tag.id < 0) t["id"].Fail("an id >= 0");
      tag.size = t["size"].PositiveNumber();
      tag.T_OT = t["pose"].Pose();
      obj.tags.push_back(tag);
    }
  }

  if (root.Has("symmetry")) {
    const jsonf::Field sym = root["symmetry"];
    sym.ExpectKeys({"axis", "point"});
    const Vec3 axis = sym["axis"].Vector3();
    if (!(axis.norm() > 1e-9)) sym["axis"].Fail("a direction (three numbers, not all zero)");
    if (!obj.tags.empty())
      sym.Fail("no symmetry on an object with tags (a tag shows every turn of the object)");
    obj.symmetry_axis_O = axis.normalized();
    if (sym.Has("point")) obj.symmetry_point_O = sym["point"].Vector3();
  }

  ContactFieldOptions field;
  if (root.Has("contact_field")) {
    const jsonf::Field c = root["contact_field"];
    c.ExpectKeys({"source", "spacing", "padding"});
    if (c.Has("source")) field.source = c["source"].String();
    if (c.Has("spacing")) field.params.spacing = c["spacing"].PositiveNumber();
    if (c.Has("padding")) field.params.padding = c["padding"].NonNegativeNumber();
    field.Validate(c.Where());
  }
  AttachContactField(obj, field_override ? *field_override : field, path);
  return obj;
}

}  // namespace

// A single-link URDF (YCB style): the root link's geometry and <inertial>.
ObjectModel LoadObjectUrdf(const std::string& path, const PackageMap& packages,
                           const ContactFieldOptions& field) {
  HandLoadOptions options;
  options.packages = packages;
  options.collision_mesh_components = true;
  HandModel as_hand = LoadHandModel(path, options);
  const Link& link = as_hand.links[static_cast<std::size_t>(as_hand.root_link)];
  ObjectModel obj;
  obj.name = as_hand.name;
  obj.source = path;
  obj.mesh_files = as_hand.mesh_files;
  obj.visual = link.visual;
  // "components of textured_vhacd.stl" (a stored decomposition), or the primitives' kinds.
  std::vector<std::string> parts;
  for (const ConvexPiece& p : link.collision) {
    const std::size_t cut = p.source.find(" (component ");
    const std::string part =
        cut != std::string::npos
            ? "components of " + fs::path(p.source.substr(0, cut)).filename().string()
            : std::string(ConvexPiece::KindName(p.kind));
    if (std::find(parts.begin(), parts.end(), part) == parts.end()) parts.push_back(part);
  }
  for (const std::string& part : parts)
    obj.decomposition += (obj.decomposition.empty() ? "" : ", ") + part;
  obj.decomposition += " (URDF collision)";
  obj.pieces = link.collision;
  obj.mass = link.mass;
  if (!(obj.mass > 0.0)) throw InputError(path + ": object link has no <inertial> mass > 0");
  std::vector<TriangleMesh> piece_meshes;
  std::vector<const TriangleMesh*> solids;
  for (const ConvexPiece& p : obj.pieces) piece_meshes.push_back(p.ToMesh());
  for (const TriangleMesh& m : piece_meshes) solids.push_back(&m);
  const MassProperties mp = ComputeMassProperties(solids);
  if (mp.volume > 0.0) {
    obj.com_O = mp.com;
    obj.inertia_com = mp.inertia_com * (obj.mass / mp.volume);
  }
  AttachContactField(obj, field, path);
  return obj;
}

namespace {

ObjectModel Load(const std::string& path, const PackageMap& packages,
                 const ContactFieldOptions* field) {
  if (!fs::is_regular_file(path)) throw InputError(path + ": object description not found");
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".json") return LoadObjectJson(path, packages, field);
  if (ext == ".urdf") return LoadObjectUrdf(path, packages, field ? *field : ContactFieldOptions{});
  throw InputError(path + ": unknown object description format '" + ext +
                   "', expected .json (inhand object) or .urdf (single link)");
}

}  // namespace

ObjectModel LoadObjectModel(const std::string& path, const PackageMap& packages) {
  return Load(path, packages, nullptr);
}

ObjectModel LoadObjectModel(const std::string& path, const PackageMap& packages,
                            const ContactFieldOptions& field) {
  return Load(path, packages, &field);
}

}  // namespace inhand
