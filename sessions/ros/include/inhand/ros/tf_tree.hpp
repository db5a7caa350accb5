#pragma once
// The TF tree of a recording (/tf and /tf_static): each edge a static transform or a time
// series; transforms between any two frames at a time, composed along the tree, interpolated
// between the samples of each edge (linear in position, slerp in orientation).
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "inhand/ros/messages.hpp"

namespace inhand::ros {

class TfTree {
 public:
  // Adds the pose of `child` in `parent` at `stamp_ns` (static: valid at all times). A frame
  // with two parents keeps the first and counts the conflict.
  void Add(const StampedTransform& t, bool is_static);
  // Sorts the time series; call after the last Add (and, live, before a Lookup: a series that
  // is in order already costs one pass).
  void Finish();
  // A live tree's memory: drops the samples of every dynamic edge older than `before_ns`, but
  // keeps the newest of those (a lookup just after the cut still interpolates or holds).
  void Forget(std::int64_t before_ns);

  // The pose of `frame` in `base` at `t_ns`. Throws InputError when no chain joins them (naming
  // both parts of the tree), or when a dynamic edge on the chain has no sample within
  // `max_extrapolation_ns` of t (returns nullopt then if `soft`).
  std::optional<Pose> Lookup(const std::string& base, const std::string& frame, std::int64_t t_ns,
                             bool soft = false,
                             std::int64_t max_extrapolation_ns = 100000000) const;
  // Whether every dynamic edge on the chain from `base` to `frame` has a sample at or after
  // `t_ns`: a Lookup at t then interpolates rather than holding the newest sample. False when no
  // chain joins them.
  bool Covers(const std::string& base, const std::string& frame, std::int64_t t_ns) const;
  // Throws InputError naming both parts when no chain of edges joins `a` and `b`.
  void RequireConnected(const std::string& a, const std::string& b) const;

  // frame → parent, and whether the edge is static, for --list.
  struct EdgeInfo {
    std::string parent;
    bool is_static = false;
    std::size_t samples = 0;
  };
  std::map<std::string, EdgeInfo> Edges() const;
  int conflicts() const { return conflicts_; }
  bool empty() const { return edges_.empty(); }

 private:
  struct Edge {
    std::string parent;
    bool is_static = false;
    Pose fixed;
    std::vector<std::pair<std::int64_t, Pose>> series;
  };
  std::map<std::string, Edge> edges_;  // by child
  int conflicts_ = 0;
  std::set<std::string> Component(const std::string& frame) const;
  std::optional<Pose> EdgeAt(const std::string& child, const Edge& e, std::int64_t t_ns, bool soft,
                             std::int64_t max_ns) const;
  std::vector<std::string> ToRoot(const std::string& frame) const;
  // The chains from `base` and from `frame` up to their lowest common ancestor (each ends with
  // it); both end at their own roots when no chain joins them.
  std::pair<std::vector<std::string>, std::vector<std::string>> ChainsToCommonAncestor(
      const std::string& base, const std::string& frame) const;
};

}  // namespace inhand::ros
