#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>

#include "inhand/app/commands.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand::app {

namespace {

using jsonf::Json;

Json PiecesJson(const std::vector<ConvexPiece>& pieces) {
  Json out = Json::array();
  for (const ConvexPiece& p : pieces)
    out.push_back({{"kind", ConvexPiece::KindName(p.kind)},
                   {"hull_vertices", p.hull_vertices.size()},
                   {"bounding_radius", p.bounding_radius},
                   {"source", p.source}});
  return out;
}

std::string KindsSummary(const std::vector<const ConvexPiece*>& pieces) {
  std::map<std::string, int> kinds;
  for (const ConvexPiece* p : pieces) ++kinds[ConvexPiece::KindName(p->kind)];
  std::string out;
  for (const auto& [k, n] : kinds) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + k;
  return out.empty() ? "none" : out;
}

int PrintHand(const HandModel& hand, bool as_json) {
  std::size_t triangles = hand.NumVisualTriangles();
  if (as_json) {
    Json joints = Json::array();
    for (int j : hand.q_joints) {
      const Joint& joint = hand.joints[j];
      joints.push_back({{"name", joint.name},
                        {"type", JointTypeName(joint.type)},
                        {"lower", joint.has_limits ? Json(joint.lower) : Json(nullptr)},
                        {"upper", joint.has_limits ? Json(joint.upper) : Json(nullptr)},
                        {"effort", joint.effort_limit},
                        {"velocity", joint.velocity_limit}});
    }
    Json mimic = Json::array();
    for (const Joint& joint : hand.joints)
      if (joint.is_mimic)
        mimic.push_back({{"name", joint.name},
                         {"follows", hand.joints[hand.q_joints[joint.q_index]].name},
                         {"multiplier", joint.multiplier},
                         {"offset", joint.offset}});
    Json links = Json::array();
    for (const Link& link : hand.links) {
      std::size_t tris = 0;
      for (const TriangleMesh& m : link.visual) tris += m.num_triangles();
      links.push_back(
          {{"name", link.name},
           {"parent_joint",
            link.parent_joint >= 0 ? Json(hand.joints[link.parent_joint].name) : Json(nullptr)},
           {"visual_triangles", tris},
           {"pieces", PiecesJson(link.collision)},
           {"visual_from_collision", link.visual_from_collision},
           {"collision_from_visual", link.collision_from_visual}});
    }
    Json out = {{"kind", "hand"},         {"name", hand.name},
                {"source", hand.source},  {"palm_link", hand.links[hand.root_link].name},
                {"joints", joints},       {"mimic_joints", mimic},
                {"links", links},         {"pieces", hand.NumCollisionPieces()},
                {"triangles", triangles}, {"mesh_files", hand.mesh_files}};
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::cout << "hand '" << hand.name << "' from " << hand.source << "\n"
            << "palm frame P = link '" << hand.links[hand.root_link].name << "'\n\n"
            << hand.num_q() << " joints (configuration order):\n";
  for (int i = 0; i < hand.num_q(); ++i) {
    const Joint& joint = hand.joints[hand.q_joints[i]];
    std::cout << "  " << std::setw(3) << i << "  " << std::left << std::setw(24) << joint.name
              << std::setw(11) << JointTypeName(joint.type) << std::right;
    if (joint.has_limits)
      std::cout << "[" << std::fixed << std::setprecision(3) << std::setw(7) << joint.lower << ", "
                << std::setw(7) << joint.upper << "]";
    else
      std::cout << "unlimited";
    std::cout << std::defaultfloat << "\n";
  }
  for (const Joint& joint : hand.joints)
    if (joint.is_mimic)
      std::cout << "  mimic " << joint.name << " = " << joint.multiplier << " * "
                << hand.joints[hand.q_joints[joint.q_index]].name << " + " << joint.offset << "\n";
  std::vector<const ConvexPiece*> all;
  std::cout << "\n" << hand.links.size() << " links (visual triangles, collision pieces):\n";
  for (const Link& link : hand.links) {
    std::size_t tris = 0;
    for (const TriangleMesh& m : link.visual) tris += m.num_triangles();
    std::vector<const ConvexPiece*> pieces;
    for (const ConvexPiece& p : link.collision) pieces.push_back(&p), all.push_back(&p);
    std::cout << "  " << std::left << std::setw(28) << link.name << std::right << std::setw(8)
              << tris << "  " << KindsSummary(pieces)
              << (link.visual_from_collision ? "  (visual from collision)" : "")
              << (link.collision_from_visual ? "  (collision from visual)" : "") << "\n";
  }
  std::cout << "\ntotal: " << triangles << " visual triangles, " << all.size() << " convex pieces ("
            << KindsSummary(all) << ")\n"
            << hand.mesh_files.size() << " mesh files:\n";
  for (const std::string& f : hand.mesh_files) std::cout << "  " << f << "\n";
  return 0;
}

// What `inhand model` says of an object's pieces, beside its visual mesh.
struct PieceSummary {
  double smallest = 0.0, largest = 0.0;  // [m] longest bounding-box edge of a piece
  double pieces_volume = 0.0;            // [m³] sum over pieces (overlaps counted twice)
  double mesh_volume = 0.0;              // [m³] of the visual meshes when they are closed, else 0
  bool mesh_closed = false;
};

PieceSummary SummarisePieces(const ObjectModel& obj) {
  PieceSummary s;
  s.smallest = std::numeric_limits<double>::infinity();
  for (const ConvexPiece& p : obj.pieces) {
    const TriangleMesh m = p.ToMesh();
    const double extent = m.Bounds().Size().maxCoeff();
    s.smallest = std::min(s.smallest, extent);
    s.largest = std::max(s.largest, extent);
    s.pieces_volume += ComputeMassProperties({&m}).volume;
  }
  std::vector<const TriangleMesh*> visual;
  for (const TriangleMesh& m : obj.visual) visual.push_back(&m);
  s.mesh_closed = IsWatertightForParity(visual);
  if (s.mesh_closed) s.mesh_volume = ComputeMassProperties(visual).volume;
  return s;
}

int PrintObject(const ObjectModel& obj, bool as_json) {
  const Aabb box = obj.Bounds();
  const PieceSummary ps = SummarisePieces(obj);
  const DistanceField* field = obj.field.get();
  if (as_json) {
    Json tags = Json::array();
    for (const TagPlacement& t : obj.tags)
      tags.push_back({{"family", t.family},
                      {"id", t.id},
                      {"size", t.size},
                      {"pose", jsonf::PoseToJson(t.T_OT)}});
    Json field_json = nullptr;
    if (field)
      field_json = {{"source", field->source},
                    {"spacing", field->spacing},
                    {"dims", {field->dims[0], field->dims[1], field->dims[2]}},
                    {"cache_file", obj.field_cache}};
    Json out = {
        {"kind", "object"},
        {"name", obj.name},
        {"source", obj.source},
        {"mass", obj.mass},
        {"com", {obj.com_O.x(), obj.com_O.y(), obj.com_O.z()}},
        {"inertia_diagonal", {obj.inertia_com(0, 0), obj.inertia_com(1, 1), obj.inertia_com(2, 2)}},
        {"size", {box.Size().x(), box.Size().y(), box.Size().z()}},
        {"pieces", obj.pieces.size()},
        {"piece_size_range", {ps.smallest, ps.largest}},
        {"pieces_volume", ps.pieces_volume},
        {"mesh_volume", ps.mesh_closed ? Json(ps.mesh_volume) : Json(nullptr)},
        {"piece_list", PiecesJson(obj.pieces)},
        {"decomposition", obj.decomposition},
        {"contact_field", field_json},
        {"triangles", obj.NumVisualTriangles()},
        {"mesh_files", obj.mesh_files},
        {"tags", tags},
        {"symmetry",
         obj.symmetry_axis_O.isZero()
             ? Json(nullptr)
             : Json{{"axis",
                     {obj.symmetry_axis_O.x(), obj.symmetry_axis_O.y(), obj.symmetry_axis_O.z()}},
                    {"point",
                     {obj.symmetry_point_O.x(), obj.symmetry_point_O.y(),
                      obj.symmetry_point_O.z()}}}}};
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::vector<const ConvexPiece*> pieces;
  for (const ConvexPiece& p : obj.pieces) pieces.push_back(&p);
  const Vec3 size = box.Size() * 1000.0;
  std::cout << "object '" << obj.name << "' from " << obj.source << "\n"
            << std::fixed << std::setprecision(1) << "size " << size.x() << " x " << size.y()
            << " x " << size.z() << " mm, mass " << std::setprecision(3) << obj.mass << " kg\n"
            << obj.NumVisualTriangles() << " visual triangles ("
            << (ps.mesh_closed ? "closed" : "not closed: no volume") << ")\n"
            << obj.pieces.size() << " convex pieces (" << KindsSummary(pieces) << "), from "
            << obj.decomposition << "\n"
            << std::setprecision(1) << "  piece size " << ps.smallest * 1e3 << " .. "
            << ps.largest * 1e3 << " mm; volume " << ps.pieces_volume * 1e6 << " cm3";
  if (ps.mesh_closed)
    std::cout << " against the mesh's " << ps.mesh_volume * 1e6 << " cm3 (" << std::setprecision(0)
              << 100.0 * ps.pieces_volume / ps.mesh_volume << " %)";
  std::cout << "\ncontacts: ";
  if (field)
    std::cout << "signed distance field of the " << field->source << ", " << std::setprecision(2)
              << field->spacing * 1e3 << " mm grid " << field->dims[0] << " x " << field->dims[1]
              << " x " << field->dims[2] << "\n  cache " << obj.field_cache;
  else
    std::cout << "GJK against each piece";
  std::cout << "\n" << obj.tags.size() << " AprilTags";
  for (const TagPlacement& t : obj.tags)
    std::cout << "\n  " << t.family << " id " << t.id << ", " << std::setprecision(1)
              << t.size * 1000.0 << " mm";
  if (!obj.symmetry_axis_O.isZero())
    std::cout << std::setprecision(3) << "\nlooks the same turned about the axis ("
              << obj.symmetry_axis_O.x() << ", " << obj.symmetry_axis_O.y() << ", "
              << obj.symmetry_axis_O.z() << ") through (" << obj.symmetry_point_O.x() << ", "
              << obj.symmetry_point_O.y() << ", " << obj.symmetry_point_O.z()
              << ") m: images measure no such turn";
  std::cout << std::defaultfloat << "\n" << obj.mesh_files.size() << " mesh files:\n";
  for (const std::string& f : obj.mesh_files) std::cout << "  " << f << "\n";
  return 0;
}

// The pieces as an object of their own, each piece in its own colour (golden-angle hues).
ObjectModel PiecesAsObject(const ObjectModel& obj) {
  ObjectModel out;
  out.name = obj.name + " pieces";
  for (std::size_t i = 0; i < obj.pieces.size(); ++i) {
    TriangleMesh m = obj.pieces[i].ToMesh();
    const double hue = std::fmod(i * 0.618033988749895, 1.0) * 6.0;
    const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
    const int sector = static_cast<int>(hue);
    const double rgb[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
    for (int c = 0; c < 3; ++c) m.material.rgba[c] = 0.25 + 0.7 * rgb[sector % 6][c];
    m.material.rgba[3] = 1.0;
    out.visual.push_back(std::move(m));
  }
  return out;
}

// Three views around the model's bounding box, side by side, with captions.
void RenderPreview(const std::string& path, const std::array<std::string, 3>& titles,
                   const std::function<void(Renderer&, Scene&, int view)>& populate,
                   const Aabb& box) {
  Renderer renderer;
  const double radius = std::max(0.5 * box.Size().norm(), 0.02);
  const double distance = 1.15 * radius / std::sin(20.0 * M_PI / 180.0);
  std::vector<Image8> views;
  const std::vector<std::pair<double, double>> angles = {
      {-0.5 * M_PI, 0.35}, {0.0, 0.35}, {0.6, 1.2}};
  for (const auto& [azimuth, elevation] : angles) {
    Scene scene;
    scene.K = IntrinsicsFromFov(480, 480, 40.0);
    scene.background = Vec3(0.86, 0.88, 0.91);
    populate(renderer, scene, static_cast<int>(views.size()));
    scene.T_PC = OrbitCamera(box.Center(), distance, azimuth, elevation);
    RenderOutput out;
    renderer.Render(scene, out, false);
    views.push_back(out.colour);
  }
  const Image8 all =
      SideBySide({&views[0], &views[1], &views[2]}, {titles[0], titles[1], titles[2]});
  WriteImage(path, all);
}

// An object when asked, when the file is an object JSON, or when a URDF has a single link and no
// joints (how YCB and most object datasets ship their models).
bool IsObjectFile(const ModelCommand& cmd, const PackageMap& packages) {
  if (cmd.object || std::filesystem::path(cmd.file).extension() == ".json") return true;
  HandLoadOptions probe;
  probe.packages = packages;
  probe.load_visual_meshes = false;
  const HandModel hand = LoadHandModel(cmd.file, probe);
  return hand.links.size() == 1 && hand.joints.empty();
}

}  // namespace

int RunModel(const ModelCommand& cmd) {
  PackageMap packages;
  for (const std::string& spec : cmd.packages) packages.AddSpec(spec);
  if (IsObjectFile(cmd, packages)) {
    const ObjectModel object = LoadObjectModel(cmd.file, packages);
    const int code = PrintObject(object, cmd.json);
    if (!cmd.render.empty()) {
      // The object as it looks, then its pieces in distinct colours from the side and above.
      const ObjectModel pieces = PiecesAsObject(object);
      std::vector<int> object_meshes, piece_meshes;
      RenderPreview(
          cmd.render,
          {object.name, std::to_string(object.pieces.size()) + " pieces, side", "pieces, above"},
          [&](Renderer& r, Scene& s, int view) {
            std::vector<int>& meshes = view == 0 ? object_meshes : piece_meshes;
            if (meshes.empty()) meshes = UploadObject(r, view == 0 ? object : pieces);
            AddObject(s, meshes, Transform::Identity());
          },
          object.Bounds());
    }
    return code;
  }
  HandLoadOptions options;
  options.packages = packages;
  const HandModel hand = LoadHandModel(cmd.file, options);
  const int code = PrintHand(hand, cmd.json);
  if (!cmd.render.empty()) {
    // Joints at a third of their range: a relaxed, slightly closed hand.
    Eigen::VectorXd q(hand.num_q());
    for (int i = 0; i < hand.num_q(); ++i) {
      const Joint& j = hand.joints[hand.q_joints[i]];
      q[i] = j.has_limits ? j.lower + (j.upper - j.lower) / 3.0 : 0.0;
      if (j.has_limits && j.lower <= 0.0 && j.upper >= 0.0 && j.upper - j.lower < 1.0)
        q[i] = 0.0;  // abduction-like
    }
    KinematicsData kin(hand);
    kin.Update(hand, q);
    Aabb box;
    for (std::size_t l = 0; l < hand.links.size(); ++l)
      for (const TriangleMesh& m : hand.links[l].visual)
        for (const Vec3& v : m.vertices) box.Extend(kin.T_PL(static_cast<int>(l)) * v);
    std::optional<HandMeshes> meshes;
    RenderPreview(
        cmd.render, {hand.name, "side", "above"},
        [&](Renderer& r, Scene& s, int) {
          if (!meshes) meshes = UploadHand(r, hand);
          AddHand(s, *meshes, kin.link_poses(), 1.0, true);
        },
        box);
  }
  return code;
}

}  // namespace inhand::app
