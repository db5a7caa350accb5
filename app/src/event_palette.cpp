#include "inhand/app/event_palette.hpp"

namespace inhand::app {

Rgb HealthColour(HealthState state) {
  switch (state) {
    case HealthState::kOk:
      return {50, 130, 70};
    case HealthState::kUncertain:
      return {220, 190, 50};
    case HealthState::kInconsistent:
      return {240, 120, 40};
    case HealthState::kLost:
      return {230, 50, 50};
  }
  return {255, 255, 255};
}

Rgb EventColour(const TrackerEvent& e) {
  switch (e.kind) {
    case EventKind::kContactMade:
      return {120, 200, 120};
    case EventKind::kContactBroken:
      return {140, 140, 140};
    case EventKind::kGripLoosened:
      return {240, 220, 60};
    case EventKind::kFeaturesLost:
    case EventKind::kTagsElsewhere:
      return {255, 120, 60};
    case EventKind::kFeaturesFound:
    case EventKind::kRelocalized:
    case EventKind::kRecovered:
    case EventKind::kStartSettled:
      return {80, 200, 255};
    case EventKind::kShiftRefused:
      return {90, 130, 255};
    case EventKind::kContactsGated:
    case EventKind::kVisionGated:
      return {190, 110, 255};
    case EventKind::kHealth:
      return HealthColour(e.health.state);
    case EventKind::kNeesBeyondBound:
      return {255, 80, 200};
    default:  // samples and images the tracker could not use, or used late
      return {235, 235, 235};
  }
}

bool IsContact(const TrackerEvent& e) {
  return e.kind == EventKind::kContactMade || e.kind == EventKind::kContactBroken;
}

StripMarker::Shape MarkerShape(const TrackerEvent& e) {
  if (IsContact(e)) return StripMarker::Shape::kTick;
  return e.duration > 0.0 ? StripMarker::Shape::kBar : StripMarker::Shape::kDot;
}

std::vector<std::pair<std::string, Rgb>> EventLegend() {
  TrackerEvent e;
  const auto of = [&](EventKind k) {
    e.kind = k;
    return EventColour(e);
  };
  return {{"contact made", of(EventKind::kContactMade)},
          {"broken", of(EventKind::kContactBroken)},
          {"grip loosened", of(EventKind::kGripLoosened)},
          {"lost / elsewhere", of(EventKind::kFeaturesLost)},
          {"found / relocated", of(EventKind::kRelocalized)},
          {"shift refused", of(EventKind::kShiftRefused)},
          {"gated", of(EventKind::kContactsGated)},
          {"NEES > 99%", of(EventKind::kNeesBeyondBound)},
          {"input dropped / late", of(EventKind::kSamplesDropped)},
          {"ok", HealthColour(HealthState::kOk)},
          {"uncertain", HealthColour(HealthState::kUncertain)},
          {"inconsistent", HealthColour(HealthState::kInconsistent)},
          {"lost", HealthColour(HealthState::kLost)}};
}

TimelineStrip MakeTimelineStrip(const std::vector<ModalitySet>& sets,
                                const std::vector<std::vector<TrackerEvent>>& events, double t0,
                                double t1) {
  TimelineStrip strip;
  strip.t0 = t0, strip.t1 = std::max(t1, t0 + 1e-3);
  strip.legend = EventLegend();
  for (std::size_t i = 0; i < sets.size(); ++i) {
    StripLane lane;
    lane.name = sets[i].name;
    lane.colour = sets[i].colour;
    lane.health.emplace_back(t0, HealthColour(HealthState::kOk));
    if (i < events.size())
      for (const TrackerEvent& e : events[i]) {
        if (e.kind == EventKind::kHealth)
          lane.health.emplace_back(e.t, HealthColour(e.health.state));
        else
          lane.markers.push_back({e.t, e.duration, MarkerShape(e), EventColour(e)});
      }
    strip.lanes.push_back(std::move(lane));
  }
  return strip;
}

}  // namespace inhand::app
