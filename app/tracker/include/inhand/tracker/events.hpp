#pragma once
// What a tracker did and saw, as a stream of events (FORMAT.md, "events.csv"): contacts made and
// broken, the grip loosened, features lost and found, tags that see the object elsewhere,
// relocalizations, gated measurements in bursts, samples and images the tracker could not use,
// images fused late, health changes. The tracker produces them as it goes (Tracker::TakeEvents);
// a caller with ground truth adds its own (NEES beyond its bound). Each event is plain data; its
// words come from EventMessage.
#include <string>
#include <vector>

#include "inhand/core/hand_model.hpp"
#include "inhand/filter/filter.hpp"
#include "inhand/filter/health.hpp"

namespace inhand {

enum class EventKind {
  kContactMade,      // subject link; count 1: torque-confirmed, value [N] the force estimated at
                     // it; count 0: kinematic (a penetration removed), value [m] how deep
  kContactBroken,    // subject link; duration [s] the contact lasted
  kGripLoosened,     // the filter grew the object's random walk: the grip is too weak to hold it
                     // (again after it held for HealthParams::slip_hold)
  kFeaturesLost,     // the extracted features are lost (VisualMemory::features_lost)
  kFeaturesFound,    // they match again; value [m] how far the object was found from the estimate
                     // (0: where it was)
  kTagsElsewhere,    // the tags put the object where the estimate cannot be
  kRelocalized,      // the object was put where an image found it; value [m] how far
  kRecovered,        // the estimate left a pressing finger in the air and was moved to a pose
                     // that explains the hand and fits the image; value [m] how far
  kStartSettled,     // the start put a link deep inside the object and the estimate began from a
                     // pose on the palm's grasp side instead (HandPlausibility::SettleStart):
                     // subject that link, value [m] how far it was moved
  kShiftRefused,     // count whole-object shifts of the features' search that the hand refused
  kContactsGated,    // a burst: count contact updates gated over `duration`; subject the link
                     // gated most often; value the largest Mahalanobis distance
  kVisionGated,      // a burst of images whose gate refused more than half the features offered:
                     // count images over `duration`; value the largest share refused
  kSamplesDropped,   // a burst: count joint samples not later than the previous one
  kSamplesRejected,  // a burst: count joint samples no hand can produce; subject the first's
                     // joint (configuration index), value its position [rad] or torque [N m]
  kImageDropped,     // captured beyond the horizon or before the first sample (value: t_capture),
                     // or the worker was busy (subject 1)
  kImageRejected,    // empty, or with a time or camera pose that is not finite
  kImageLate,        // fused behind joint samples already fused: value [s] how late, count the
                     // samples re-applied after it
  kHealth,           // the health state changed to `health`
  kNeesBeyondBound,  // ground truth (callers only): the NEES left its χ²₆ 99 % bound (16.81);
                     // value the NEES
};
constexpr int kNumEventKinds = static_cast<int>(EventKind::kNeesBeyondBound) + 1;
// "contact_made", "contact_broken", "grip_loosened", "features_lost", "features_found",
// "tags_elsewhere", "relocalized", "recovered", "start_settled", "shift_refused", "contacts_gated",
// "vision_gated", "samples_dropped", "samples_rejected", "image_dropped", "image_rejected",
// "image_late", "health", "nees_beyond_bound".
const char* EventKindName(EventKind kind);

struct TrackerEvent {
  double t = 0.0;  // [s] when it happened (a burst: its first measurement; an image: its capture)
  EventKind kind = EventKind::kHealth;
  int subject = -1;       // a link or joint index (EventKind), -1: none
  double value = 0.0;     // per kind
  int count = 1;          // per kind
  double duration = 0.0;  // [s] bursts and broken contacts
  Health health;          // kHealth: the new state
  bool operator==(const TrackerEvent& o) const {
    return t == o.t && kind == o.kind && subject == o.subject && value == o.value &&
           count == o.count && duration == o.duration && health == o.health;
  }
};

// The subject in words: a link's or joint's name, the health state; "" when none.
std::string EventSubject(const TrackerEvent& event, const HandModel& hand);
// One line for people: "index_tip touches the object (torque-confirmed, 1.2 N)". Allocates.
std::string EventMessage(const TrackerEvent& event, const HandModel& hand);

// Turns what a tracker fuses into events. Plain data (a tracker's snapshot copies it); sized from
// the hand once, it allocates nothing per sample unless an event is emitted.
class EventDetector {
 public:
  // A contact is made (broken) when a link has had (lacked) an ungated kinematic or torque
  // contact for this long: a finger closing on the object touches and leaves it for a sample or
  // two, and a penetration removed by the update is gone at the next query.
  static constexpr double kContactHold = 0.05;  // [s]
  // Gated measurements, dropped and rejected samples closer than this in time form one burst.
  static constexpr double kBurstGap = 0.2;  // [s]

  EventDetector() = default;
  // `slip_hold` [s]: the grip loosens and firms from one sample to the next; it has loosened
  // again only after it has held this long (HealthParams::slip_hold).
  EventDetector(const HandModel& hand, double slip_hold);
  void Reset();

  // After the joint sample at t and the images fused at it: its trace and the health then.
  void OnSample(double t, const FilterTrace& trace, const Health& health,
                std::vector<TrackerEvent>& out);
  // The health decided again at t (after an image fused between samples).
  void OnHealth(double t, const Health& health, std::vector<TrackerEvent>& out);
  // What one fused image did (on the caller's thread, in the order fused).
  struct Image {
    ImageEvidence evidence;  // what the health monitor is told of it
    double newest_t = 0.0;   // [s] the newest joint sample when it was fused
    long replayed = 0;       // joint samples re-applied after it
    bool recovered = false;  // VisualStep::recovered
    int shifts_refused = 0;  // VisualStep::shifts_refused
  };
  void OnImage(const Image& image, std::vector<TrackerEvent>& out);
  // A joint sample dropped (not later than the previous) or rejected (joint `joint` = value).
  void OnSampleDropped(double t, std::vector<TrackerEvent>& out);
  void OnSampleRejected(double t, int joint, double value, std::vector<TrackerEvent>& out);
  // Emits the bursts still open (at the end of a recording).
  void Close(std::vector<TrackerEvent>& out);

 private:
  struct Burst {
    bool open = false;
    double t0 = 0.0, t_last = 0.0;
    int count = 0, subject = -1;
    double value = 0.0;
  };
  struct LinkContact {
    bool in = false;          // the contact, as last declared
    bool raw = false;         // this sample's
    bool pending = false;     // raw has differed from `in` since raw_since
    double raw_since = 0.0;   // [s]
    double declared_t = 0.0;  // [s] when it was last made
    bool torque = false;      // this sample's: torque-confirmed
    double force = 0.0;       // [N] this sample's largest (torque-confirmed)
    double depth = 0.0;       // [m] this sample's deepest penetration
    int gated = 0;            // this burst's gated updates
  };
  void Add(Burst& b, EventKind kind, double t, int subject, double value, int count,
           std::vector<TrackerEvent>& out);
  void CloseIfIdle(Burst& b, EventKind kind, double t, std::vector<TrackerEvent>& out);
  static void Emit(Burst& b, EventKind kind, std::vector<TrackerEvent>& out);

  std::vector<LinkContact> links_;
  double slip_hold_ = 0.25;
  double slipping_t_ = -1e300;  // [s] the last sample with the grip loosened
  Health health_;
  bool features_lost_ = false, tags_elsewhere_ = false;
  Burst contacts_gated_, vision_gated_, dropped_, rejected_;
};

}  // namespace inhand
