#pragma once
// A plain 8-bit image: rows top to bottom, channels interleaved (RGB or grey). The common
// currency between sessions, renderer, features and app, free of any library's type.
#include <cstdint>
#include <vector>

namespace inhand {

struct Image8 {
  int width = 0;
  int height = 0;
  int channels = 3;  // 1 (grey), 3 (RGB) or 4 (RGBA)
  std::vector<std::uint8_t> data;

  Image8() = default;
  Image8(int w, int h, int c) : width(w), height(h), channels(c), data(std::size_t(w) * h * c, 0) {}
  bool empty() const { return data.empty(); }
  std::uint8_t* pixel(int x, int y) { return &data[(std::size_t(y) * width + x) * channels]; }
  const std::uint8_t* pixel(int x, int y) const {
    return &data[(std::size_t(y) * width + x) * channels];
  }
};

// A rectangle of pixels: columns [x0, x1), rows [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  // The part within a width x height image (empty if none).
  PixelRect ClippedTo(int width, int height) const {
    PixelRect r{x0 < 0 ? 0 : x0, y0 < 0 ? 0 : y0, x1 > width ? width : x1,
                y1 > height ? height : y1};
    if (r.empty()) r = PixelRect{};
    return r;
  }
};

}  // namespace inhand
