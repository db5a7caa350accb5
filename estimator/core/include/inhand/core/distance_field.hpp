#pragma once
// A signed distance field of an object's closed surface, sampled on a regular grid in the object
// frame: what a link must be moved by to leave the object as a whole. A convex decomposition
// into many thin pieces cannot say that: a piece can only be penetrated as deep as it is thick,
// so the deepest per-piece pair under-reports the depth and points out of the piece, not out of
// the object.
//
// Sign convention as ContactPair: > 0 outside, < 0 inside. Values at the nodes are exact
// distances to the surface's triangles (a BVH query per node); between nodes the field is
// trilinear. Inside/outside comes from ray parity along the three axes (majority) for a closed
// mesh, from point-in-piece tests for a union of convex pieces.
#include <memory>
#include <string>
#include <vector>

#include "inhand/core/mesh.hpp"

namespace inhand {

struct DistanceFieldParams {
  double spacing = 1e-3;        // [m] grid step; grown if the grid would exceed max_nodes
  double padding = 0.025;       // [m] grid margin around the surface (beyond it: box distance)
  long max_nodes = 24'000'000;  // memory bound (4 bytes per node)
  void Validate(const std::string& where) const;
};

struct DistanceField {
  Vec3 origin = Vec3::Zero();                      // node (0, 0, 0), object frame
  double spacing = 0.0;                            // [m]
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();  // nodes per axis
  std::vector<float> values;                       // signed [m], x fastest, then y, then z
  std::string source;  // "closed visual mesh (16384 triangles)", "union of 66 pieces"

  bool empty() const { return values.empty(); }
  // Signed distance at `p_O`: trilinear inside the grid; outside it, the value at the nearest
  // grid point plus the distance to that point (a consistent over-estimate far away).
  double Distance(const Vec3& p_O) const;
  // The same and its gradient (central differences of the interpolant, step = spacing / 2),
  // normalised: the outward surface normal near the surface.
  double Distance(const Vec3& p_O, Vec3* unit_gradient) const;
};

// The field of a closed triangle soup (IsWatertightForParity, mesh.hpp), e.g. a scanned object's
// mesh.
DistanceField BuildDistanceFieldFromMesh(const std::vector<const TriangleMesh*>& meshes,
                                         const DistanceFieldParams& params);
// The field of the union of convex pieces (overlapping, touching or apart). Piece faces that lie
// inside the union (a cut between two pieces) are found by probing just outside them and are not
// surface.
DistanceField BuildDistanceFieldFromPieces(const std::vector<ConvexPiece>& pieces,
                                           const DistanceFieldParams& params);

// Where the line of sight from `eye` grazes the surface near `x`, a point on (or near) it that
// the eye sees: the outline of the object there. A point a little inside the outline (the depth
// of a pixel next to the background) walks over the surface away from the eye (the line of sight
// projected on the tangent plane, back onto the surface along the gradient), in steps of a
// quarter of the spacing, until the surface turns away from the eye, then bisects to where it
// grazes. A smooth body's outline is reached where its normal is perpendicular to the line of
// sight; a crease (a box's edge, a cap's rim) stops the walk on it. The walk keeps x's distance
// to the field's surface (a visual mesh a little off the pieces stays off them). Returns x
// itself when the surface there does not face the eye, when x is farther than 4 spacings from
// the surface, or when no grazing point lies within `max_travel` [m].
Vec3 GrazingPoint(const DistanceField& field, const Vec3& x, const Vec3& eye, double max_travel);

// Signed distance of `p` to one convex piece (exact for primitives and, inside, for hulls;
// outside a hull, exact through the closest point on its triangles). For tests and builders.
double PieceSignedDistance(const ConvexPiece& piece, const Vec3& p);

// Exact unsigned distance from `p` to triangle (a, b, c) and the closest point.
double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                             Vec3* closest = nullptr);

}  // namespace inhand
