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
#include "visual_source.hpp"

namespace inhand::tracker_detail {

class ExtractedFeatures final : public VisualSource {
 public:
  ExtractedFeatures(const HandModel& hand, const ObjectModel& object, const FeatureParams& params);
  ~ExtractedFeatures() override;
  // Fills step.virtual_view, step.match, step.used_match, step.relocalized (also the update's
  // widening: the object found again that far away) and step.residual_before, and the update's
  // features.
  void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
               const Filter& filter, VisualStep& step, VisualUpdate& update) override;
  // Counts a poorly matched frame (fewer than kWellMatched fused); step.residual_after.
  void Fused(const Filter& filter, const VisualUpdate& update, int used, VisualStep& step) override;
  void Remember(VisualMemory& memory) const override;
  void Recall(const VisualMemory& memory) override;

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
  void Inliers(const MatchResult& match, const Transform& T_PC, const Intrinsics& K,
               const Filter& f, const RenderOutput& view, std::vector<int>& used,
               std::vector<VisualFeature>& out) const;
  static bool OnOutline(const RenderOutput& view, int x, int y);
  // [px] each feature's distance from where the filter's pose puts its point.
  static void Residuals(const Filter& f, const VisualUpdate& update, std::vector<double>& out);
  static constexpr int kOutlinePixels =
      2;  // a corner this close to the background is on the outline
  static constexpr int kWellMatched = VisualMemory::kWellMatched;  // inliers on the object that
                                                                   // end the wide first search
  static constexpr int kLostFrames = VisualMemory::kLostFrames;    // frames in a row that fused
                                                                 // fewer: lost, searched for again
  bool matched_well_ = false;
  int poor_frames_ = 0;  // frames in a row that fused fewer than kWellMatched features
};

}  // namespace inhand::tracker_detail
