#pragma once
// The annotated pictures of one camera frame (the paper's Fig. 1 and more): camera image with
// every set's overlays | virtual view at the estimate of the last set | external 3-D view. For
// sessions without a camera, the external 3-D view alone, with contacts and forces drawn in.
#include <memory>

#include "inhand/app/player.hpp"
#include "inhand/contacts/bullet_contact_query.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand::app {

// What the pictures show, copied from the player after a sample: they can then be drawn on
// another thread while the player goes on.
struct PictureState {
  double t = 0.0;
  int camera_frame = -1;
  Image8 camera;  // that frame's image
  struct Set {
    EstimateRecord record;
    Mat6 pose_covariance = Mat6::Zero();  // the filter's, over (δp, δθ)
    std::vector<FilterTrace::Contact> contacts;
    std::vector<FilterTrace::Visual> visual;
    double found_again = 0.0;  // [m] an image of the last second found the lost object this far
                               // from the estimate (TrackerStats::last_relocalized)
    std::string health;        // HealthMessage of record.health, empty when ok
  };
  std::vector<Set> sets;
  std::vector<Transform> link_poses;  // the hand as the last set believes it (biased joints)
  // The last set's virtual image of this frame when it matched features on it (rendered at its
  // estimate before the update): the middle panel, instead of rendering one more.
  Image8 matched_view;
};

// A set's HUD line: its name, the error against the truth (when there is one), the largest
// principal σ of its position and of its orientation (what the set claims: on a recording without
// ground truth, the only measure of how far to trust it), its constraints and what the tracker
// says beside the numbers (found again, not matched, tags elsewhere, grip loosened), then its
// health when not ok, in capitals when inconsistent or lost.
std::string HudLine(const std::string& name, const PictureState::Set& set);
// √ of the largest eigenvalue of a covariance block.
double LargestSigma(const Mat3& covariance);
// A set's part of the pictures at time t: `record` (what the set reported after its last sample)
// with its tracker's covariance, contacts, feature matches, a relocalization of the last second
// and the health in words.
PictureState::Set CaptureSet(const Tracker& tracker, const EstimateRecord& record, double t,
                             const HandModel& hand);
// A set's estimate as the camera overlay draws it: silhouette, position σ, contacts, matches; the
// contacts of `selected_link` and the visual measurement `selected_visual` (FilterTrace::Visual::
// id) marked selected (-1: none).
OverlayEstimate OverlayOf(const std::string& name, const Rgb& colour, const PictureState::Set& set,
                          int selected_link = -1, int selected_visual = -1);

class FrameComposer {
 public:
  // Draws with its own renderer, on the thread that calls it (one at a time).
  explicit FrameComposer(const SessionPlayer& player);
  // The player's state now, at time t, with camera frame `camera_frame` (-1: none); without its
  // image when `camera_image` is false (the caller reads it when it draws).
  static PictureState Capture(const SessionPlayer& player, int camera_frame, double t,
                              bool camera_image = true);
  Image8 Compose(const PictureState& state, const OverlayLayers& layers = {});
  Image8 Compose(int camera_frame, double t, const OverlayLayers& layers = {}) {
    return Compose(Capture(p_, camera_frame, t), layers);
  }
  // The external 3-D view (hand, every set's estimate, truth, contacts, forces and a HUD, with its
  // depth cues: each finger's gap to the last set's estimate and a small view from the side),
  // width x height pixels.
  Image8 ComposeExternal(const PictureState& state, int width = 960, int height = 720,
                         const OverlayLayers& layers = {});
  Image8 ComposeExternal(double t, int width = 960, int height = 720,
                         const OverlayLayers& layers = {}) {
    return ComposeExternal(Capture(p_, -1, t), width, height, layers);
  }
  // The depth cue the external view draws: each finger's gap to the last set's estimate, from
  // its link nearest to it within 50 mm (Bullet's GJK, as the filter's contacts); the palm's too.
  std::vector<OverlayGap> Gaps(const PictureState& state);
  // The external 3-D view's orbit around the object (the GUI drags it).
  struct Orbit {
    double azimuth = -2.2;    // [rad]
    double elevation = 0.55;  // [rad]
    double distance = 0.42;   // [m]
  } orbit;
  // What the GUI's inspector selected, ringed in every view: one set's contacts of a link or one
  // of its visual measurements (FilterTrace::Visual::id); -1: none.
  struct Selection {
    int set = -1;
    int link = -1;
    int visual = -1;
  } selection;
  // How Compose lays its three pictures out: in a row at the camera's height (the replay video,
  // like the paper's Fig. 1), or the camera at its own size with the virtual view and the 3-D view
  // stacked on its right at half its height (the GUI: the camera, the evidence, gets the largest
  // share).
  enum class Layout { kRow, kCameraLarge } layout = Layout::kRow;
  // Where the last picture drew its external 3-D view: the view's camera (palm frame), its
  // intrinsics, its rectangle in the picture [px] and the scale it was drawn at (valid: a picture
  // has been composed). The GUI maps a click on it back to the contact drawn there.
  struct ExternalView {
    bool valid = false;
    Transform T_PC = Transform::Identity();
    Intrinsics K;
    int x0 = 0, y0 = 0;
    int width = 0, height = 0;
    double scale = 1.0;
  };
  const ExternalView& last_external_view() const { return external_view_; }

 private:
  // Every set's estimate with its contacts, and the HUD lines, as the overlays take them.
  void AddEstimates(OverlayFrame* frame, const PictureState& state) const;
  // The 3-D scene around the palm: hand, truth dark, estimates translucent, seen through K from
  // the orbit.
  Scene ExternalScene(const PictureState& state, const Intrinsics& K, const Orbit& from) const;
  // The scene seen from the side (the orbit turned by 90°) in the lower right corner of the
  // external view.
  void AddSideView(const PictureState& state, Image8& view);
  const SessionPlayer& p_;
  Renderer renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::unique_ptr<OverlayPainter> painter_;
  BulletContactQuery query_;
  std::vector<ContactPair> pairs_;
  ExternalView external_view_;
};

}  // namespace inhand::app
