#pragma once
// ContactQuery with Bullet's GJK (btGjkPairDetector) and EPA (btGjkEpaPenetrationDepthSolver)
// in double precision. Shapes are built once from the models; a query only moves transforms.
// Exact shapes: spheres and capsules natively, boxes and hulls as convex hulls with a small
// margin that is subtracted again (docs/dependencies.md: EPA is unreliable on coplanar faces
// without margin), cylinders natively with a 0.1 mm rounding of their rims.
//
// An object with a distance field (ObjectModel::field: a scan's closed surface or the union of
// many pieces) is queried against the field instead: a link piece's depth is how far it is inside
// the object as a whole, not inside one fragment. Link spheres and capsules are exact through
// their centre / segment; boxes and hulls through surface samples 1.5 mm apart (on a surface
// curved with radius R the missed depth between samples is below (0.75 mm)^2 / 2R). The pair's
// piece is then -1 and its normal is the field's gradient.
#include <memory>

#include "inhand/core/contact.hpp"
#include "inhand/core/hand_model.hpp"
#include "inhand/core/object_model.hpp"

namespace inhand {

class BulletContactQuery final : public ContactQuery {
 public:
  BulletContactQuery(const HandModel& hand, const ObjectModel& object);
  ~BulletContactQuery() override;
  BulletContactQuery(const BulletContactQuery&) = delete;
  BulletContactQuery& operator=(const BulletContactQuery&) = delete;

  void Query(const std::vector<Transform>& T_PL, const Transform& T_PO, double max_distance,
             std::vector<ContactPair>& out) override;
  Stats stats() const override;

  // Exhaustive query without the broad phase: the oracle for tests.
  void QueryExhaustive(const std::vector<Transform>& T_PL, const Transform& T_PO,
                       double max_distance, std::vector<ContactPair>& out);
  // The signed distance of one (link piece, object piece) pair, for tests.
  ContactPair QueryPair(int link, int link_piece, int object_piece, const Transform& T_PL,
                        const Transform& T_PO);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inhand
