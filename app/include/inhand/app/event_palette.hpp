#pragma once
// How events and health look wherever they are drawn — the GUI's timeline and event list, the
// replay video's timeline strip: one colour per kind of event and per health state, one shape
// per kind of marker.
#include <vector>

#include "inhand/app/modalities.hpp"
#include "inhand/renderer/timeline_strip.hpp"
#include "inhand/tracker/events.hpp"

namespace inhand::app {

// ok green, uncertain yellow, inconsistent orange, lost red.
Rgb HealthColour(HealthState state);
Rgb EventColour(const TrackerEvent& e);
bool IsContact(const TrackerEvent& e);
// Contacts as ticks, bursts as bars over their span, the rest as dots.
StripMarker::Shape MarkerShape(const TrackerEvent& e);
// The legend of EventColour and HealthColour, in words.
std::vector<std::pair<std::string, Rgb>> EventLegend();

// The video's strip over [t0, t1]: a lane per set with its events (events[i] for sets[i]) and
// its health from the health events.
TimelineStrip MakeTimelineStrip(const std::vector<ModalitySet>& sets,
                                const std::vector<std::vector<TrackerEvent>>& events, double t0,
                                double t1);

}  // namespace inhand::app
