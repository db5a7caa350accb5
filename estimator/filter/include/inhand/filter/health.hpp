#pragma once
// An estimate's health, judged without ground truth (docs/estimator.md, "Health"): is what the
// estimate claims consistent with what the hand and the camera say right now? Four states, the
// worst condition that holds deciding:
//   ok            nothing below holds;
//   uncertain     the estimate may be off by more than it can use, and says so: σ wide, the grip
//                 loosened, the object just found again, the features lost, images late or
//                 frozen, images that fuse too little of the object to check the estimate;
//   inconsistent  the measurements contradict the estimate: a link deep inside the object, a
//                 finger that the torques say presses while the object is far from it, vision
//                 whose features or tags the estimate cannot explain;
//   lost          inconsistent for longer than HealthParams::lost_after.
// The monitor is plain data (a tracker's snapshot copies it) and allocates nothing per sample.
#include <array>
#include <string>
#include <vector>

#include "inhand/core/contact.hpp"
#include "inhand/core/hand_model.hpp"
#include "inhand/filter/contact_model.hpp"
#include "inhand/filter/plausibility.hpp"

namespace inhand {

struct FilterTrace;

enum class HealthState { kOk = 0, kUncertain = 1, kInconsistent = 2, kLost = 3 };
const char* HealthStateName(HealthState state);  // "ok", "uncertain", "inconsistent", "lost"

// Why the state is what it is: the condition that decided it.
enum class HealthCause {
  kNone = 0,
  kWideSigma,        // value: the largest σ of the position [m] (subject 0) or of the
                     // orientation [rad] (subject 1)
  kSlipping,         // the grip loosened (FilterTrace::slipping): the object may slip
  kRelocalized,      // the object was found again, value [m] that far from the estimate
  kFeaturesLost,     // the extracted features are lost (VisualMemory::features_lost)
  kImagesStale,      // value: [s] since the newest image, images having arrived before
  kImagesFrozen,     // value: identical images in a row
  kVisionDisagrees,  // value: the share of the features offered over the last images that the
                     // estimate's gate refused
  kVisionBlind,      // value: the features or tag corners the last images fused, together:
                     // too few to check the estimate (HealthParams::vision_min_used)
  kTagsElsewhere,    // the tags put the object where the estimate cannot be
  kPenetration,      // value: [m] how deep link `subject` lies inside the estimated object
  kPressingInAir,    // value: [m] how far the estimated object is from the finger whose
                     // nearest link is `subject`, while its joint torques say it presses
};
// "none", "wide_sigma", "slipping", "relocalized", "features_lost", "images_stale",
// "images_frozen", "vision_disagrees", "vision_blind", "tags_elsewhere", "penetration",
// "pressing_in_air".
const char* HealthCauseName(HealthCause cause);

struct Health {
  HealthState state = HealthState::kOk;
  HealthCause cause = HealthCause::kNone;
  double value = 0.0;  // the cause's figure (HealthCause)
  int subject = -1;    // the cause's link, or -1
  double since = 0.0;  // [s] when the state began
  // [m] how far the evidence behind an inconsistent or lost state puts the object from the
  // estimate, for the causes that measure it: a pressing finger's gap, a link's depth (both the
  // value), the features' displacement when vision disagrees (ImageEvidence::displacement); 0
  // otherwise.
  double distance = 0.0;
  bool operator==(const Health& o) const {
    return state == o.state && cause == o.cause && value == o.value && subject == o.subject &&
           since == o.since && distance == o.distance;
  }
};
// One line for people: "inconsistent since 1.20 s: thumb_tip presses but the object is 23.1 mm
// from it". Allocates (the HUD, logs; not the joint-rate path).
std::string HealthMessage(const Health& health, const HandModel& hand);

// What an estimate may claim. A set that is inconsistent or lost because a finger the torques say
// presses is g from the estimated object, because a link lies d inside it, or because its gate
// refuses most of what the images measure, which lies v away at the object's depth, knows its
// estimate is about that far off; its claim must not be tighter. HealthPositionSigma is that
// distance [m] (Health::distance: g, d or v), 0 for every other state and cause.
// ClaimedPoseCovariance is the filter's pose covariance (δp, δθ) with that distance s added twice:
// s² to the position's variance along every axis, and, as a turn, s²/γᵢ about each principal axis
// of the object's gyration tensor Γ = Σ γᵢ eᵢeᵢᵀ (`gyration_O`, O axes; R_PO turns it into P),
// at most π²/3 (an angle no better known than uniform): a turn by θ about eᵢ moves the object's
// points by θ√γᵢ on average, so s is as much a turn as a shift. Γ zero (not known): the position
// only. What the tracker reports (σ, NEES, the HUD, exports). The filter's own covariance, and
// so every estimate, stays as it was.
double HealthPositionSigma(const Health& health);
Mat6 ClaimedPoseCovariance(const Mat6& P, const Health& health, const Mat3& R_PO,
                           const Mat3& gyration_O);

// Thresholds, with units; why each default is what it is in docs/evaluation.md ("Health").
struct HealthParams {
  double uncertain_position = 0.010;    // [m] σ of the position, any axis, beyond this: uncertain
  double uncertain_orientation = 0.35;  // [rad] σ of the orientation (20°), any axis
  double penetration = 0.005;           // [m] a link this deep inside the estimate ...
  double press_torque = 0.4;            // [N m] a finger presses when a joint of it carries this
  double press_gap = 0.010;             // [m] ... and is in the air when the object is this far
  double press_reach = 0.05;            // [m] how far the press check looks (farther: ≥ this)
  double press_period = 0.02;           // [s] the press check runs this often (it queries the
                                        // contacts wider than the filter's step does)
  double sustain = 0.1;                 // [s] penetration and a pressing finger in the air must
                                        // last this long to count (a finger closing on the
                                        // object goes through it for a step or two)
  int vision_window = 5;                // images whose gated share is judged together
  int vision_min_offered = 8;           // features offered over them, at least, to judge
  double vision_gated_share = 0.5;      // more than this share gated: vision disagrees
  int vision_min_used = 8;              // fewer fused over a full window: vision is blind, the
                                        // estimate unchecked by the images (0: never)
  double images_stale = 0.3;            // [s] without a new image once images came: uncertain
  int images_frozen = 3;                // identical images in a row: uncertain
  double relocalized_hold = 0.5;        // [s] uncertain after the object was found again
  double slip_hold = 0.25;              // [s] uncertain after the grip last loosened (it
                                        // loosens and firms from one sample to the next)
  double lost_after = 1.0;              // [s] inconsistent this long: lost
  // Recovery (sets with torques and extracted features; docs/estimator.md, "Plausibility and
  // recovery"): after recover_images images in a row that found a pressing finger more than
  // recover_gap from the estimated object, the object is searched for among poses that explain
  // the hand (0 images: never).
  int recover_images = 2;
  double recover_gap = 0.03;    // [m] (hard joint offsets leave a pressing finger 15-20 mm
                                // from an estimate that is 8 mm off)
  double recover_reach = 0.15;  // [m] how far from the object the recovery looks for fingers
  void Validate(const std::string& source = "health parameters") const;
};

// What one fused image said, for the monitor.
struct ImageEvidence {
  double t_capture = 0.0;
  int offered = 0;              // features or tag corners given to the update
  int used = 0;                 // of them, fused
  bool features_lost = false;   // VisualMemory::features_lost() after it
  bool tags_elsewhere = false;  // VisualMemory::tag_disagreements > 0 after it
  double relocalized = 0.0;     // [m] VisualStep::relocalized
  double displacement = 0.0;    // [m] VisualStep::displacement
};

// The press check's finding: of the fingers whose joint torques say they press, the one whose
// nearest link is farthest from the estimated object.
struct PressEvidence {
  bool pressing = false;  // some finger presses
  double gap = 0.0;       // [m] its nearest link's distance (<= 0: touching or inside)
  int link = -1;          // that link
  double torque = 0.0;    // [N m] its largest joint torque
};

// The press check over a hand's fingers (HandFingers). Allocates nothing per check once warmed
// up.
class PressCheck {
 public:
  explicit PressCheck(const HandModel& hand);
  // tau in the hand's configuration order; T_PL every link's pose at the estimate's joints;
  // `trace` the last step's contacts (a finger with a contact within them is not queried again);
  // `query` runs the wide query for the others.
  PressEvidence Measure(const Eigen::Ref<const Eigen::VectorXd>& tau,
                        const std::vector<Transform>& T_PL, const Transform& T_PO,
                        const FilterTrace& trace, ContactQuery& query, const HealthParams& params);
  int num_fingers() const { return fingers_.size(); }

 private:
  HandFingers fingers_;
  std::vector<double> torque_, gap_;  // per finger, this check
  std::vector<int> nearest_;          // per finger: its nearest link
  std::vector<ContactPair> pairs_;
};

// The health of one estimate over time. Fed on the estimate's own thread: every joint sample
// (OnSample), the press check when it ran (OnPress), every image added (OnImageAdded) and every
// fused one (OnImage).
class HealthMonitor {
 public:
  explicit HealthMonitor(const HealthParams& params = {});
  void Reset(double t);
  // After the sample at t: its trace and the pose's σ (position [m], orientation [rad]).
  void OnSample(double t, const FilterTrace& trace, const Vec3& sigma_position,
                const Vec3& sigma_orientation);
  void OnPress(double t, const PressEvidence& press);
  // An image arrived (captured at t_capture); `fingerprint` identifies its pixels.
  void OnImageAdded(double t_capture, unsigned long long fingerprint);
  void OnImage(const ImageEvidence& image);
  // Decides the state at t from what the calls above recorded (OnSample decides too).
  void Decide(double t);
  const Health& health() const { return health_; }
  const PressEvidence& press() const { return press_; }
  const HealthParams& params() const { return params_; }

 private:
  HealthParams params_;
  Health health_;
  // Conditions carried between calls.
  double penetration_since_ = -1.0, press_since_ = -1.0, inconsistent_since_ = -1.0;
  double penetration_ = 0.0;
  int penetration_link_ = -1;
  PressEvidence press_;
  double slipping_t_ = -1.0;  // the last sample with the grip loosened
  Vec3 sigma_position_ = Vec3::Zero(), sigma_orientation_ = Vec3::Zero();
  bool have_image_ = false;
  double last_image_t_ = 0.0;
  unsigned long long last_fingerprint_ = 0;
  int identical_images_ = 0;
  static constexpr int kMaxWindow = 32;
  std::array<int, kMaxWindow> offered_{}, used_{};
  std::array<double, kMaxWindow> displacement_{};
  int images_seen_ = 0;
  bool features_lost_ = false, tags_elsewhere_ = false;
  double relocalized_ = 0.0, relocalized_t_ = -1.0;
};

// A fingerprint of an image's bytes: 64-bit FNV-1a over about 65,000 of them, evenly spread (a
// camera's noise changes nearly every byte from one frame to the next; a frozen stream repeats
// them all). Equal for identical images; about 0.1 ms for 640×480 RGB.
unsigned long long ImageFingerprint(const unsigned char* data, std::size_t size);

}  // namespace inhand
