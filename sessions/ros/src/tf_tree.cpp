#include "inhand/ros/tf_tree.hpp"

#include <algorithm>

#include "inhand/core/error.hpp"

namespace inhand::ros {

namespace {
std::string Strip(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}
}  // namespace

void TfTree::Add(const StampedTransform& t, bool is_static) {
  const std::string child = Strip(t.child_frame_id), parent = Strip(t.header.frame_id);
  if (child.empty() || parent.empty() || child == parent) return;
  auto [it, inserted] = edges_.try_emplace(child);
  Edge& e = it->second;
  if (inserted) e.parent = parent, e.is_static = is_static;
  if (e.parent != parent) {
    ++conflicts_;
    return;
  }
  if (is_static) {
    e.is_static = true;
    e.fixed = t.T;
  } else if (!e.is_static) {
    e.series.emplace_back(t.header.stamp_ns, t.T);
  }
}

void TfTree::Finish() {
  const auto earlier = [](const auto& a, const auto& b) { return a.first < b.first; };
  for (auto& [child, e] : edges_)
    if (!std::is_sorted(e.series.begin(), e.series.end(), earlier))
      std::stable_sort(e.series.begin(), e.series.end(), earlier);
}

void TfTree::Forget(std::int64_t before_ns) {
  for (auto& [child, e] : edges_) {
    const auto first_kept = std::lower_bound(
        e.series.begin(), e.series.end(), before_ns,
        [](const std::pair<std::int64_t, Pose>& a, std::int64_t t) { return a.first < t; });
    if (first_kept - e.series.begin() > 1) e.series.erase(e.series.begin(), first_kept - 1);
  }
}

std::map<std::string, TfTree::EdgeInfo> TfTree::Edges() const {
  std::map<std::string, EdgeInfo> out;
  for (const auto& [child, e] : edges_)
    out[child] = {e.parent, e.is_static, e.is_static ? 1 : e.series.size()};
  return out;
}

std::vector<std::string> TfTree::ToRoot(const std::string& frame) const {
  std::vector<std::string> chain{frame};
  for (auto it = edges_.find(frame); it != edges_.end() && chain.size() <= edges_.size();
       it = edges_.find(it->second.parent))
    chain.push_back(it->second.parent);
  return chain;
}

std::set<std::string> TfTree::Component(const std::string& frame) const {
  const std::vector<std::string> chain = ToRoot(frame);
  const std::string& root = chain.back();
  std::set<std::string> out{root};
  for (const auto& [child, e] : edges_)
    if (ToRoot(child).back() == root) out.insert(child);
  return out;
}

std::pair<std::vector<std::string>, std::vector<std::string>> TfTree::ChainsToCommonAncestor(
    const std::string& base, const std::string& frame) const {
  std::vector<std::string> a = ToRoot(base), b = ToRoot(frame);
  while (a.size() > 1 && b.size() > 1 && a[a.size() - 2] == b[b.size() - 2])
    a.pop_back(), b.pop_back();
  return {std::move(a), std::move(b)};
}

void TfTree::RequireConnected(const std::string& a_in, const std::string& b_in) const {
  const std::string a = Strip(a_in), b = Strip(b_in);
  if (a == b || ToRoot(a).back() == ToRoot(b).back()) return;
  const auto list = [](const std::set<std::string>& s) {
    std::string out;
    int n = 0;
    for (const auto& f : s) {
      if (n++ == 12) return out + ", ... (" + std::to_string(s.size()) + " frames)";
      out += (out.empty() ? "" : ", ") + f;
    }
    return out;
  };
  throw InputError("no TF path from '" + a + "' to '" + b + "': the tree is split into {" +
                   list(Component(a)) + "} and {" + list(Component(b)) + "}" +
                   (edges_.empty() ? " (the recording has no /tf or /tf_static)" : ""));
}

std::optional<Pose> TfTree::EdgeAt(const std::string& child, const Edge& e, std::int64_t t,
                                   bool soft, std::int64_t max_ns) const {
  if (e.is_static) return e.fixed;
  const auto& s = e.series;
  const auto fail = [&](std::int64_t gap) -> std::optional<Pose> {
    if (soft) return std::nullopt;
    throw InputError("TF " + e.parent + " -> " + child + " has no transform within " +
                     std::to_string(max_ns / 1000000) + " ms of t = " + std::to_string(t) +
                     " ns (nearest " + std::to_string(gap / 1000000) + " ms away)");
  };
  auto hi = std::lower_bound(s.begin(), s.end(), t,
                             [](const auto& a, std::int64_t v) { return a.first < v; });
  if (hi != s.end() && hi->first == t) return hi->second;  // exact: no arithmetic
  if (hi == s.begin())
    return s.front().first - t <= max_ns ? std::optional<Pose>(s.front().second)
                                         : fail(s.front().first - t);
  if (hi == s.end())
    return t - s.back().first <= max_ns ? std::optional<Pose>(s.back().second)
                                        : fail(t - s.back().first);
  const auto& lo = *(hi - 1);
  const double a = static_cast<double>(t - lo.first) / static_cast<double>(hi->first - lo.first);
  return Pose{(1 - a) * lo.second.p + a * hi->second.p, lo.second.q.slerp(a, hi->second.q)};
}

std::optional<Pose> TfTree::Lookup(const std::string& base_in, const std::string& frame_in,
                                   std::int64_t t_ns, bool soft, std::int64_t max_ns) const {
  const std::string base = Strip(base_in), frame = Strip(frame_in);
  if (base == frame) return Pose();
  RequireConnected(base, frame);
  // Up from each to the common ancestor: T_base_frame = (T_root_base)^-1 T_root_frame, with the
  // shared part of the chains cancelled.
  const auto [a, b] = ChainsToCommonAncestor(base, frame);
  // Pose of chain[0] in chain.back(); a chain of one frame is the identity (no arithmetic, so a
  // single edge comes out exactly as recorded).
  const auto up = [&](const std::vector<std::string>& chain) -> std::optional<Pose> {
    std::optional<Pose> T;
    for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
      const auto e = EdgeAt(chain[i], edges_.at(chain[i]), t_ns, soft, max_ns);
      if (!e) return std::nullopt;
      T = T ? *e * *T : *e;
    }
    return T ? T : Pose();
  };
  const auto Ta = up(a), Tb = up(b);
  if (!Ta || !Tb) return std::nullopt;
  if (a.size() == 1) return Tb;
  if (b.size() == 1) return Ta->Inverse();
  return Ta->Inverse() * *Tb;
}

bool TfTree::Covers(const std::string& base_in, const std::string& frame_in,
                    std::int64_t t_ns) const {
  const std::string base = Strip(base_in), frame = Strip(frame_in);
  if (base == frame) return true;
  const auto [a, b] = ChainsToCommonAncestor(base, frame);
  if (a.back() != b.back()) return false;  // no chain joins them
  for (const std::vector<std::string>* chain : {&a, &b})
    for (std::size_t i = 0; i + 1 < chain->size(); ++i) {
      const Edge& e = edges_.at((*chain)[i]);
      if (!e.is_static && (e.series.empty() || e.series.back().first < t_ns)) return false;
    }
  return true;
}

}  // namespace inhand::ros
