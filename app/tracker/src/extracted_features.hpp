#pragma once
// Extracted features as visual measurements: the scene as the filter believes it is rendered
// from the camera (the virtual image), matched with the camera image (features/extracted.hpp:
// Canny → Harris → contour pieces → Hough → RANSAC), and each inlier's virtual pixel taken back
// to its point on the object through the virtual depth. The renderer is created on the thread
// that first measures (OpenGL contexts belong to one thread); used on that thread only.
#include <memory>
#include <vector>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/filter/plausibility.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/tracker/tracker.hpp"
#include "visual_source.hpp"

namespace inhand::tracker_detail {

class ExtractedFeatures final : public VisualSource {
 public:
  // `torque`: the set measures joint torques, so that the poses the step can jump to are scored
  // by the hand (HandPlausibility) and a pose that leaves pressing fingers in the air recovered.
  ExtractedFeatures(const HandModel& hand, const ObjectModel& object, const TrackerParams& params,
                    bool torque);
  ~ExtractedFeatures() override;
  // Fills step.virtual_view, step.match, step.used_match, step.relocalized (also the update's
  // widening: the object found again that far away) and step.residual_before, and the update's
  // features; or, recovering (step.recovered), the update's relocation.
  void Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K,
               const Eigen::VectorXd& tau, const Filter& filter, VisualStep& step,
               VisualUpdate& update) override;
  // Counts a poorly matched frame (fewer than kWellMatched fused); step.residual_after.
  void Fused(const Filter& filter, const VisualUpdate& update, int used, VisualStep& step) override;
  void Remember(VisualMemory& memory) const override;
  void Recall(const VisualMemory& memory) override;

 private:
  const HandModel& hand_;
  const ObjectModel& object_;
  FeatureParams params_;
  HealthParams health_;
  std::unique_ptr<BulletContactQuery> query_;       // sets with torques: for plausibility_
  std::unique_ptr<HandPlausibility> plausibility_;  // null without torques
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
  // Renders the scene with the object at T_PO (the hand at the filter's joints) into `view`,
  // within `region` (empty: the whole image), and the object's and the hand's masks from it.
  void RenderAt(const Filter& f, const Transform& T_PO, const Transform& T_PC, const Intrinsics& K,
                const PixelRect& region, RenderOutput& view);
  // The image of the object's bounds at T_PO (empty if it reaches behind the camera).
  Eigen::AlignedBox2d ImageBox(const Transform& T_PO, const Transform& T_PC,
                               const Intrinsics& K) const;
  // The pose of the object moved by a shift of `shift` px of its image at depth `depth`.
  static Transform Shifted(const Transform& T_PO, const Vec2& shift, double depth,
                           const Transform& T_PC, const Intrinsics& K);
  // Whether the hand admits the pose T_PO that a whole-object shift implies: it leaves no
  // pressing finger farther than recover_gap, or none farther than the estimate (`now`) does.
  bool AdmitsShift(const Eigen::VectorXd& tau, const Filter& f, const Transform& T_PO,
                   const Plausibility& now);
  // Recovery: poses that explain the hand (the estimate settled onto the pressing fingers, and
  // the object put between them and settled), the one that fits the image best among those the
  // hand admits. True when it relocates the update there.
  bool Recover(const Image8& image, const Transform& T_PC, const Intrinsics& K,
               const Eigen::VectorXd& tau, const Filter& f, VisualStep& step, VisualUpdate& update);
  // [px] each feature's distance from where the filter's pose puts its point.
  static void Residuals(const Filter& f, const VisualUpdate& update, std::vector<double>& out);
  static constexpr int kOutlinePixels =
      2;  // a corner this close to the background is on the outline
  static constexpr int kWellMatched = VisualMemory::kWellMatched;  // inliers on the object that
                                                                   // end the wide first search
  static constexpr int kLostFrames = VisualMemory::kLostFrames;    // frames in a row that fused
                                                                 // fewer: lost, searched for again
  bool matched_well_ = false;
  int poor_frames_ = 0;         // frames in a row that fused fewer than kWellMatched features
  int implausible_images_ = 0;  // images in a row with a pressing finger in the air
  RenderOutput hypothesis_view_;
};

}  // namespace inhand::tracker_detail
