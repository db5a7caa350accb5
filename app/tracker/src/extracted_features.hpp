#pragma once
// Extracted features as visual measurements: the scene as the filter believes it is rendered
// from the camera (the virtual image), matched with the camera image (features/extracted.hpp:
// Canny → Harris → contour pieces → Hough → RANSAC), and each inlier's virtual pixel taken back
// to its point on the object through the virtual depth. The renderer is created on the thread
// that first measures (OpenGL contexts belong to one thread); used on that thread only.
#include <memory>
#include <vector>

#include "inhand/filter/filter.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::tracker_detail {

class ExtractedFeatures {
 public:
  ExtractedFeatures(const HandModel& hand, const ObjectModel& object, const FeatureParams& params);
  ~ExtractedFeatures();
  // Fills step.virtual_view, step.match, step.used_match and step.relocalized, and `out`.
  // Fused() must follow with the number of them the filter fused (not gated).
  void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K, const Filter& filter,
               VisualStep& step, std::vector<VisualFeature>& out);
  void Fused(int used);
  // What Measure carries from one frame to the next (VisualMemory), to save and to set back.
  bool matched_well() const { return matched_well_; }
  int poor_frames() const { return poor_frames_; }
  void Recall(bool matched_well, int poor_frames) { matched_well_ = matched_well, poor_frames_ = poor_frames; }

 private:
  const HandModel& hand_;
  const ObjectModel& object_;
  FeatureParams params_;
  Vec3 centre_O_;  // of the object's visual bounds, and half their diagonal (the search radius)
  double radius_;
  std::unique_ptr<Renderer> renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::vector<std::uint8_t> object_mask_, hand_mask_;
  // The inliers of `match` that lie on the object in `view`, as features (object point through
  // the virtual depth, measured pixel undistorted; on the outline, OnOutline, the point where
  // the line of sight grazes the surface), with their indices into match.matches.
  void Inliers(const MatchResult& match, const Transform& T_PC, const Intrinsics& K, const Filter& f,
               const RenderOutput& view, std::vector<int>& used, std::vector<VisualFeature>& out) const;
  static bool OnOutline(const RenderOutput& view, int x, int y);
  static constexpr int kOutlinePixels = 2;  // a corner this close to the background is on the outline
  static constexpr int kWellMatched = VisualMemory::kWellMatched;  // inliers on the object that
                                                                   // end the wide first search
  static constexpr int kLostFrames = VisualMemory::kLostFrames;    // frames in a row that fused
                                                                   // fewer: lost, searched for again
  bool matched_well_ = false;
  int poor_frames_ = 0;  // frames in a row that fused fewer than kWellMatched features
};

}  // namespace inhand::tracker_detail
