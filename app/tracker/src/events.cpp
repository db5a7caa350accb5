#include "inhand/tracker/events.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace inhand {

const char* EventKindName(EventKind kind) {
  switch (kind) {
    case EventKind::kContactMade:
      return "contact_made";
    case EventKind::kContactBroken:
      return "contact_broken";
    case EventKind::kGripLoosened:
      return "grip_loosened";
    case EventKind::kFeaturesLost:
      return "features_lost";
    case EventKind::kFeaturesFound:
      return "features_found";
    case EventKind::kTagsElsewhere:
      return "tags_elsewhere";
    case EventKind::kRelocalized:
      return "relocalized";
    case EventKind::kRecovered:
      return "recovered";
    case EventKind::kStartSettled:
      return "start_settled";
    case EventKind::kShiftRefused:
      return "shift_refused";
    case EventKind::kContactsGated:
      return "contacts_gated";
    case EventKind::kVisionGated:
      return "vision_gated";
    case EventKind::kSamplesDropped:
      return "samples_dropped";
    case EventKind::kSamplesRejected:
      return "samples_rejected";
    case EventKind::kImageDropped:
      return "image_dropped";
    case EventKind::kImageRejected:
      return "image_rejected";
    case EventKind::kImageLate:
      return "image_late";
    case EventKind::kHealth:
      return "health";
    case EventKind::kNeesBeyondBound:
      return "nees_beyond_bound";
  }
  return "?";
}

namespace {

std::string LinkName(int link, const HandModel& hand) {
  return link >= 0 && link < static_cast<int>(hand.links.size())
             ? hand.links[static_cast<std::size_t>(link)].name
             : std::string("a link");
}

std::string JointName(int joint, const HandModel& hand) {
  return joint >= 0 && joint < static_cast<int>(hand.q_joints.size())
             ? hand.joints[static_cast<std::size_t>(hand.q_joints[static_cast<std::size_t>(joint)])]
                   .name
             : std::string("a joint");
}

bool HasLink(EventKind kind) {
  return kind == EventKind::kContactMade || kind == EventKind::kContactBroken ||
         kind == EventKind::kContactsGated || kind == EventKind::kStartSettled;
}

}  // namespace

std::string EventSubject(const TrackerEvent& e, const HandModel& hand) {
  if (e.kind == EventKind::kHealth) return HealthStateName(e.health.state);
  if (e.subject < 0) return "";
  if (HasLink(e.kind)) return LinkName(e.subject, hand);
  if (e.kind == EventKind::kSamplesRejected) return JointName(e.subject, hand);
  return std::to_string(e.subject);
}

std::string EventMessage(const TrackerEvent& e, const HandModel& hand) {
  char line[300];
  const std::string subject = EventSubject(e, hand);
  switch (e.kind) {
    case EventKind::kContactMade:
      if (e.count)
        std::snprintf(line, sizeof line, "%s touches the object (torque-confirmed, %.2f N)",
                      subject.c_str(), e.value);
      else
        std::snprintf(line, sizeof line, "%s touches the object (kinematic, %.2f mm deep)",
                      subject.c_str(), e.value * 1000);
      break;
    case EventKind::kContactBroken:
      std::snprintf(line, sizeof line, "%s leaves the object after %.2f s", subject.c_str(),
                    e.duration);
      break;
    case EventKind::kGripLoosened:
      std::snprintf(line, sizeof line, "the grip loosened: the object may slip");
      break;
    case EventKind::kFeaturesLost:
      std::snprintf(line, sizeof line, "the image features are lost");
      break;
    case EventKind::kFeaturesFound:
      if (e.value > 0.0)
        std::snprintf(line, sizeof line,
                      "the image features match again, the object %.1f mm from the estimate",
                      e.value * 1000);
      else
        std::snprintf(line, sizeof line, "the image features match again, near the estimate");
      break;
    case EventKind::kTagsElsewhere:
      std::snprintf(line, sizeof line, "the tags see the object where the estimate cannot be");
      break;
    case EventKind::kRelocalized:
      std::snprintf(line, sizeof line, "the object was found again %.1f mm from the estimate",
                    e.value * 1000);
      break;
    case EventKind::kRecovered:
      std::snprintf(line, sizeof line,
                    "the estimate left a pressing finger in the air; moved %.1f mm to where the "
                    "hand and the image agree",
                    e.value * 1000);
      break;
    case EventKind::kStartSettled:
      std::snprintf(line, sizeof line,
                    "the start put %s deep inside the object; began %.1f mm away, on the palm's "
                    "grasp side",
                    subject.c_str(), e.value * 1000);
      break;
    case EventKind::kShiftRefused:
      std::snprintf(line, sizeof line,
                    "%d whole-object shift(s) refused: they leave a pressing finger in the air",
                    e.count);
      break;
    case EventKind::kContactsGated:
      std::snprintf(line, sizeof line,
                    "%d contact update(s) gated over %.2f s, most at %s (Mahalanobis up to %.1f)",
                    e.count, e.duration, subject.c_str(), e.value);
      break;
    case EventKind::kVisionGated:
      std::snprintf(line, sizeof line,
                    "%d image(s) over %.2f s whose gate refused most features (up to %.0f%%)",
                    e.count, e.duration, e.value * 100);
      break;
    case EventKind::kSamplesDropped:
      std::snprintf(line, sizeof line,
                    "%d joint sample(s) over %.2f s dropped: not later than the previous one",
                    e.count, e.duration);
      break;
    case EventKind::kSamplesRejected:
      std::snprintf(line, sizeof line,
                    "%d joint sample(s) over %.2f s rejected: no hand can produce them (first: "
                    "%s = %g)",
                    e.count, e.duration, subject.c_str(), e.value);
      break;
    case EventKind::kImageDropped:
      std::snprintf(line, sizeof line, "image captured at %.3f s dropped: %s", e.value,
                    e.subject == 1 ? "the vision worker was busy"
                                   : "captured beyond the horizon or before the first sample");
      break;
    case EventKind::kImageRejected:
      std::snprintf(line, sizeof line,
                    "image rejected: empty, or its time or camera pose is not finite");
      break;
    case EventKind::kImageLate:
      std::snprintf(line, sizeof line, "image fused %.3f s late, %d joint sample(s) re-applied",
                    e.value, e.count);
      break;
    case EventKind::kHealth:
      return HealthMessage(e.health, hand);
    case EventKind::kNeesBeyondBound:
      std::snprintf(line, sizeof line, "NEES %.1f beyond its chi-square 99%% bound (16.81)",
                    e.value);
      break;
  }
  return line;
}

EventDetector::EventDetector(const HandModel& hand, double slip_hold)
    : links_(hand.links.size()), slip_hold_(slip_hold) {}

void EventDetector::Reset() {
  std::fill(links_.begin(), links_.end(), LinkContact());
  slipping_t_ = -1e300;
  health_ = Health();
  features_lost_ = tags_elsewhere_ = false;
  contacts_gated_ = vision_gated_ = dropped_ = rejected_ = Burst();
}

void EventDetector::Emit(Burst& b, EventKind kind, std::vector<TrackerEvent>& out) {
  TrackerEvent e;
  e.t = b.t0;
  e.kind = kind;
  e.subject = b.subject;
  e.value = b.value;
  e.count = b.count;
  e.duration = b.t_last - b.t0;
  out.push_back(e);
  b = Burst();
}

void EventDetector::CloseIfIdle(Burst& b, EventKind kind, double t,
                                std::vector<TrackerEvent>& out) {
  if (b.open && t - b.t_last > kBurstGap) Emit(b, kind, out);
}

void EventDetector::Add(Burst& b, EventKind kind, double t, int subject, double value, int count,
                        std::vector<TrackerEvent>& out) {
  CloseIfIdle(b, kind, t, out);
  if (!b.open) {
    b.open = true;
    b.t0 = t;
    b.subject = subject;
    b.value = value;
  }
  b.t_last = t;
  b.count += count;
  if (kind == EventKind::kContactsGated || kind == EventKind::kVisionGated)
    b.value = std::max(b.value, value);
}

void EventDetector::OnSample(double t, const FilterTrace& trace, const Health& health,
                             std::vector<TrackerEvent>& out) {
  // Contacts per link: this sample's raw state, then what has held for kContactHold.
  for (LinkContact& l : links_) l.raw = false;
  int gated = 0;
  double gated_max = 0.0;
  for (const FilterTrace::Contact& c : trace.contacts) {
    if (c.link < 0 || c.link >= static_cast<int>(links_.size())) continue;
    LinkContact& l = links_[static_cast<std::size_t>(c.link)];
    if (c.gated) {
      ++l.gated, ++gated;
      gated_max = std::max(gated_max, c.mahalanobis);
      continue;
    }
    if (c.kind != ContactKind::kKinematic && c.kind != ContactKind::kTorque) continue;
    if (!l.raw) l.torque = false, l.force = l.depth = 0.0;  // the link's first contact here
    l.raw = true;
    l.torque = l.torque || c.kind == ContactKind::kTorque;
    if (c.kind == ContactKind::kTorque) l.force = std::max(l.force, c.force_P.norm());
    l.depth = std::max(l.depth, -c.distance);
  }
  for (std::size_t i = 0; i < links_.size(); ++i) {
    LinkContact& l = links_[i];
    if (l.raw == l.in) {
      l.pending = false;
      continue;
    }
    if (!l.pending) l.pending = true, l.raw_since = t;  // the first sample that differs
    if (t - l.raw_since < kContactHold - 1e-9) continue;
    TrackerEvent e;
    e.t = l.raw_since;
    e.subject = static_cast<int>(i);
    if (l.raw) {
      e.kind = EventKind::kContactMade;
      e.value = l.torque ? l.force : l.depth;
      e.count = l.torque ? 1 : 0;
      l.declared_t = e.t;
    } else {
      e.kind = EventKind::kContactBroken;
      e.duration = e.t - l.declared_t;
    }
    l.in = l.raw;
    l.pending = false;
    out.push_back(e);
  }
  if (gated > 0) {
    int most = -1, most_count = 0;
    for (std::size_t i = 0; i < links_.size(); ++i)
      if (links_[i].gated > most_count) most_count = links_[i].gated, most = static_cast<int>(i);
    Add(contacts_gated_, EventKind::kContactsGated, t, most, gated_max, gated, out);
    contacts_gated_.subject = most;  // the burst's most gated link so far
  } else {
    CloseIfIdle(contacts_gated_, EventKind::kContactsGated, t, out);
  }
  if (!contacts_gated_.open)
    for (LinkContact& l : links_) l.gated = 0;
  CloseIfIdle(vision_gated_, EventKind::kVisionGated, t, out);
  CloseIfIdle(dropped_, EventKind::kSamplesDropped, t, out);
  CloseIfIdle(rejected_, EventKind::kSamplesRejected, t, out);

  if (trace.slipping) {
    if (t - slipping_t_ > slip_hold_ + 1e-9) {
      TrackerEvent e;
      e.t = t;
      e.kind = EventKind::kGripLoosened;
      out.push_back(e);
    }
    slipping_t_ = t;
  }

  OnHealth(t, health, out);
}

void EventDetector::OnHealth(double t, const Health& health, std::vector<TrackerEvent>& out) {
  if (health.state != health_.state) {
    TrackerEvent e;
    e.t = t;
    e.kind = EventKind::kHealth;
    e.subject = health.subject;
    e.value = health.value;
    e.health = health;
    out.push_back(e);
  }
  health_ = health;
}

void EventDetector::OnImage(const Image& image, std::vector<TrackerEvent>& out) {
  const ImageEvidence& im = image.evidence;
  const auto emit = [&](EventKind kind, double value, int count = 1) {
    TrackerEvent e;
    e.t = im.t_capture;
    e.kind = kind;
    e.value = value;
    e.count = count;
    out.push_back(e);
  };
  if (image.replayed > 0)
    emit(EventKind::kImageLate, image.newest_t - im.t_capture, static_cast<int>(image.replayed));
  if (image.shifts_refused > 0) emit(EventKind::kShiftRefused, 0.0, image.shifts_refused);
  if (im.relocalized > 0.0)
    emit(image.recovered ? EventKind::kRecovered : EventKind::kRelocalized, im.relocalized);
  if (im.features_lost && !features_lost_) emit(EventKind::kFeaturesLost, 0.0);
  if (!im.features_lost && features_lost_) emit(EventKind::kFeaturesFound, im.relocalized);
  features_lost_ = im.features_lost;
  if (im.tags_elsewhere && !tags_elsewhere_) emit(EventKind::kTagsElsewhere, 0.0);
  tags_elsewhere_ = im.tags_elsewhere;
  // The gate refused most of what this image offered (at least a few features).
  constexpr int kMinOffered = 4;
  if (im.offered >= kMinOffered && 2 * im.used < im.offered)
    Add(vision_gated_, EventKind::kVisionGated, im.t_capture, -1,
        1.0 - static_cast<double>(im.used) / im.offered, 1, out);
}

void EventDetector::OnSampleDropped(double t, std::vector<TrackerEvent>& out) {
  Add(dropped_, EventKind::kSamplesDropped, std::isfinite(t) ? t : dropped_.t_last, -1, 0.0, 1,
      out);
}

void EventDetector::OnSampleRejected(double t, int joint, double value,
                                     std::vector<TrackerEvent>& out) {
  Add(rejected_, EventKind::kSamplesRejected, t, joint, value, 1, out);
}

void EventDetector::Close(std::vector<TrackerEvent>& out) {
  if (contacts_gated_.open) Emit(contacts_gated_, EventKind::kContactsGated, out);
  if (vision_gated_.open) Emit(vision_gated_, EventKind::kVisionGated, out);
  if (dropped_.open) Emit(dropped_, EventKind::kSamplesDropped, out);
  if (rejected_.open) Emit(rejected_, EventKind::kSamplesRejected, out);
  for (LinkContact& l : links_) l.gated = 0;
}

}  // namespace inhand
