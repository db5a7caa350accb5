#include <algorithm>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand {

const char* JointTypeName(JointType type) {
  switch (type) {
    case JointType::kRevolute:
      return "revolute";
    case JointType::kContinuous:
      return "continuous";
    case JointType::kPrismatic:
      return "prismatic";
    case JointType::kFixed:
      return "fixed";
  }
  return "?";
}

int HandModel::LinkIndex(const std::string& link_name) const {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == link_name) return static_cast<int>(i);
  return -1;
}

int HandModel::JointIndex(const std::string& joint_name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == joint_name) return static_cast<int>(i);
  return -1;
}

std::vector<std::string> HandModel::QNames() const {
  std::vector<std::string> names;
  for (int j : q_joints) names.push_back(joints[j].name);
  return names;
}

std::size_t HandModel::NumCollisionPieces() const {
  std::size_t n = 0;
  for (const Link& l : links) n += l.collision.size();
  return n;
}

std::size_t HandModel::NumVisualTriangles() const {
  std::size_t n = 0;
  for (const Link& l : links)
    for (const TriangleMesh& m : l.visual) n += m.num_triangles();
  return n;
}

std::array<Vec3, 4> TagPlacement::CornersO() const {
  const double h = 0.5 * size;
  return {T_OT * Vec3(-h, -h, 0.0), T_OT * Vec3(h, -h, 0.0), T_OT * Vec3(h, h, 0.0),
          T_OT * Vec3(-h, h, 0.0)};
}

std::size_t ObjectModel::NumVisualTriangles() const {
  std::size_t n = 0;
  for (const TriangleMesh& m : visual) n += m.num_triangles();
  return n;
}

Aabb ObjectModel::Bounds() const {
  Aabb box;
  for (const TriangleMesh& m : visual) box.Extend(m.Bounds());
  return box;
}

}  // namespace inhand
