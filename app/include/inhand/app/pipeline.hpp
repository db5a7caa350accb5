#pragma once
// Per-frame orchestration shared by replay and the GUI (README, "The per-frame loop"): one
// filter per modality set over a session, stepped sample by sample, plus the pictures that
// explain each estimate (Fig.-1 overlays, the virtual view, an external 3-D view).
#include <memory>
#include <string>
#include <vector>

#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/features/extracted.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"
#include "inhand/sessions/session.hpp"

namespace inhand::app {

struct ModalitySet {
  std::string name;  // j, jt, jta, jtf
  bool torque = false;
  bool tags = false;
  bool features = false;
  Rgb colour;
};
// Filter parameters from a JSON file as `replay` writes it (params.json); InputError naming the
// file when it cannot be read or a field is wrong.
FilterParams ReadFilterParams(const std::string& path);
// Parses "j,jt,..."; throws InputError for unknown or not yet supported sets.
std::vector<ModalitySet> ParseModalities(const std::string& list);

struct EstimateRecord {
  double t = 0.0;
  Transform T_PO;
  Vec3 sigma_position = Vec3::Zero();     // [m]
  Vec3 sigma_orientation = Vec3::Zero();  // [rad]
  Eigen::VectorXd biases;
  double position_error = std::numeric_limits<double>::quiet_NaN();     // [m] when truth exists
  double orientation_error = std::numeric_limits<double>::quiet_NaN();  // [rad]
  // The same errors per axis of the true object frame (estimate − truth), so the degrees of
  // freedom the fingers leave unobservable (along and about a bottle's axis) can be read apart.
  Vec3 position_error_O = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());     // [m]
  Vec3 orientation_error_O = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // [rad], R_gtᵀ R̂ = Exp(·)
  double step_time_us = 0.0;
  int constraints = 0;
  int contacts = 0;
  int gated = 0;            // measurement blocks rejected by a gate in this sample
  double visual_mahalanobis = 0.0;  // mean over the features of the last visual update
  double nees = std::numeric_limits<double>::quiet_NaN();  // 6-D pose error against P, when truth exists
  double visual_ms = -1.0;  // last visual step (detection + update) when one ran at this sample
  int visual_used = 0;      // features used by it
};

class Pipeline {
 public:
  // `sets` empty: every set the session supports (jta only when the object carries tags, jta and
  // jtf only with camera images).
  Pipeline(Session& session, const FilterParams& params, std::vector<ModalitySet> sets = {});
  int num_samples() const { return session_.num_samples(); }
  // Runs every filter on joint sample k (k = 0 initialises them), then the visual updates of
  // the camera frames that arrived since the previous sample.
  void Step(int k);
  // The camera frame the last Step processed (-1: none) and its image.
  int last_frame() const { return state_.last_frame; }
  const Image8& last_image() const { return state_.image; }
  const std::vector<TagDetection>& last_tags() const { return state_.tags; }
  // The extracted-feature step of the last frame (sets with features): the virtual image, the
  // matches with every stage's output, and each used feature's pixel residual before and after
  // the update.
  struct FeatureStep {
    int frame = -1;
    RenderOutput virtual_view;
    MatchResult match;
    std::vector<int> used_match;      // index into match.matches of each feature used
    std::vector<double> residual_before, residual_after;  // [px]
  };
  const FeatureStep& last_feature_step() const { return state_.feature_step; }

 private:
  // Everything Step changes besides the filters.
  struct StepState {
    std::vector<EstimateRecord> last;
    std::size_t next_frame = 0;
    int last_frame = -1;
    Image8 image;
    std::vector<TagDetection> tags;
    std::vector<VisualFeature> features;
    FeatureStep feature_step;
  };

 public:
  // Restoring a checkpoint and stepping on gives bit-identical estimates to an uninterrupted
  // run (the contact query keeps no state between calls), so the GUI seeks back from the
  // nearest checkpoint instead of from the start.
  struct Checkpoint {
    std::vector<Filter> filters;
    StepState state;
  };
  Checkpoint Save() const;
  void Restore(const Checkpoint& c);
  FeatureParams& feature_params() { return feature_params_; }
  const std::vector<ModalitySet>& sets() const { return sets_; }
  const Filter& filter(std::size_t i) const { return *filters_[i]; }
  const EstimateRecord& last(std::size_t i) const { return state_.last[i]; }
  const Session& session() const { return session_; }
  const SessionModels& models() const { return models_; }
  const FilterParams& params() const { return params_; }

 private:
  Session& session_;
  SessionModels models_;
  FilterParams params_;
  std::vector<ModalitySet> sets_;
  std::vector<std::unique_ptr<BulletContactQuery>> queries_;
  std::vector<std::unique_ptr<Filter>> filters_;
  StepState state_;
  std::unique_ptr<TagDetector> tag_detector_;       // the whole frame, decimated
  std::unique_ptr<TagDetector> tag_detector_fine_;  // full resolution, around an expected tag
  std::unique_ptr<Renderer> renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  FeatureParams feature_params_;
  void FeatureUpdate(std::size_t set, int frame);
  void DetectTags(const Transform& T_PC, const Intrinsics& K);
};

// The annotated pictures of one camera frame: camera image with overlays | virtual view at the
// estimate of the last set | external 3-D view.
class FrameComposer {
 public:
  explicit FrameComposer(const Pipeline& pipeline);
  Image8 Compose(int camera_frame, double t, const OverlayLayers& layers = {});
  // The external 3-D view's orbit around the object (the GUI drags it).
  struct Orbit {
    double azimuth = -2.2;   // [rad]
    double elevation = 0.55; // [rad]
    double distance = 0.42;  // [m]
  } orbit;

 private:
  const Pipeline& p_;
  Renderer renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::unique_ptr<OverlayPainter> painter_;
};

}  // namespace inhand::app
