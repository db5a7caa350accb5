#pragma once
// The online estimator a robot calls: one Tracker per modality set (joints, plus any of
// torques, AprilTags, extracted features) over the filter, the feature extractors and the
// renderer. Joint samples are fused at joint rate on the caller's thread; images are fused at
// their capture time, also when they arrive after later joint samples: the tracker keeps a
// checkpoint of the filter after every joint sample, goes back to the one before the capture
// time, applies the visual update there and re-applies the joint samples since.
//
//   Tracker tracker(hand, object, Modalities{true, false, true}, params, options);
//   tracker.Start(t0, T_PO_guess, StartSigmas{});
//   loop: tracker.AddJointSample(t, q, tau);              // q, tau in hand.q_joints order
//         tracker.AddImage(t_capture, image, T_PC, K);     // whenever a frame arrives
//         use tracker.T_PO(), tracker.covariance()
//
// Threaded: AddImage hands the frame to a worker that detects, renders and matches off the
// caller's thread, fuses it at its capture time into its own copy of the filter and re-applies
// the samples since; the caller adopts the result at its next AddJointSample, so the joint rate
// never waits for vision. Deterministic (threaded = false, the default): each image is
// processed on the caller's thread when it is added; replays are bit-stable. Both give the same
// estimates when images are added in capture order.
//
// Not thread-safe itself: call it from one thread. The hand and object must outlive it.
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/features/extracted.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/filter/health.hpp"
#include "inhand/renderer/renderer.hpp"
#include "inhand/tracker/events.hpp"
#include "inhand/tracker/tracker_params.hpp"

namespace inhand {

// Which measurements a tracker fuses besides the joint positions (always).
struct Modalities {
  bool torque = false;       // t: contacts confirmed by joint torques
  bool tags = false;         // a: AprilTag corners
  bool features = false;     // f: features extracted from the camera and the rendered image
  std::string Name() const;  // "j", "jt", "jta", "jtf", "ja", "jf", "jtaf", ...
  // "j" followed by any of t, a, f once each, in any order ("jat" is jta). Throws InputError
  // "CONTEXT: 'TEXT': ..." naming the letter at fault.
  static Modalities Parse(const std::string& text, const std::string& context);
};

struct TrackerOptions {
  bool threaded = false;       // vision on a worker thread (online use)
  double horizon = 0.5;        // [s] images captured longer ago than this before the newest
                               // joint sample are dropped (counted), never fused
  int history_samples = 2048;  // joint samples kept with their checkpoints (2 s at 1 kHz)
  int max_queued_images = 2;   // threaded: images waiting for the worker; when more arrive
                               // the oldest waiting one is dropped (counted)
};

struct TrackerStats {
  long samples = 0;           // joint samples fused
  long samples_dropped = 0;   // not later than the previous one, or before the start
  long samples_rejected = 0;  // no hand can produce them (ScreenJointSample)
  long images_added = 0;
  long images_fused = 0;
  long images_dropped_late = 0;   // captured beyond the horizon or before the first sample
  long images_dropped_busy = 0;   // threaded: the worker was behind
  long images_rejected = 0;       // empty, or with a time or camera pose that is not finite
  long rewinds = 0;               // images fused before joint samples already fused
  long samples_replayed = 0;      // joint samples re-applied after them
  long relocalizations = 0;       // images that found a lost object again (VisualStep::relocalized)
  long images_features_lost = 0;  // images after which the extracted features were lost
                                  // (VisualMemory::features_lost)
  long images_tags_elsewhere = 0;  // images whose tags put the object where the estimate cannot
                                   // be and that did not relocate it (yet; with relocation on)
  long recoveries = 0;  // of the relocalizations, images whose estimate did not explain the hand
                        // and that moved it to a pose that does (VisualStep::recovered)
  long shifts_refused = 0;  // whole-object shifts of the features' search that the hand refused
                            // (VisualStep::shifts_refused)
  double last_relocalization_t = 0.0;  // [s] the last one's capture time (when relocalizations > 0)
  double last_relocalized = 0.0;       // [m] and how far from the estimate it found the object
};

// What the last fused image showed and did, for overlays, the GUI and `inhand match`.
struct VisualStep {
  long sequence = 0;               // images fused so far (0: none yet)
  double t_capture = 0.0;          // [s]
  double ms = 0.0;                 // detection, rendering, matching and update(s) [ms]
  int offered = 0;                 // features given to the update(s)
  int used = 0;                    // of them, fused (not gated)
  double mean_mahalanobis = 0.0;   // over the offered features
  std::vector<TagDetection> tags;  // tag sets: the tags found
  // Feature sets: the virtual image at the estimate, the matches with every stage's output,
  // and for each feature offered to the update its match and pixel residual before and after.
  bool has_features = false;
  RenderOutput virtual_view;  // drawn within `region` only: the background elsewhere
  MatchResult match;
  PixelRect region;       // the pixels matched (and drawn): around the object, as far as its search
                          // reaches; empty: the whole image
  int search_radius = 0;  // [px] how far the object was searched (widened while
                          // uncertain; beyond FeatureParams::search_radius, match.debug
                          // has the global shift)
  double relocalized = 0.0;     // [m] the object, lost for frames, was found this far from
                                // the estimate. Extracted features: the σ added to its
                                // position before the update; tags: the fit of the tags'
                                // corners that the object was put at (VisualUpdate::relocate)
  bool recovered = false;       // extracted features with torques: the estimate left a finger
                                // that presses more than HealthParams::recover_gap away for
                                // recover_images images, and the object was put where it
                                // explains the hand and fits the image (relocalized: how far),
                                // nothing else fused
  int shifts_refused = 0;       // whole-object shifts the hand refused (HandPlausibility)
  double displacement = 0.0;    // [m] how far the image puts the object from the estimate: of
                                // the measurements offered (features or tag corners), the
                                // median of the pixel residual at the estimate before the
                                // update times the point's depth over the focal length (the
                                // larger of the sources' when both measure)
  std::vector<int> used_match;  // index into match.matches
  std::vector<double> residual_before, residual_after;  // [px]
};

// One visual update as fused: the measurements of one image (its tag corners, or its
// extracted features), kept so that an older image fused later can re-apply it after itself.
struct VisualUpdate {
  double t_capture = 0.0;
  double widen_position = 0.0;  // [m] σ added to the position before the update (relocalized)
  // Tags that disagreed with the estimate in TrackerParams::tag_relocate_images images in a row:
  // the object is put where their fit says (Filter::Relocate), and that fit is this image's
  // measurement (`features` stays empty: the same corners are not counted twice).
  bool relocate = false;
  Transform relocate_T_PO = Transform::Identity();
  Mat6 relocate_covariance = Mat6::Identity();
  std::vector<VisualFeature> features;
  Transform T_PC = Transform::Identity();
  Intrinsics K;

  // Features of the image captured at t_capture by a camera at T_PC, fused after the position's
  // σ is widened by `widen_position` (none: 0).
  static VisualUpdate Features(double t_capture, const Transform& T_PC, const Intrinsics& K,
                               double widen_position = 0.0,
                               std::vector<VisualFeature> features = {});
  // The object put at T_PO with `covariance` (Filter::Relocate).
  static VisualUpdate Relocation(double t_capture, const Transform& T_PO, const Mat6& covariance,
                                 const Transform& T_PC, const Intrinsics& K);
};

// One joint sample as the tracker keeps it: the sample, the filter's checkpoint after its
// contacts, and the visual updates fused after it.
struct TrackedSample {
  double t = 0.0, dt = 0.0;
  Eigen::VectorXd q, tau;
  FilterState after_sample;
  std::vector<VisualUpdate> fused;
};

// What the visual step carries from one image to the next; a snapshot must hold it, or a run
// continued from the snapshot measures its next images otherwise than the uninterrupted run.
struct VisualMemory {
  int tag_disagreements = 0;           // images in a row whose tags put the object where the
                                       // estimate cannot be (TrackerParams::tag_relocate_images)
  bool features_matched_well = false;  // a frame has matched well: the wide first search is over
  int features_poor_frames = 0;        // frames in a row since that fused few features
  int implausible_images = 0;          // images in a row whose estimate left a pressing finger
                                       // in the air (HealthParams::recover_images)
  // The features are lost after kLostFrames frames in a row that fused fewer than kWellMatched
  // features, once a frame had matched well; the object is then searched for as at the start.
  static constexpr int kWellMatched = 8;
  static constexpr int kLostFrames = 3;
  bool features_lost() const {
    return features_matched_well && features_poor_frames >= kLostFrames;
  }
  bool operator==(const VisualMemory& o) const {
    return tag_disagreements == o.tag_disagreements &&
           features_matched_well == o.features_matched_well &&
           features_poor_frames == o.features_poor_frames &&
           implausible_images == o.implausible_images;
  }
};
std::ostream& operator<<(std::ostream& os, const VisualMemory& m);

// A tracker's state at one joint sample, to continue from later (the GUI seeks with these).
struct TrackerSnapshot {
  bool started = false;
  double t = 0.0;
  TrackedSample last;  // the newest sample
  FilterState filter;  // after it and its visual updates
  VisualStep visual;
  VisualMemory memory;  // after its visual updates
  TrackerStats stats;
  HealthMonitor health;
  double next_press_t = 0.0;
  EventDetector events;  // the events not taken are not in it
};

class Tracker {
 public:
  Tracker(const HandModel& hand, const ObjectModel& object, const Modalities& modalities,
          const TrackerParams& params, const TrackerOptions& options = {});
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // The estimate to start from and its uncertainty; the first joint sample at or after t starts
  // the filter there (earlier samples are dropped). Starting again discards the history and what
  // the visual step remembered (the next image is searched for as the first was).
  void Start(double t, const Transform& T_PO, const StartSigmas& sigmas = {});
  // A joint sample: positions and external torques (zeros without torque sensing), in the
  // hand's configuration order. Samples not later than the previous one are dropped (counted).
  // Sets with torques on a hand with joint stiffness (HandModel::joint_stiffness) fuse the
  // link's position, q − τ / k: the encoder of an elastic joint reads the motor side.
  void AddJointSample(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& tau);
  // A camera image (RGB or grey) captured at t_capture by a camera at T_PC (palm frame) with
  // intrinsics K. Fused after the last joint sample at or before t_capture; an image captured
  // after the newest sample waits for the samples up to its time.
  void AddImage(double t_capture, const Image8& image, const Transform& T_PC, const Intrinsics& K);
  // Threaded: blocks until every image whose capture time the joint samples have reached is
  // fused or dropped, and adopts the result. Deterministic: returns at once.
  void WaitForImages();

  bool started() const;
  double t() const;  // [s] of the newest joint sample
  Transform T_PO() const;
  Eigen::MatrixXd covariance() const;  // of (δp, δθ, δb)
  const Eigen::VectorXd& biases() const;
  const Eigen::VectorXd& joints() const;  // the newest sample's positions as fused (undeflected,
                                          // clamped when asked); empty before the first
  const FilterTrace& trace() const;       // of the newest joint sample (and images fused at it)
  const Filter& filter() const;
  const VisualStep& last_visual() const;
  VisualMemory visual_memory() const;  // after last_visual()
  TrackerStats stats() const;
  // The estimate's health at the newest joint sample, from what the hand and the camera said up
  // to it (filter/health.hpp); HealthMessage(tracker.health(), hand) says it in words. Sets with
  // torques check every HealthParams::press_period that the fingers the torques say press are near
  // the estimated object; press_evidence() is that check's last finding.
  const Health& health() const;
  // The pose covariance (δp, δθ) the estimate claims: the filter's, widened by what its health
  // knows (ClaimedPoseCovariance: a pressing finger in the air or a link inside the object at
  // distance d adds d² to the position's variance on every axis, and the turn that moves the
  // object's points by d to the orientation's). What σ, NEES and the HUD report.
  Mat6 claimed_pose_covariance() const;
  const PressEvidence& press_evidence() const;
  const Modalities& modalities() const;
  const TrackerParams& params() const;
  // What the tracker did and saw since the last call (events.hpp), appended to `out` in the order
  // found: a burst, an image fused late or a contact (made once it has held) is found after
  // samples later than its time. Threaded: an image's events come with the sample that adopts it.
  void TakeEvents(std::vector<TrackerEvent>& out);
  // Ends the bursts still open (at the end of a recording); TakeEvents then returns them.
  void CloseEvents();

  TrackerSnapshot Save() const;
  // Continues from a snapshot of a tracker of the same models and parameters; the history
  // before it is gone (older images are dropped as late).
  void Restore(const TrackerSnapshot& snapshot);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inhand
