#include "inhand/renderer/timeline_strip.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "cv_colour.hpp"
#include "inhand/core/error.hpp"

namespace inhand {

namespace {

constexpr int kLabel = 48;   // [px] the lanes' names
constexpr int kAxis = 18;    // [px] the time axis's labels
constexpr int kLane = 16;    // [px] per set
constexpr int kLegend = 18;  // [px]
constexpr int kRight = 8;    // [px] after the axis's end
constexpr double kFont = 0.4;
const cv::Scalar kBackground(22, 22, 28);
const cv::Scalar kGrid(70, 70, 80);
const cv::Scalar kText(170, 170, 180);

cv::Mat View(Image8& im) { return cv::Mat(im.height, im.width, CV_8UC3, im.data.data()); }

void Text(cv::Mat& img, const std::string& s, int x, int y_bottom, const cv::Scalar& c) {
  cv::putText(img, s, cv::Point(x, y_bottom), cv::FONT_HERSHEY_SIMPLEX, kFont, c, 1, cv::LINE_AA);
}

int TextWidth(const std::string& s) {
  int base = 0;
  return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, kFont, 1, &base).width;
}

}  // namespace

double TickStep(double span, double width, double min_px) {
  const double raw = span * min_px / std::max(1.0, width);
  const double decade = std::pow(10.0, std::floor(std::log10(std::max(raw, 1e-9))));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * decade >= raw) return m * decade;
  return 10.0 * decade;
}

TimelineStripPainter::TimelineStripPainter(const TimelineStrip& strip, int width) : strip_(strip) {
  INHAND_CHECK(width >= kLabel + kRight + 16, "TimelineStripPainter: too narrow");
  INHAND_CHECK(strip.t1 > strip.t0, "TimelineStripPainter: an empty span");
  const int lanes = static_cast<int>(strip.lanes.size());
  int height = kAxis + kLane * lanes + (strip.legend.empty() ? 4 : kLegend);
  height += height % 2;
  width += width % 2;
  x0_ = kLabel, x1_ = width - kRight;
  background_ = Image8(width, height, 3);
  cv::Mat img = View(background_);
  img.setTo(kBackground);
  const auto x_of = [&](double t) { return static_cast<int>(std::lround(X(t))); };
  const int lanes_end = kAxis + kLane * lanes;
  // The axis: a grid line and a label per tick.
  const double step = TickStep(strip.t1 - strip.t0, x1_ - x0_, 70.0);
  for (double t = std::ceil(strip.t0 / step - 1e-9) * step; t <= strip.t1 + 1e-9; t += step) {
    const int x = x_of(t);
    cv::line(img, cv::Point(x, kAxis - 4), cv::Point(x, lanes_end), kGrid, 1);
    char label[32];
    std::snprintf(label, sizeof label, "%g s", std::round(t / step) * step + 0.0);  // not -0
    if (x + 2 + TextWidth(label) <= width) Text(img, label, x + 2, kAxis - 6, kText);
  }
  for (int i = 0; i < lanes; ++i) {
    const StripLane& lane = strip.lanes[static_cast<std::size_t>(i)];
    const int y = kAxis + kLane * i;
    Text(img, lane.name, 4, y + kLane - 4, Colour(lane.colour));
    // The health band, from each change to the next.
    for (std::size_t h = 0; h < lane.health.size(); ++h) {
      const double to = h + 1 < lane.health.size() ? lane.health[h + 1].first : strip.t1;
      const int a = std::max(x_of(lane.health[h].first), x0_), b = std::min(x_of(to), x1_);
      if (a < b)
        cv::rectangle(img, cv::Point(a, y + kLane - 5), cv::Point(b, y + kLane - 3),
                      Colour(lane.health[h].second), cv::FILLED);
      if (h > 0)  // each change as a small bar of its colour
        cv::rectangle(img, cv::Point(a - 1, y + kLane - 9), cv::Point(a, y + kLane - 3),
                      Colour(lane.health[h].second), cv::FILLED);
    }
    const int mid = y + 7;
    for (const StripMarker& m : lane.markers) {
      const int x = x_of(m.t);
      if (x < x0_ - 3 || x > x1_ + 3) continue;
      const cv::Scalar c = Colour(m.colour);
      switch (m.shape) {
        case StripMarker::Shape::kTick:
          cv::line(img, cv::Point(x, y + 1), cv::Point(x, y + 5), c, 1);
          break;
        case StripMarker::Shape::kBar:
          cv::rectangle(img, cv::Point(x, mid - 3),
                        cv::Point(std::max(x + 2, x_of(m.t + m.duration)), mid + 2), c, cv::FILLED);
          break;
        case StripMarker::Shape::kDot:
          cv::circle(img, cv::Point(x, mid), 3, c, cv::FILLED, cv::LINE_AA);
          break;
      }
    }
  }
  // The legend: a swatch and a word per colour, as many as fit.
  int x = 4;
  for (const auto& [name, colour] : strip.legend) {
    const int w = 12 + TextWidth(name) + 12;
    if (x + w > width) break;
    cv::rectangle(img, cv::Point(x, lanes_end + 6), cv::Point(x + 8, lanes_end + 12),
                  Colour(colour), cv::FILLED);
    Text(img, name, x + 12, lanes_end + 14, kText);
    x += w;
  }
}

double TimelineStripPainter::X(double t) const {
  return x0_ + (t - strip_.t0) / (strip_.t1 - strip_.t0) * (x1_ - x0_);
}

Image8 TimelineStripPainter::At(double t) const {
  Image8 out = background_;
  cv::Mat img = View(out);
  const int x = static_cast<int>(std::lround(X(std::clamp(t, strip_.t0, strip_.t1))));
  const int bottom = kAxis + kLane * static_cast<int>(strip_.lanes.size());
  // What has been played: the lanes behind the cursor a little lighter.
  if (x > x0_) {
    cv::Mat played = img(cv::Rect(x0_, kAxis, x - x0_, bottom - kAxis));
    played += cv::Scalar(14, 14, 14);
  }
  cv::line(img, cv::Point(x, kAxis - 6), cv::Point(x, bottom), cv::Scalar(255, 255, 255), 1);
  const cv::Point head[] = {{x - 4, kAxis - 9}, {x + 4, kAxis - 9}, {x, kAxis - 4}};
  cv::fillConvexPoly(img, head, 3, cv::Scalar(255, 255, 255), cv::LINE_AA);
  return out;
}

Image8 StackBelow(const Image8& top, const Image8& bottom) {
  INHAND_CHECK(top.channels == 3 && bottom.channels == 3, "StackBelow takes RGB images");
  const int width = top.width + top.width % 2;
  int height = top.height + bottom.height;
  height += height % 2;
  Image8 out(width, height, 3);
  std::fill(out.data.begin(), out.data.end(), std::uint8_t{0});
  for (int y = 0; y < top.height; ++y)
    std::memcpy(&out.data[static_cast<std::size_t>(y) * width * 3],
                &top.data[static_cast<std::size_t>(y) * top.width * 3],
                static_cast<std::size_t>(top.width) * 3);
  const int w = std::min(width, bottom.width);
  for (int y = 0; y < bottom.height; ++y)
    std::memcpy(&out.data[static_cast<std::size_t>(top.height + y) * width * 3],
                &bottom.data[static_cast<std::size_t>(y) * bottom.width * 3],
                static_cast<std::size_t>(w) * 3);
  return out;
}

}  // namespace inhand
