#include <filesystem>
#include <iomanip>
#include <iostream>
#include <functional>
#include <map>

#include "inhand/app/commands.hpp"
#include "inhand/io/detail/json_fields.hpp"
#include "inhand/io/object_loader.hpp"
#include "inhand/io/urdf_loader.hpp"
#include "inhand/kinematics/kinematics.hpp"
#include "inhand/renderer/image_io.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"

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
      links.push_back({{"name", link.name},
                       {"parent_joint", link.parent_joint >= 0 ? Json(hand.joints[link.parent_joint].name) : Json(nullptr)},
                       {"visual_triangles", tris},
                       {"pieces", PiecesJson(link.collision)},
                       {"visual_from_collision", link.visual_from_collision},
                       {"collision_from_visual", link.collision_from_visual}});
    }
    Json out = {{"kind", "hand"},
                {"name", hand.name},
                {"source", hand.source},
                {"palm_link", hand.links[hand.root_link].name},
                {"joints", joints},
                {"mimic_joints", mimic},
                {"links", links},
                {"pieces", hand.NumCollisionPieces()},
                {"triangles", triangles},
                {"mesh_files", hand.mesh_files}};
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
      std::cout << "[" << std::fixed << std::setprecision(3) << std::setw(7) << joint.lower
                << ", " << std::setw(7) << joint.upper << "]";
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
  std::cout << "\ntotal: " << triangles << " visual triangles, " << all.size()
            << " convex pieces (" << KindsSummary(all) << ")\n"
            << hand.mesh_files.size() << " mesh files:\n";
  for (const std::string& f : hand.mesh_files) std::cout << "  " << f << "\n";
  return 0;
}

int PrintObject(const ObjectModel& obj, bool as_json) {
  const Aabb box = obj.Bounds();
  if (as_json) {
    Json tags = Json::array();
    for (const TagPlacement& t : obj.tags)
      tags.push_back({{"family", t.family}, {"id", t.id}, {"size", t.size}, {"pose", jsonf::PoseToJson(t.T_OT)}});
    Json out = {{"kind", "object"},
                {"name", obj.name},
                {"source", obj.source},
                {"mass", obj.mass},
                {"com", {obj.com_O.x(), obj.com_O.y(), obj.com_O.z()}},
                {"inertia_diagonal", {obj.inertia_com(0, 0), obj.inertia_com(1, 1), obj.inertia_com(2, 2)}},
                {"size", {box.Size().x(), box.Size().y(), box.Size().z()}},
                {"pieces", obj.pieces.size()},
                {"piece_list", PiecesJson(obj.pieces)},
                {"decomposition", obj.decomposition},
                {"triangles", obj.NumVisualTriangles()},
                {"tags", tags}};
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::vector<const ConvexPiece*> pieces;
  for (const ConvexPiece& p : obj.pieces) pieces.push_back(&p);
  const Vec3 size = box.Size() * 1000.0;
  std::cout << "object '" << obj.name << "' from " << obj.source << "\n"
            << std::fixed << std::setprecision(1) << "size " << size.x() << " x " << size.y()
            << " x " << size.z() << " mm, mass " << std::setprecision(3) << obj.mass << " kg\n"
            << obj.NumVisualTriangles() << " visual triangles, " << obj.pieces.size()
            << " convex pieces (" << KindsSummary(pieces) << "; " << obj.decomposition << ")\n"
            << obj.tags.size() << " AprilTags";
  for (const TagPlacement& t : obj.tags)
    std::cout << "\n  " << t.family << " id " << t.id << ", " << t.size * 1000.0 << " mm";
  std::cout << std::defaultfloat << "\n";
  return 0;
}

// Three views around the model's bounding box, side by side, with captions.
void RenderPreview(const std::string& path, const std::string& title,
                   const std::function<void(Renderer&, Scene&)>& populate, const Aabb& box) {
  Renderer renderer;
  Scene scene;
  scene.K = IntrinsicsFromFov(480, 480, 40.0);
  scene.background = Vec3(0.86, 0.88, 0.91);
  populate(renderer, scene);
  const double radius = std::max(0.5 * box.Size().norm(), 0.02);
  const double distance = 1.15 * radius / std::sin(20.0 * M_PI / 180.0);
  std::vector<Image8> views;
  const std::vector<std::pair<double, double>> angles = {{-0.5 * M_PI, 0.35}, {0.0, 0.35}, {0.6, 1.2}};
  for (const auto& [azimuth, elevation] : angles) {
    scene.T_PC = OrbitCamera(box.Center(), distance, azimuth, elevation);
    RenderOutput out;
    renderer.Render(scene, out, false);
    views.push_back(out.colour);
  }
  const Image8 all = SideBySide({&views[0], &views[1], &views[2]}, {title, "side", "above"});
  WriteImage(path, all);
}

}  // namespace

int RunModel(const ModelCommand& cmd) {
  PackageMap packages;
  for (const std::string& spec : cmd.packages) packages.AddSpec(spec);
  if (std::filesystem::path(cmd.file).extension() == ".json") {
    const ObjectModel object = LoadObjectModel(cmd.file, packages);
    const int code = PrintObject(object, cmd.json);
    if (!cmd.render.empty())
      RenderPreview(cmd.render, object.name,
                    [&](Renderer& r, Scene& s) { AddObject(s, UploadObject(r, object), Transform::Identity()); },
                    object.Bounds());
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
      if (j.has_limits && j.lower <= 0.0 && j.upper >= 0.0 && j.upper - j.lower < 1.0) q[i] = 0.0;  // abduction-like
    }
    KinematicsData kin(hand);
    kin.Update(hand, q);
    Aabb box;
    for (std::size_t l = 0; l < hand.links.size(); ++l)
      for (const TriangleMesh& m : hand.links[l].visual)
        for (const Vec3& v : m.vertices) box.Extend(kin.T_PL(static_cast<int>(l)) * v);
    RenderPreview(cmd.render, hand.name,
                  [&](Renderer& r, Scene& s) { AddHand(s, UploadHand(r, hand), kin.link_poses()); }, box);
  }
  return code;
}

}  // namespace inhand::app
