#pragma once
// The grasped object: rigid, of known geometry. Built once by io/ (LoadObjectModel).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "inhand/core/distance_field.hpp"
#include "inhand/core/mesh.hpp"

namespace inhand {

// An AprilTag glued to the object. Tag frame T: origin at the tag centre, z out of the
// surface (towards a camera that sees it), x to the right and y up as printed. `size` is the
// edge of the outer black border, whose corners are what detectors report.
struct TagPlacement {
  std::string family = "tag36h11";
  int id = 0;
  double size = 0.0;  // [m]
  Transform T_OT = Transform::Identity();
  // Outer corners in O, in the detector's order: bottom-left, bottom-right, top-right, top-left.
  std::array<Vec3, 4> CornersO() const;
};

struct ObjectModel {
  std::string name;
  std::string source;                   // description file
  std::vector<std::string> mesh_files;  // every mesh file it uses, resolved, first use first
  std::vector<TriangleMesh> visual;     // object frame O
  std::vector<ConvexPiece> pieces;      // object frame O, for contacts
  std::string decomposition;            // how pieces were obtained (for reports)
  // The signed distance field of the object as a whole (contacts against the union of the
  // pieces, not against one piece). Null when contacts use the pieces directly (one convex
  // piece is exact with GJK) or when the description turns it off.
  std::shared_ptr<const DistanceField> field;
  std::string field_cache;              // the file it was read from or written to, if any
  double mass = 0.0;                    // [kg]
  Vec3 com_O = Vec3::Zero();            // [m]
  Mat3 inertia_com = Mat3::Identity();  // [kg m²] about the centre of mass, O axes
  double friction = 0.8;                // Coulomb coefficient against the fingers
  std::vector<TagPlacement> tags;
  // A continuous symmetry of the object's appearance: turned about this axis (through
  // symmetry_point_O), the object looks the same, as a plain pen does about its own axis. No
  // image measures such a turn (docs/estimator.md, "Vision"). Zero axis: none declared.
  Vec3 symmetry_axis_O = Vec3::Zero();   // unit
  Vec3 symmetry_point_O = Vec3::Zero();  // [m]

  std::size_t NumVisualTriangles() const;
  Aabb Bounds() const;  // of the visual meshes
};

}  // namespace inhand
