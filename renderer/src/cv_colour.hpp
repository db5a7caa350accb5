// The renderer's colours as OpenCV scalars (internal to the renderer's sources).
#pragma once

#include <opencv2/core.hpp>

#include "inhand/renderer/overlay.hpp"

namespace inhand {

// The Mats that the renderer draws on hold RGB, as Image8 does.
inline cv::Scalar Colour(const Rgb& c) { return cv::Scalar(c.r, c.g, c.b); }

}  // namespace inhand
