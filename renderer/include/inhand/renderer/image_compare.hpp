#pragma once
// Image regression: two numbers decide: the largest per-channel difference, and the
// fraction of pixels whose difference exceeds a tolerance. A heat map shows where.
#include "inhand/core/image.hpp"

namespace inhand {

struct ImageDiff {
  int max_channel_delta = 0;  // over all pixels and channels, 0..255
  double bad_fraction = 0.0;  // pixels with any channel delta > tolerance, over all pixels
  long bad_pixels = 0;
  Image8 heatmap;  // RGB: black = equal, through red to yellow = large difference
};

// Throws InputError when sizes or channel counts differ.
ImageDiff CompareImages(const Image8& a, const Image8& b, int tolerance);

}  // namespace inhand
