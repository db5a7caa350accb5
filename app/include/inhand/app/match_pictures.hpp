#pragma once
// Pictures of every stage of the extracted-feature matching of one frame, shared by
// `inhand match` and the GUI.
#include "inhand/tracker/tracker.hpp"

namespace inhand::app {

struct MatchPictures {
  Image8 edges_camera, edges_virtual;      // 1. Canny
  Image8 corners_camera, corners_virtual;  // 2. Harris (virtual: kept green, rejected red)
  Image8 pieces;                           // 3. contour pieces, one colour each
  Image8 votes;                            // 4. Hough accumulators, tiled (weak peaks marked)
  Image8 matches;                          // 4+5. virtual -> camera pixel, RANSAC inliers green
  Image8 difference;                       // |camera - virtual|
  Image8 stages;                           // the main ones in one 3x2 picture
};
MatchPictures DrawMatchPictures(const Image8& camera, const VisualStep& step);

}  // namespace inhand::app
