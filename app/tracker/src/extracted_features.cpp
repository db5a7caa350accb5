#include "extracted_features.hpp"

#include <cmath>

namespace inhand::tracker_detail {

ExtractedFeatures::ExtractedFeatures(const HandModel& hand, const ObjectModel& object, const FeatureParams& params)
    : hand_(hand), object_(object), params_(params) {
  params_.Validate();
}

ExtractedFeatures::~ExtractedFeatures() = default;

void ExtractedFeatures::Measure(const Image8& image, const Transform& T_PC, const Intrinsics& K, const Filter& f,
                                VisualStep& step, std::vector<VisualFeature>& out) {
  if (!renderer_) {
    renderer_ = std::make_unique<Renderer>();
    hand_meshes_ = UploadHand(*renderer_, hand_);
    object_meshes_ = UploadObject(*renderer_, object_, PrintedTagMeshes(object_));  // its appearance
  }
  step.has_features = true;
  // The virtual image: the scene as this filter believes it (hand at its biased joints).
  renderer_->Render(CameraScene(hand_meshes_, f.kinematics().link_poses(), object_meshes_, f.T_PO(), T_PC, K, Vec3(0.5, 0.5, 0.5)),
                    step.virtual_view, true);
  const std::vector<std::uint16_t>& label = step.virtual_view.label;
  object_mask_.resize(label.size());
  hand_mask_.resize(label.size());
  for (std::size_t i = 0; i < label.size(); ++i) {
    object_mask_[i] = label[i] == kObjectLabel;
    hand_mask_[i] = label[i] >= kHandLabelBase && label[i] < kExtraLabelBase;
  }
  step.match = MatchFeatures(image, step.virtual_view.colour, &object_mask_, params_, &hand_mask_, false);  // no debug-only camera corners
  // Inliers to object points through the virtual depth, moved into O with the estimate.
  const Transform T_OP = f.T_PO().inverse();
  out.clear();
  step.used_match.clear();
  for (std::size_t m = 0; m < step.match.matches.size(); ++m) {
    const FeatureMatch& match = step.match.matches[m];
    if (!match.inlier) continue;
    const int x = static_cast<int>(std::lround(match.virtual_px.x())), y = static_cast<int>(std::lround(match.virtual_px.y()));
    if (x < 0 || y < 0 || x >= K.width || y >= K.height || !object_mask_[std::size_t(y) * K.width + x]) continue;
    const float z = step.virtual_view.depth_at(x, y);
    if (!std::isfinite(z)) continue;
    const Vec3 X_P = T_PC * K.Unproject(match.virtual_px, z);
    out.push_back({match.id, T_OP * X_P, K.Undistort(match.real_px)});
    step.used_match.push_back(static_cast<int>(m));
  }
}

}  // namespace inhand::tracker_detail
