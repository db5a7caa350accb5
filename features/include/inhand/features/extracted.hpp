#pragma once
// Extracted features, the paper's five steps between the camera image and the virtual image
// rendered at the current estimate (docs/estimator.md, "Vision"), and optionally a step
// before them that finds the whole object far off (global_search_radius):
//   0. one shift of the object       → the virtual object's edges placed on the camera's edges
//                                          by an oriented chamfer over a wide window; the
//                                          local searches of step 4 start from it
//   1. Canny on both images            → edge images
//   2. Harris on the edge images        → corners (virtual: on the object only)
//   3. contour pieces around the corners → the virtual edge pixels within a radius
//   4. generalized Hough transform      → each piece located in the camera's edges, searched
//                                          locally around its virtual corner (votes of edge
//                                          pixels with matching gradient direction)
//   5. RANSAC                            → matches consistent with one image similarity
// Every stage keeps its rejects for the matching debug views. Deterministic (seeded).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "inhand/core/image.hpp"
#include "inhand/core/so3.hpp"

namespace inhand {

struct FeatureParams {
  double canny_low = 40.0;  // hysteresis thresholds on the Sobel gradient magnitude
  double canny_high = 120.0;
  double blur_sigma = 1.0;  // [px] Gaussian blur before Canny (noise)
  int harris_block = 5;     // neighbourhood of the Harris matrix [px]
  double harris_k = 0.04;
  double harris_relative = 0.05;      // keep responses above this share of the maximum (with an
                                      // object mask: the maximum near the object), or of a clean
                                      // right-angle corner's response if that is larger
  int max_corners = 40;               // strongest virtual corners kept
  double min_corner_distance = 10.0;  // [px] between kept corners
  int occluder_clearance = 8;         // [px] virtual corners this close to an occluder (a finger)
                                      // are junctions of its edges with the object's: they move
                                      // with the finger, not the object (they had dragged jtf
                                      // 30-40 mm along a smooth bottle's axis)
  int piece_radius = 14;              // [px] contour piece: edge pixels within this radius
  int min_piece_pixels = 12;          // pieces with fewer edge pixels are rejected
  int search_radius = 30;             // [px] local Hough search around the virtual corner
  int max_search_radius = 90;         // [px] the tracker widens the search to 3σ of the object's
                                      // predicted pixel while the estimate is uncertain (a start
                                      // 40 mm off is 45 px at 0.5 m), up to this; = search_radius
                                      // keeps it fixed
  int global_search_radius = 0;       // [px] > 0: step 0 searches one shift of the whole object
                                      // within this, and step 4 searches search_radius around
                                      // it (each corner on its own within a window this wide
                                      // matched clutter: a start 40 mm off was fused 60 mm off)
  double global_truncation = 8.0;     // [px] step 0's chamfer: a virtual edge pixel costs its
                                      // distance to the nearest camera edge of its orientation
                                      // (±1 bin), at most this
  int orientation_bins = 12;          // gradient-direction bins (mod π); neighbours may vote
  double min_vote_fraction = 0.35;    // votes of the peak over the piece's pixels
  double ransac_threshold = 2.5;      // [px]
  int ransac_iterations = 300;
  unsigned seed = 1;
  void Validate() const;  // throws InputError naming the field
};

struct FeatureMatch {
  int id = -1;  // index of the virtual corner
  Vec2 virtual_px = Vec2::Zero();
  Vec2 real_px = Vec2::Zero();
  double vote_fraction = 0.0;
  bool inlier = false;  // kept by RANSAC
};

// What each stage produced, for `inhand match` and the GUI.
struct MatchDebug {
  Image8 real_edges, virtual_edges;                 // grey, 255 on edges
  std::vector<Vec2> real_corners, virtual_corners;  // Harris corners (virtual: kept ones)
  std::vector<Vec2> virtual_corners_rejected;       // off the object, too weak or too close
  std::vector<std::vector<Vec2>> pieces;            // per virtual corner, edge offsets
  std::vector<int> piece_rejected;                  // corner ids whose piece was too small
  std::vector<Image8> votes;                        // per corner, the Hough accumulator (grey)
  std::vector<int> vote_rejected;                   // corner ids whose peak was too weak
  Eigen::Matrix<double, 2, 3> similarity = Eigen::Matrix<double, 2, 3>::Zero();  // RANSAC model
  // Step 0 (global_search_radius > 0): the shift [px] and its mean chamfer cost [px], and the
  // cost without a shift; costs are NaN when step 0 did not run or the object has no edges.
  Vec2 global_shift = Vec2::Zero();
  double global_cost = std::numeric_limits<double>::quiet_NaN();
  double global_cost_unshifted = std::numeric_limits<double>::quiet_NaN();
};

struct MatchResult {
  std::vector<FeatureMatch> matches;  // every Hough match; inliers flagged
  MatchDebug debug;
  int num_inliers() const;
};

// `object_mask` (optional, virtual image size, non-zero on the object's visible pixels) limits
// the virtual corners to the object, and the virtual edges to its mask's box grown by a piece
// (piece_radius + 3 px: all that the steps read of them); `occluder_mask` (optional, same size,
// non-zero on what occludes it: the hand) rejects the corners within occluder_clearance of it.
// Images are RGB or grey of the same size. `camera_corners` false leaves debug.real_corners empty:
// the matching does not use them (the tracker skips them; EdgeCorners computes them for a debug
// view). `region` (not empty): only those pixels of both images are read (clipped to the images),
// as if they were the whole images: edges, corners, pieces and votes are found there, and reported
// in the whole image's pixels (the debug edge images are zero outside it). The caller keeps the
// object and the search around it inside, and the filters' borders (blur, Sobel, Harris block)
// away from what matters: an edge that leaves the region and comes back is not followed.
MatchResult MatchFeatures(const Image8& real, const Image8& virtual_image,
                          const std::vector<std::uint8_t>* object_mask, const FeatureParams& params,
                          const std::vector<std::uint8_t>* occluder_mask = nullptr,
                          bool camera_corners = true, const PixelRect& region = {});

// The region MatchFeatures with `params` needs around an object whose image lies within
// `object` [px]: that box grown by a corner's piece and how far it is searched for (with a
// whole-object shift first, step 0: the shift, the local search around it and the chamfer's
// truncation), and by kRegionBorder for the blur, Sobel and Harris windows' borders; clipped to
// the width x height image. Empty (the whole image) if `object` is not finite or the region
// misses the image.
inline constexpr int kRegionBorder = 8;  // [px]
PixelRect SearchRegion(const Eigen::AlignedBox2d& object, const FeatureParams& params, int width,
                       int height);

// What of the virtual image MatchFeatures reads with an object mask, for an object whose image
// lies within `object`: the box grown by a corner's piece, the mask's growth (3 px) and
// kRegionBorder. A view drawn only there (Scene::region) matches as a whole one does.
PixelRect DrawnRegion(const Eigen::AlignedBox2d& object, const FeatureParams& params, int width,
                      int height);

// Harris corners of an edge image (grey, 255 on edges) as MatchFeatures finds them.
std::vector<Vec2> EdgeCorners(const Image8& edges, const FeatureParams& params);

}  // namespace inhand
