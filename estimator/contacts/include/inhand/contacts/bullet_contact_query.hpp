#pragma once
// ContactQuery with Bullet's GJK (btGjkPairDetector) and EPA (btGjkEpaPenetrationDepthSolver)
// in double precision. Shapes are built once from the models; a query only moves transforms.
// Exact shapes: spheres and capsules natively, boxes and hulls as convex hulls with a small
// margin that is subtracted again (dependencies.md: EPA is unreliable on coplanar faces
// without margin), cylinders natively with a 0.1 mm rounding of their rims.
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
