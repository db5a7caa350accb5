#include <gtest/gtest.h>

#include <cmath>

#include "inhand/renderer/timeline_strip.hpp"

namespace inhand {
namespace {

bool Is(const std::uint8_t* px, int r, int g, int b) {
  return px[0] == r && px[1] == g && px[2] == b;
}

TimelineStrip TwoLanes() {
  TimelineStrip s;
  s.t0 = 2.0, s.t1 = 12.0;
  StripLane a{"j", {214, 39, 40}, {}, {{2.0, {50, 130, 70}}, {7.0, {230, 50, 50}}}};
  a.markers.push_back({4.0, 0.0, StripMarker::Shape::kDot, {240, 220, 60}});
  StripLane b{"jt", {31, 119, 220}, {}, {{2.0, {50, 130, 70}}}};
  b.markers.push_back({5.0, 2.0, StripMarker::Shape::kBar, {190, 110, 255}});
  s.lanes = {a, b};
  s.legend = {{"grip loosened", {240, 220, 60}}};
  return s;
}

// The axis runs from 48 px to 8 px before the right edge over [t0, t1]; the lanes (16 px each)
// start 18 px down, the legend follows them.
TEST(TimelineStrip, TimesLandWhereTheAxisPutsThem) {
  const TimelineStripPainter painter(TwoLanes(), 448);
  EXPECT_DOUBLE_EQ(painter.X(2.0), 48.0);
  EXPECT_DOUBLE_EQ(painter.X(12.0), 440.0);
  EXPECT_DOUBLE_EQ(painter.X(7.0), 244.0);
  const Image8 img = painter.At(9.5);
  EXPECT_EQ(img.width, 448);
  EXPECT_EQ(img.height, 18 + 2 * 16 + 18);
  // The cursor: one white column through the lanes, at 9.5 s (48 + 0.75 * 392 = 342).
  for (int y = 18; y < 50; y += 5)
    for (int x = 40; x < 448; ++x)
      EXPECT_EQ(Is(img.pixel(x, y), 255, 255, 255), x == 342) << x << ", " << y;
  // Lane j: the dot at 4 s (x 126.4, mid-lane y 25), lightened by 14 behind the cursor; its
  // health band green before 7 s and red after it (rows 29-31).
  EXPECT_TRUE(Is(img.pixel(126, 25), 254, 234, 74));
  EXPECT_TRUE(Is(img.pixel(150, 30), 64, 144, 84));
  EXPECT_TRUE(Is(img.pixel(300, 30), 244, 64, 64));
  EXPECT_TRUE(Is(img.pixel(400, 30), 230, 50, 50));  // ahead of the cursor: as painted
  // Lane jt: the burst as a bar from 5 s to 7 s (x 165.6 to 244), nothing beyond it.
  EXPECT_TRUE(Is(img.pixel(200, 18 + 16 + 7), 204, 124, 255));
  EXPECT_FALSE(Is(img.pixel(260, 18 + 16 + 7), 204, 124, 255));
  // Before any time, the cursor sits on the axis's start; nothing is lightened.
  const Image8 start = painter.At(0.0);
  EXPECT_TRUE(Is(start.pixel(48, 30), 255, 255, 255));
  EXPECT_TRUE(Is(start.pixel(150, 30), 50, 130, 70));
}

TEST(TimelineStrip, StackBelowKeepsBothAndEvenSizes) {
  Image8 top(101, 51, 3), bottom(90, 20, 3);
  top.pixel(100, 50)[0] = 7;
  bottom.pixel(89, 19)[1] = 9;
  const Image8 both = StackBelow(top, bottom);
  EXPECT_EQ(both.width, 102);
  EXPECT_EQ(both.height, 72);
  EXPECT_EQ(both.pixel(100, 50)[0], 7);
  EXPECT_EQ(both.pixel(89, 70)[1], 9);
  EXPECT_EQ(both.pixel(101, 60)[0], 0);
}

}  // namespace
}  // namespace inhand
