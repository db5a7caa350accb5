#include "inhand/renderer/image_compare.hpp"

#include <algorithm>
#include <cstdlib>
#include <string>

#include "inhand/core/error.hpp"

namespace inhand {

ImageDiff CompareImages(const Image8& a, const Image8& b, int tolerance) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw InputError("images differ in size: " + std::to_string(a.width) + "x" +
                     std::to_string(a.height) + "x" + std::to_string(a.channels) + " vs " +
                     std::to_string(b.width) + "x" + std::to_string(b.height) + "x" +
                     std::to_string(b.channels));
  ImageDiff d;
  d.heatmap = Image8(a.width, a.height, 3);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      int worst = 0;
      for (int c = 0; c < a.channels; ++c)
        worst = std::max(worst, std::abs(int(a.pixel(x, y)[c]) - int(b.pixel(x, y)[c])));
      d.max_channel_delta = std::max(d.max_channel_delta, worst);
      d.bad_pixels += worst > tolerance;
      // Heat: red grows with the difference, yellow beyond 128.
      std::uint8_t* h = d.heatmap.pixel(x, y);
      h[0] = static_cast<std::uint8_t>(std::min(255, worst * 4));
      h[1] = static_cast<std::uint8_t>(std::clamp((worst - 64) * 2, 0, 255));
      h[2] = 0;
    }
  d.bad_fraction =
      a.width * a.height > 0 ? double(d.bad_pixels) / (double(a.width) * a.height) : 0.0;
  return d;
}

}  // namespace inhand
