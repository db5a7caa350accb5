#pragma once
// Contact queries between the hand's links and the object (docs/estimator.md, "Contacts").
// The filter sees only this interface; estimator/contacts implements it with Bullet's GJK/EPA.
#include <vector>

#include "inhand/core/so3.hpp"

namespace inhand {

// The closest (or deepest) pair between one hand link and the object.
// Sign convention (as Drake's SignedDistancePair): distance > 0 apart, < 0 penetrating.
// When penetrating, c_f - c_o is the smallest displacement of the link that resolves it.
struct ContactPair {
  int link = -1;                  // hand link index
  int piece = -1;                 // object piece index; -1: the object as a whole (its field)
  double distance = 0.0;          // signed [m]
  Vec3 c_o_P = Vec3::Zero();      // witness point on the object, palm frame
  Vec3 c_f_P = Vec3::Zero();      // witness point on the link, palm frame
  Vec3 normal_P = Vec3::UnitZ();  // unit, from the link into the object (the direction in
                                  // which the link can push the object)
};

class ContactQuery {
 public:
  virtual ~ContactQuery() = default;
  // For every link with collision geometry whose closest pair to the object is nearer than
  // `max_distance` (penetrating pairs always qualify): that pair. `T_PL` holds every link's pose
  // (KinematicsData order); `out` is cleared first. Must not allocate once `out` has capacity
  // for one pair per link.
  virtual void Query(const std::vector<Transform>& T_PL, const Transform& T_PO, double max_distance,
                     std::vector<ContactPair>& out) = 0;
  // Counters since construction, for traces and benchmarks.
  struct Stats {
    long pairs_tested = 0;   // narrow-phase GJK runs
    long pairs_skipped = 0;  // rejected by the broad phase
  };
  virtual Stats stats() const = 0;
};

}  // namespace inhand
