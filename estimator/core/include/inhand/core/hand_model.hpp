#pragma once
// The hand as the estimator sees it: a kinematic tree of links with visual meshes and convex
// collision pieces. Built once by io/ (LoadHandModel) and then only read (model/data split:
// per-configuration quantities live in kinematics/KinematicsData).
#include <string>
#include <vector>

#include "inhand/core/mesh.hpp"

namespace inhand {

enum class JointType { kRevolute, kContinuous, kPrismatic, kFixed };
const char* JointTypeName(JointType type);

struct Joint {
  std::string name;
  JointType type = JointType::kFixed;
  int parent_link = -1;
  int child_link = -1;
  Transform T_LJ = Transform::Identity();  // joint frame in the parent link frame (URDF origin)
  Vec3 axis = Vec3::UnitZ();               // unit, in the joint frame
  bool has_limits = false;
  double lower = 0.0;           // [rad] or [m]
  double upper = 0.0;           // [rad] or [m]
  double effort_limit = 0.0;    // [N m] or [N], 0 when unknown
  double velocity_limit = 0.0;  // [rad/s] or [m/s], 0 when unknown
  // Which entry of the configuration vector q drives this joint: its own (independent joint),
  // or its mimicked source's, as value = multiplier * q[q_index] + offset. -1 for fixed joints.
  int q_index = -1;
  bool is_mimic = false;
  double multiplier = 1.0;
  double offset = 0.0;
  bool moves() const { return type != JointType::kFixed; }
};

struct Link {
  std::string name;
  int parent_joint = -1;               // -1 for the root link
  std::vector<TriangleMesh> visual;    // in the link frame
  std::vector<ConvexPiece> collision;  // in the link frame
  bool visual_from_collision = false;  // fallbacks applied when an element was missing
  bool collision_from_visual = false;
  double mass = 0.0;  // [kg], from the URDF when given
};

struct HandModel {
  std::string name;
  std::string source;                   // the URDF file
  std::vector<std::string> mesh_files;  // every mesh file it uses, resolved, first use first
  std::vector<Link> links;
  std::vector<Joint> joints;  // topological order: a joint after its parent link's
  std::vector<int> q_joints;  // joint index of each q entry (independent joints,
                              // in the URDF's document order)
  int root_link = 0;          // the palm frame P is this link's frame
  // Per link: the moving joints from the root to the link (root first).
  std::vector<std::vector<int>> support;
  // Per configuration entry (q order): the joint's stiffness between motor and link [N m/rad],
  // 0 for a rigid joint; empty: every joint rigid. Not part of a URDF: a session's
  // hand.joint_stiffness, or the caller. A tendon-driven or series-elastic hand's encoder reads
  // the motor side, and under an external torque τ (sessions/FORMAT.md's sign) the link lags it:
  // q_link = q_recorded − τ / k. Estimates that use torques correct the joints by that.
  std::vector<double> joint_stiffness;

  int num_q() const { return static_cast<int>(q_joints.size()); }
  // The joint of configuration entry i (q order).
  const Joint& QJoint(int i) const {
    return joints[static_cast<std::size_t>(q_joints[static_cast<std::size_t>(i)])];
  }
  // -1 when absent.
  int LinkIndex(const std::string& link_name) const;
  int JointIndex(const std::string& joint_name) const;
  std::vector<std::string> QNames() const;
  std::size_t NumCollisionPieces() const;
  std::size_t NumVisualTriangles() const;
};

}  // namespace inhand
