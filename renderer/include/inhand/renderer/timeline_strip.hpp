#pragma once
// The timeline strip under a replay video's panels: a time axis over the whole session, one lane
// per modality set with its health as a band and a marker per event, a legend of the markers'
// colours and the current time as a cursor — so a viewer of the video sees where the moments are
// before they come. Plain input data: the app converts tracker events into it (as the GUI's
// timeline, whose look it follows).
#include <string>
#include <vector>

#include "inhand/renderer/overlay.hpp"

namespace inhand {

struct StripMarker {
  enum class Shape { kTick, kDot, kBar };  // tick: a thin mark at the lane's top (contacts)
  double t = 0.0;                          // [s]
  double duration = 0.0;                   // [s] bars: the span of a burst
  Shape shape = Shape::kDot;
  Rgb colour;
};

struct StripLane {
  std::string name;
  Rgb colour;  // the name's
  std::vector<StripMarker> markers;
  // The health band: its colour from each change on (the first at the session's start).
  std::vector<std::pair<double, Rgb>> health;
};

struct TimelineStrip {
  double t0 = 0.0, t1 = 1.0;  // [s] the session's span
  std::vector<StripLane> lanes;
  std::vector<std::pair<std::string, Rgb>> legend;  // what the colours mean
};

// Paints the strip `width` pixels wide (its height follows from the lanes) once, then a copy of it
// with the cursor at any time.
class TimelineStripPainter {
 public:
  TimelineStripPainter(const TimelineStrip& strip, int width);
  Image8 At(double t) const;
  // [px] where time t lies on the axis.
  double X(double t) const;

 private:
  TimelineStrip strip_;
  Image8 background_;
  int x0_ = 0, x1_ = 0;  // [px] the axis's span
};
// An axis's tick step: 1, 2 or 5 times a power of ten, at least `min_px` apart over `width_px`
// pixels spanning `span` (the GUI's time and value axes use it too).
double TickStep(double span, double width_px, double min_px);

// `top` above `bottom`, both as wide as `top` (`bottom` padded or cut on the right); even sizes
// for H.264.
Image8 StackBelow(const Image8& top, const Image8& bottom);

}  // namespace inhand
