#include "inhand/io/urdf_loader.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <set>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/io/mesh_io.hpp"

namespace fs = std::filesystem;

namespace inhand {

void PackageMap::AddSpec(const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
    throw InputError("package map entry '" + spec + "': expected NAME=DIR");
  const std::string dir = spec.substr(eq + 1);
  if (!fs::is_directory(dir))
    throw InputError("package map entry '" + spec + "': '" + dir + "' is not a directory");
  dirs[spec.substr(0, eq)] = dir;
}

namespace {

constexpr int kMaxLinks = 1000;

std::string FindPackage(const std::string& name, const fs::path& referrer_dir,
                        const PackageMap& packages) {
  if (auto it = packages.dirs.find(name); it != packages.dirs.end()) return it->second;
  for (fs::path d = fs::absolute(referrer_dir); !d.empty(); d = d.parent_path()) {
    if (d.filename() == name) return d.string();
    if (fs::is_directory(d / name)) return (d / name).string();
    if (d == d.parent_path()) break;
  }
  if (const char* rpp = std::getenv("ROS_PACKAGE_PATH")) {
    std::stringstream ss(rpp);
    std::string entry;
    while (std::getline(ss, entry, ':'))
      if (!entry.empty() && fs::is_directory(fs::path(entry) / name))
        return (fs::path(entry) / name).string();
  }
  return "";
}

}  // namespace

std::string ResolveResource(const std::string& uri, const std::string& referrer,
                            const PackageMap& packages) {
  const fs::path referrer_dir = fs::path(referrer).parent_path();
  fs::path resolved;
  if (uri.rfind("package://", 0) == 0) {
    const std::string rest = uri.substr(10);
    const auto slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    const std::string root = FindPackage(name, referrer_dir, packages);
    if (root.empty())
      throw InputError(referrer + ": unknown package '" + name + "' in '" + uri +
                       "' (give it with --package " + name + "=DIR or a package map)");
    resolved = fs::path(root) / (slash == std::string::npos ? "" : rest.substr(slash + 1));
  } else if (uri.rfind("file://", 0) == 0) {
    resolved = uri.substr(7);
  } else {
    resolved = uri;
    if (resolved.is_relative()) resolved = referrer_dir / resolved;
  }
  if (!fs::exists(resolved))
    throw InputError(referrer + ": file '" + uri + "' not found (resolved to " + resolved.string() +
                     ")");
  return fs::weakly_canonical(resolved).string();
}

namespace {

// Collects urdfdom's console messages so they can be put into the exception.
class CaptureHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      if (!messages.empty()) messages += "; ";
      messages += text;
    }
  }
  std::string messages;
};

Transform ToTransform(const urdf::Pose& pose) {
  const Quat q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  return MakeTransform(Vec3(pose.position.x, pose.position.y, pose.position.z), q);
}

struct XmlFacts {
  std::vector<std::string> joint_order;  // document order
  std::map<std::string, int> joint_line;
};

// Well-formedness (with line), joint document order, and checks whose urdfdom messages would
// not say which joint or line is at fault.
XmlFacts InspectXml(const std::string& xml, const std::string& source) {
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) {
    throw InputError(source + ":" + std::to_string(doc.ErrorRow()) + ": malformed XML (" +
                     doc.ErrorDesc() + ")");
  }
  const TiXmlElement* robot = doc.RootElement();
  if (robot == nullptr || std::string(robot->Value()) != "robot")
    throw InputError(source + ": not a URDF: the root element is not <robot>");
  XmlFacts facts;
  // Sane limits: hands have tens of links; a 100,000-link chain took gigabytes and minutes.
  int links = 0;
  for (const TiXmlElement* l = robot->FirstChildElement("link"); l;
       l = l->NextSiblingElement("link"))
    if (++links > kMaxLinks)
      throw InputError(source + ":" + std::to_string(l->Row()) + ": more than " +
                       std::to_string(kMaxLinks) + " links; a hand has far fewer");
  std::map<std::string, int> parent_of;  // child link → line of the joint that moves it
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j;
       j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    const char* type = j->Attribute("type");
    const std::string where = source + ":" + std::to_string(j->Row());
    if (name == nullptr) throw InputError(where + ": <joint> without a name");
    if (type == nullptr)
      throw InputError(where + ": joint '" + std::string(name) + "' has no type");
    const std::string t = type;
    if (t == "floating" || t == "planar")
      throw InputError(where + ": joint '" + std::string(name) + "' has type '" + t +
                       "'; a hand supports revolute, continuous, prismatic and fixed joints");
    if ((t == "revolute" || t == "prismatic") && j->FirstChildElement("limit") == nullptr)
      throw InputError(where + ": " + t + " joint '" + std::string(name) +
                       "' has no <limit> (lower/upper/effort/velocity are required)");
    if (const TiXmlElement* child = j->FirstChildElement("child");
        child && child->Attribute("link")) {
      const std::string link = child->Attribute("link");
      if (parent_of.count(link))
        throw InputError(where + ": joint '" + std::string(name) + "' makes link '" + link +
                         "' the child of a second joint (the first at line " +
                         std::to_string(parent_of[link]) + "); a link has one parent joint");
      parent_of[link] = j->Row();
    }
    facts.joint_line[name] = j->Row();
    facts.joint_order.emplace_back(name);
  }
  return facts;
}

Material UrdfMaterial(const urdf::Visual& v) {
  Material m;
  if (v.material) {
    m.name = v.material->name;
    m.rgba = Eigen::Vector4d(v.material->color.r, v.material->color.g, v.material->color.b,
                             v.material->color.a);
  }
  return m;
}

// Primitive or mesh geometry as convex pieces in the link frame.
void AddCollisionGeometry(const urdf::Geometry& g, const Transform& T_LG, const std::string& where,
                          const std::string& urdf_path, const HandLoadOptions& options,
                          MeshCache& cache, std::vector<ConvexPiece>& out) {
  const auto positive = [&](const char* what, double v) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw InputError(where + ": " + what + " is " + std::to_string(v) +
                       ", expected a finite number > 0");
  };
  switch (g.type) {
    case urdf::Geometry::BOX: {
      const auto& b = static_cast<const urdf::Box&>(g);
      positive("box size x", b.dim.x), positive("box size y", b.dim.y),
          positive("box size z", b.dim.z);
      out.push_back(ConvexPiece::Box(0.5 * Vec3(b.dim.x, b.dim.y, b.dim.z), T_LG));
      break;
    }
    case urdf::Geometry::SPHERE:
      positive("sphere radius", static_cast<const urdf::Sphere&>(g).radius);
      out.push_back(ConvexPiece::Sphere(static_cast<const urdf::Sphere&>(g).radius, T_LG));
      break;
    case urdf::Geometry::CYLINDER: {
      const auto& c = static_cast<const urdf::Cylinder&>(g);
      positive("cylinder radius", c.radius), positive("cylinder length", c.length);
      out.push_back(ConvexPiece::Cylinder(c.radius, 0.5 * c.length, T_LG));
      break;
    }
    case urdf::Geometry::MESH: {
      const auto& m = static_cast<const urdf::Mesh&>(g);
      positive("mesh scale x", std::abs(m.scale.x)), positive("mesh scale y", std::abs(m.scale.y)),
          positive("mesh scale z", std::abs(m.scale.z));
      const std::string file = ResolveResource(m.filename, urdf_path, options.packages);
      const auto& meshes = cache.Get(
          file, Vec3(m.scale.x, m.scale.y, m.scale.z),
          options.collision_mesh_components ? MeshGrouping::kByPart : MeshGrouping::kByMaterial);
      if (options.collision_mesh_components) {
        for (ConvexPiece& piece : ComponentHulls(meshes, file)) {
          piece.Apply(T_LG);
          out.push_back(std::move(piece));
        }
        return;
      }
      std::vector<Vec3> points;
      for (const TriangleMesh& mesh : meshes)
        for (const Vec3& v : mesh.vertices) points.push_back(T_LG * v);
      out.push_back(ComputeConvexHull(points, file));
      break;
    }
  }
  out.back().source = out.back().source.empty() ? where : out.back().source;
}

// A cylinder with spheres of its radius on both end centres is a capsule: GJK gets an exact,
// cheaper shape. Removes the spheres and replaces the cylinder.
void MergeCapsules(std::vector<ConvexPiece>& pieces) {
  for (std::size_t c = 0; c < pieces.size(); ++c) {
    ConvexPiece& cyl = pieces[c];
    if (cyl.kind != ConvexPiece::Kind::kCylinder) continue;
    const Vec3 ends[2] = {cyl.T_BS * Vec3(0, 0, -cyl.half_length),
                          cyl.T_BS * Vec3(0, 0, cyl.half_length)};
    int found[2] = {-1, -1};
    for (std::size_t s = 0; s < pieces.size(); ++s) {
      const ConvexPiece& sph = pieces[s];
      if (sph.kind != ConvexPiece::Kind::kSphere || std::abs(sph.radius - cyl.radius) > 1e-9)
        continue;
      for (int e = 0; e < 2; ++e)
        if (found[e] < 0 && (sph.T_BS.translation() - ends[e]).norm() < 1e-9)
          found[e] = static_cast<int>(s);
    }
    if (found[0] < 0 || found[1] < 0 || found[0] == found[1]) continue;
    const std::string source = cyl.source;
    cyl = ConvexPiece::Capsule(cyl.radius, cyl.half_length, cyl.T_BS);
    cyl.source = source + " (capsule)";
    const int hi = std::max(found[0], found[1]), lo = std::min(found[0], found[1]);
    pieces.erase(pieces.begin() + hi);
    pieces.erase(pieces.begin() + lo);
    c = static_cast<std::size_t>(-1);  // restart: indices moved
  }
}

}  // namespace

HandModel ParseHandModel(const std::string& urdf_xml, const std::string& base_dir,
                         const std::string& source, const HandLoadOptions& options) {
  const XmlFacts facts = InspectXml(urdf_xml, source);

  urdf::ModelInterfaceSharedPtr urdf;
  {
    static std::mutex console_mutex;  // console_bridge's handler is process-global
    std::lock_guard<std::mutex> lock(console_mutex);
    CaptureHandler capture;
    console_bridge::useOutputHandler(&capture);
    urdf = urdf::parseURDF(urdf_xml);
    console_bridge::restorePreviousOutputHandler();
    if (!urdf)
      throw InputError(
          source + ": invalid URDF (" +
          (capture.messages.empty() ? std::string("urdfdom gave no reason") : capture.messages) +
          ")");
  }
  // Paths inside resolve against the URDF's folder: ResolveResource takes the referrer file.
  const std::string referrer = (fs::path(base_dir) / fs::path(source).filename()).string();

  HandModel model;
  model.name = urdf->getName();
  model.source = source;

  // Links in a depth-first order from the root, children by the joints' document order.
  std::map<std::string, int> doc_index;
  for (std::size_t i = 0; i < facts.joint_order.size(); ++i)
    doc_index[facts.joint_order[i]] = static_cast<int>(i);
  const urdf::LinkConstSharedPtr root = urdf->getRoot();
  std::map<std::string, int> link_index;
  std::vector<urdf::LinkConstSharedPtr> link_order;
  std::vector<urdf::JointConstSharedPtr> joint_order;  // topological
  // Iterative (a long chain must not exhaust the stack): each stack entry is a joint whose child
  // link comes next, pushed in reverse document order so that they pop in document order.
  const auto visit = [&](const urdf::LinkConstSharedPtr& l,
                         std::vector<urdf::JointConstSharedPtr>& stack) {
    link_index[l->name] = static_cast<int>(link_order.size());
    link_order.push_back(l);
    std::vector<urdf::JointConstSharedPtr> children(l->child_joints.begin(), l->child_joints.end());
    std::sort(children.begin(), children.end(), [&](const auto& a, const auto& b) {
      return doc_index[a->name] > doc_index[b->name];
    });
    stack.insert(stack.end(), children.begin(), children.end());
  };
  std::vector<urdf::JointConstSharedPtr> stack;
  visit(root, stack);
  while (!stack.empty()) {
    const urdf::JointConstSharedPtr j = stack.back();
    stack.pop_back();
    joint_order.push_back(j);
    visit(urdf->getLink(j->child_link_name), stack);
  }
  model.root_link = 0;

  MeshCache cache;
  for (const auto& ul : link_order) {
    auto note_mesh = [&](const urdf::GeometrySharedPtr& g) {
      if (!g || g->type != urdf::Geometry::MESH) return;
      const std::string file =
          ResolveResource(static_cast<const urdf::Mesh&>(*g).filename, referrer, options.packages);
      if (std::find(model.mesh_files.begin(), model.mesh_files.end(), file) ==
          model.mesh_files.end())
        model.mesh_files.push_back(file);
    };
    for (const auto& v : ul->visual_array)
      if (v) note_mesh(v->geometry);
    for (const auto& c : ul->collision_array)
      if (c) note_mesh(c->geometry);
    Link link;
    link.name = ul->name;
    if (ul->inertial) link.mass = ul->inertial->mass;
    const std::string where = source + ": link '" + ul->name + "'";
    for (const auto& c : ul->collision_array) {
      if (!c || !c->geometry) continue;
      AddCollisionGeometry(*c->geometry, ToTransform(c->origin), where, referrer, options, cache,
                           link.collision);
    }
    MergeCapsules(link.collision);
    for (const auto& v : ul->visual_array) {
      if (!v || !v->geometry) continue;
      const Transform T_LV = ToTransform(v->origin);
      const Material urdf_material = UrdfMaterial(*v);
      if (v->geometry->type == urdf::Geometry::MESH) {
        const auto& m = static_cast<const urdf::Mesh&>(*v->geometry);
        const std::string file = ResolveResource(m.filename, referrer, options.packages);
        if (!options.load_visual_meshes) continue;
        for (TriangleMesh mesh : cache.Get(file, Vec3(m.scale.x, m.scale.y, m.scale.z))) {
          mesh.Apply(T_LV);
          // A colour given in the URDF wins over the file's, a texture in the file wins over both.
          if (v->material && !mesh.material.HasTexture()) mesh.material = urdf_material;
          link.visual.push_back(std::move(mesh));
        }
      } else {
        std::vector<ConvexPiece> prim;
        AddCollisionGeometry(*v->geometry, T_LV, where, referrer, options, cache, prim);
        TriangleMesh mesh = prim.front().ToMesh();
        mesh.material = urdf_material;
        link.visual.push_back(std::move(mesh));
      }
    }
    // Fallbacks: each geometry stands in for the other when missing.
    if (link.visual.empty() && !link.collision.empty() && options.load_visual_meshes) {
      for (const ConvexPiece& p : link.collision) link.visual.push_back(p.ToMesh());
      link.visual_from_collision = true;
    }
    if (link.collision.empty() && !ul->visual_array.empty() && options.load_visual_meshes) {
      std::vector<Vec3> points;
      for (const TriangleMesh& m : link.visual)
        points.insert(points.end(), m.vertices.begin(), m.vertices.end());
      if (points.size() >= 4) {
        link.collision.push_back(ComputeConvexHull(points, where + " (hull of visual)"));
        link.collision_from_visual = true;
      }
    }
    model.links.push_back(std::move(link));
  }

  std::map<std::string, int> joint_index;
  for (const auto& uj : joint_order) {
    Joint joint;
    joint.name = uj->name;
    joint.parent_link = link_index.at(uj->parent_link_name);
    joint.child_link = link_index.at(uj->child_link_name);
    joint.T_LJ = ToTransform(uj->parent_to_joint_origin_transform);
    const std::string where =
        source + ":" +
        std::to_string(facts.joint_line.count(uj->name) ? facts.joint_line.at(uj->name) : 0) +
        ": joint '" + uj->name + "'";
    switch (uj->type) {
      case urdf::Joint::REVOLUTE:
        joint.type = JointType::kRevolute;
        break;
      case urdf::Joint::CONTINUOUS:
        joint.type = JointType::kContinuous;
        break;
      case urdf::Joint::PRISMATIC:
        joint.type = JointType::kPrismatic;
        break;
      case urdf::Joint::FIXED:
        joint.type = JointType::kFixed;
        break;
      default:
        throw InputError(where + ": unsupported joint type");
    }
    if (joint.moves()) {
      const Vec3 axis(uj->axis.x, uj->axis.y, uj->axis.z);
      if (!(axis.norm() > 1e-12) || !axis.allFinite())
        throw InputError(where + ": axis (" + std::to_string(axis.x()) + " " +
                         std::to_string(axis.y()) + " " + std::to_string(axis.z()) +
                         ") has no direction");
      joint.axis = axis.normalized();  // urdfdom does not normalise
    }
    if (uj->limits && joint.type != JointType::kContinuous && joint.moves()) {
      joint.has_limits = true;
      joint.lower = uj->limits->lower;
      joint.upper = uj->limits->upper;
      if (joint.lower > joint.upper)
        throw InputError(where + ": limit lower " + std::to_string(joint.lower) + " > upper " +
                         std::to_string(joint.upper));
    }
    if (uj->limits) {
      joint.effort_limit = uj->limits->effort;
      joint.velocity_limit = uj->limits->velocity;
    }
    if (uj->mimic && joint.moves()) {
      joint.is_mimic = true;
      joint.multiplier = uj->mimic->multiplier;
      joint.offset = uj->mimic->offset;
    }
    joint_index[joint.name] = static_cast<int>(model.joints.size());
    model.joints.push_back(joint);
    model.links[joint.child_link].parent_joint = static_cast<int>(model.joints.size()) - 1;
  }

  // Configuration vector: independent moving joints in document order.
  for (const std::string& name : facts.joint_order) {
    auto it = joint_index.find(name);
    if (it == joint_index.end()) continue;  // not connected to the root
    Joint& joint = model.joints[it->second];
    if (joint.moves() && !joint.is_mimic) {
      joint.q_index = model.num_q();
      model.q_joints.push_back(it->second);
    }
  }
  // Mimic joints follow their source's q entry; chains compose.
  for (Joint& joint : model.joints) {
    if (!joint.is_mimic) continue;
    const auto& uj = urdf->getJoint(joint.name);
    double multiplier = joint.multiplier, offset = joint.offset;
    std::string target = uj->mimic->joint_name;
    std::set<std::string> seen{joint.name};
    for (;;) {
      auto it = joint_index.find(target);
      if (it == joint_index.end())
        throw InputError(source + ": joint '" + joint.name + "' mimics unknown joint '" + target +
                         "'");
      if (!seen.insert(target).second)
        throw InputError(source + ": joint '" + joint.name + "' is part of a mimic cycle");
      const Joint& src = model.joints[it->second];
      if (!src.moves())
        throw InputError(source + ": joint '" + joint.name + "' mimics fixed joint '" + target +
                         "'");
      if (!src.is_mimic) {
        joint.q_index = src.q_index;
        break;
      }
      // value = m (m_s q + o_s) + o
      offset += multiplier * src.offset;
      multiplier *= src.multiplier;
      target = urdf->getJoint(target)->mimic->joint_name;
    }
    joint.multiplier = multiplier;
    joint.offset = offset;
  }

  model.support.resize(model.links.size());
  for (std::size_t l = 0; l < model.links.size(); ++l) {
    std::vector<int> chain;
    for (int j = model.links[l].parent_joint; j >= 0;
         j = model.links[model.joints[j].parent_link].parent_joint)
      if (model.joints[j].moves()) chain.push_back(j);
    model.support[l].assign(chain.rbegin(), chain.rend());
  }
  return model;
}

HandModel LoadHandModel(const std::string& urdf_path, const HandLoadOptions& options) {
  std::ifstream in(urdf_path, std::ios::binary);
  if (!fs::is_regular_file(urdf_path) || !in)
    throw InputError(urdf_path + ": cannot open URDF file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string base = fs::path(urdf_path).parent_path().string();
  return ParseHandModel(ss.str(), base.empty() ? "." : base, urdf_path, options);
}

}  // namespace inhand
