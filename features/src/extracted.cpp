#include "inhand/features/extracted.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <opencv2/imgproc.hpp>

#include "inhand/core/error.hpp"

namespace inhand {

void FeatureParams::Validate() const {
  const auto fail = [](const char* field, double v, const char* expected) {
    throw InputError(std::string("feature parameter '") + field + "' is " + std::to_string(v) +
                     ", expected " + expected);
  };
  if (!(canny_low > 0 && canny_high > canny_low)) fail("canny_high", canny_high, "> canny_low > 0");
  if (!(blur_sigma >= 0 && blur_sigma <= 10)) fail("blur_sigma", blur_sigma, "in [0, 10]");
  if (harris_block < 2 || harris_block > 31) fail("harris_block", harris_block, "in [2, 31]");
  if (!(harris_relative > 0 && harris_relative < 1))
    fail("harris_relative", harris_relative, "in (0, 1)");
  if (max_corners < 1 || max_corners > 1000) fail("max_corners", max_corners, "in [1, 1000]");
  if (occluder_clearance < 0 || occluder_clearance > 100)
    fail("occluder_clearance", occluder_clearance, "in [0, 100]");
  if (piece_radius < 3 || piece_radius > 100) fail("piece_radius", piece_radius, "in [3, 100]");
  if (search_radius < 1 || search_radius > 200) fail("search_radius", search_radius, "in [1, 200]");
  if (max_search_radius < search_radius || max_search_radius > 200)
    fail("max_search_radius", max_search_radius, "in [search_radius, 200]");
  if (global_search_radius < 0 || global_search_radius > 200)
    fail("global_search_radius", global_search_radius, "in [0, 200]");
  if (!(global_truncation >= 1 && global_truncation <= 100))
    fail("global_truncation", global_truncation, "in [1, 100]");
  if (orientation_bins < 1 || orientation_bins > 64)
    fail("orientation_bins", orientation_bins, "in [1, 64]");
  if (!(min_vote_fraction > 0 && min_vote_fraction <= 1))
    fail("min_vote_fraction", min_vote_fraction, "in (0, 1]");
  if (!(ransac_threshold > 0)) fail("ransac_threshold", ransac_threshold, "> 0");
  if (ransac_iterations < 1) fail("ransac_iterations", ransac_iterations, ">= 1");
}

int MatchResult::num_inliers() const {
  return static_cast<int>(std::count_if(matches.begin(), matches.end(),
                                        [](const FeatureMatch& m) { return m.inlier; }));
}

namespace {

cv::Mat Wrap(const Image8& im) {
  return cv::Mat(im.height, im.width, im.channels == 1 ? CV_8UC1 : CV_8UC3,
                 const_cast<std::uint8_t*>(im.data.data()));
}

cv::Mat Grey(const cv::Mat& m) {
  if (m.channels() == 1) return m.clone();
  cv::Mat g;
  cv::cvtColor(m, g, cv::COLOR_RGB2GRAY);
  return g;
}

Image8 ToImage(const cv::Mat& grey) {
  Image8 out(grey.cols, grey.rows, 1);
  for (int y = 0; y < grey.rows; ++y)
    std::copy_n(grey.ptr<std::uint8_t>(y), grey.cols, out.pixel(0, y));
  return out;
}

struct EdgeData {
  cv::Mat edges;        // CV_8U, 255 on edges
  cv::Mat orientation;  // CV_8U, gradient direction bin (mod π)
};

// Gradient directions agree when their bins (mod π) are at most one apart, circularly.
bool BinsAgree(int a, int b, int bins) {
  const int d = std::abs(a - b);
  return std::min(d, bins - d) <= 1;
}

EdgeData Edges(const cv::Mat& im, const FeatureParams& p) {
  cv::Mat g = Grey(im);
  if (p.blur_sigma > 0) cv::GaussianBlur(g, g, cv::Size(0, 0), p.blur_sigma);
  EdgeData e;
  cv::Canny(g, e.edges, p.canny_low, p.canny_high, 3, true);
  cv::Mat gx, gy;
  cv::Sobel(g, gx, CV_32F, 1, 0, 3);
  cv::Sobel(g, gy, CV_32F, 0, 1, 3);
  // Orientation only where it is read: on edge pixels (0 elsewhere).
  e.orientation = cv::Mat::zeros(g.size(), CV_8U);
  for (int y = 0; y < g.rows; ++y) {
    const std::uint8_t* edge = e.edges.ptr<std::uint8_t>(y);
    for (int x = 0; x < g.cols; ++x) {
      if (!edge[x]) continue;
      double a = std::atan2(gy.at<float>(y, x), gx.at<float>(y, x));
      if (a < 0) a += M_PI;  // mod π: edges have no sign (light/dark may differ between images)
      e.orientation.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(
          std::min(p.orientation_bins - 1, static_cast<int>(a / M_PI * p.orientation_bins)));
    }
  }
  return e;
}

// The edges of `im` within `keep` (zero elsewhere), found over `keep` grown by kRegionBorder:
// the same as the whole image's there, but for an edge that leaves that border and comes back.
EdgeData EdgesWithin(const Image8& im, const cv::Rect& keep, const FeatureParams& p) {
  EdgeData e;
  e.edges = cv::Mat::zeros(im.height, im.width, CV_8U);
  e.orientation = cv::Mat::zeros(im.height, im.width, CV_8U);
  if (keep.empty()) return e;
  const cv::Rect computed =
      cv::Rect(keep.x - kRegionBorder, keep.y - kRegionBorder, keep.width + 2 * kRegionBorder,
               keep.height + 2 * kRegionBorder) &
      cv::Rect(0, 0, im.width, im.height);
  const EdgeData part = Edges(Wrap(im)(computed), p);
  const cv::Rect in_part(keep.x - computed.x, keep.y - computed.y, keep.width, keep.height);
  part.edges(in_part).copyTo(e.edges(keep));
  part.orientation(in_part).copyTo(e.orientation(keep));
  return e;
}

// The Harris response of a clean right-angle corner of one-pixel edges (two arms 28 px long),
// with the parameters' window and k.
double CornerReference(const FeatureParams& p) {
  cv::Mat f = cv::Mat::zeros(64, 64, CV_32F), response;
  f(cv::Rect(32, 32, 28, 1)).setTo(1.0f);
  f(cv::Rect(32, 32, 1, 28)).setTo(1.0f);
  cv::cornerHarris(f, response, p.harris_block, 3, p.harris_k);
  double max_r = 0.0;
  cv::minMaxLoc(response, nullptr, &max_r);
  return max_r;
}

// Harris corners of an edge image: local maxima above a share of the maximum, strongest first,
// at least min_distance apart. The maximum is at least a clean corner's (CornerReference): a
// view whose edges have only weak corners (a thin pen seen alone) does not lower the bar. `keep`
// filters candidates (virtual: on the object). Only edges within `area` count (none elsewhere: the
// response is zero farther than the Harris window).
std::vector<Vec2> HarrisCorners(const cv::Mat& edges, const FeatureParams& p,
                                const std::vector<std::uint8_t>* mask, std::vector<Vec2>* rejected,
                                cv::Rect area = cv::Rect()) {
  if (area.empty()) area = cv::Rect(0, 0, edges.cols, edges.rows);
  const int reach = p.harris_block + 2;  // the window and the Sobel aperture
  area = cv::Rect(area.x - reach, area.y - reach, area.width + 2 * reach, area.height + 2 * reach) &
         cv::Rect(0, 0, edges.cols, edges.rows);
  if (area.empty()) return {};
  cv::Mat f, response;
  edges(area).convertTo(f, CV_32F, 1.0 / 255.0);
  cv::cornerHarris(f, response, p.harris_block, 3, p.harris_k);
  double max_r = 0.0;
  cv::minMaxLoc(response, nullptr, &max_r);
  if (!(max_r > 0)) return {};
  max_r = std::max(max_r, CornerReference(p));
  cv::Mat dilated;
  cv::dilate(response, dilated, cv::Mat::ones(5, 5, CV_8U));
  struct Candidate {
    float r;
    int x, y;
  };
  std::vector<Candidate> cands;
  for (int y = 0; y < response.rows; ++y)
    for (int x = 0; x < response.cols; ++x) {
      const float r = response.at<float>(y, x);
      if (r >= p.harris_relative * max_r && r >= dilated.at<float>(y, x))
        cands.push_back({r, x, y});
    }
  std::stable_sort(cands.begin(), cands.end(),
                   [](const Candidate& a, const Candidate& b) { return a.r > b.r; });
  std::vector<Vec2> out;
  for (const Candidate& c : cands) {
    const Vec2 pt(c.x + area.x, c.y + area.y);
    const bool on_object =
        mask == nullptr || (*mask)[std::size_t(c.y + area.y) * edges.cols + c.x + area.x] != 0;
    bool far = true;
    for (const Vec2& q : out) far = far && (q - pt).norm() >= p.min_corner_distance;
    if (on_object && far && static_cast<int>(out.size()) < p.max_corners)
      out.push_back(pt);
    else if (rejected)
      rejected->push_back(pt);
  }
  return out;
}

// Step 0: the shift that puts the virtual object's edge pixels (on `mask`) on the camera's edges
// of the same orientation (±1 bin): the least mean of their truncated distances, searched every
// 3 px, then every pixel around the best. Ties go to the smaller shift (deterministic).
struct GlobalResult {
  Vec2 shift = Vec2::Zero();
  double cost = std::numeric_limits<double>::quiet_NaN();
  double cost_unshifted = std::numeric_limits<double>::quiet_NaN();
};

GlobalResult GlobalShift(const EdgeData& re, const EdgeData& ve,
                         const std::vector<std::uint8_t>* mask, const FeatureParams& p) {
  constexpr std::size_t kMaxPixels = 1500;  // enough for a silhouette; bounds the search's cost
  const int W = re.edges.cols, H = re.edges.rows, B = p.orientation_bins,
            G = p.global_search_radius;
  const float tau = static_cast<float>(p.global_truncation);
  struct Pixel {
    int x, y, bin;
  };
  std::vector<Pixel> all;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (ve.edges.at<std::uint8_t>(y, x) && (mask == nullptr || (*mask)[std::size_t(y) * W + x]))
        all.push_back({x, y, ve.orientation.at<std::uint8_t>(y, x)});
  GlobalResult out;
  if (all.empty()) return out;
  const std::size_t stride = (all.size() + kMaxPixels - 1) / kMaxPixels;
  std::vector<Pixel> px;
  for (std::size_t i = 0; i < all.size(); i += stride) px.push_back(all[i]);
  // Per orientation bin the virtual pixels use: the distance to the camera's edges of that bin
  // or a neighbour, truncated. Only where a shifted pixel can land: the virtual pixels' box grown
  // by the search radius, computed over that box grown by the truncation (exact Euclidean
  // distances, so a distance up to the truncation is the whole image's; beyond it both are cut).
  // The whole image took 12 distance transforms of 640x480 per frame.
  std::vector<bool> used(static_cast<std::size_t>(B), false);
  int x0 = W, y0 = H, x1 = -1, y1 = -1;
  for (const Pixel& q : px) {
    used[static_cast<std::size_t>(q.bin)] = true;
    x0 = std::min(x0, q.x), x1 = std::max(x1, q.x), y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
  }
  const int margin = G + static_cast<int>(std::ceil(tau)) + 1;
  const cv::Rect roi =
      cv::Rect(x0 - margin, y0 - margin, x1 - x0 + 2 * margin + 1, y1 - y0 + 2 * margin + 1) &
      cv::Rect(0, 0, W, H);
  std::vector<cv::Mat> dt(static_cast<std::size_t>(B));
  cv::Mat free(roi.height, roi.width, CV_8U);
  for (int b = 0; b < B; ++b) {
    if (!used[static_cast<std::size_t>(b)]) continue;
    for (int y = 0; y < roi.height; ++y) {
      const std::uint8_t* e = re.edges.ptr<std::uint8_t>(roi.y + y) + roi.x;
      const std::uint8_t* o = re.orientation.ptr<std::uint8_t>(roi.y + y) + roi.x;
      std::uint8_t* f = free.ptr<std::uint8_t>(y);
      for (int x = 0; x < roi.width; ++x) f[x] = e[x] && BinsAgree(o[x], b, B) ? 0 : 255;
    }
    cv::distanceTransform(free, dt[static_cast<std::size_t>(b)], cv::DIST_L2,
                          cv::DIST_MASK_PRECISE);
    cv::min(dt[static_cast<std::size_t>(b)], tau, dt[static_cast<std::size_t>(b)]);
  }
  const auto cost = [&](int sx, int sy) {
    double sum = 0.0;
    for (const Pixel& q : px) {
      const int x = q.x + sx, y = q.y + sy;
      sum += (x < 0 || y < 0 || x >= W || y >= H)
                 ? tau
                 : dt[static_cast<std::size_t>(q.bin)].at<float>(y - roi.y, x - roi.x);
    }
    return sum / static_cast<double>(px.size());
  };
  int bx = 0, by = 0;
  double best = cost(0, 0);
  out.cost_unshifted = best;
  const auto consider = [&](int sx, int sy) {
    if (sx < -G || sx > G || sy < -G || sy > G) return;
    const double c = cost(sx, sy);
    if (c < best || (c == best && sx * sx + sy * sy < bx * bx + by * by))
      best = c, bx = sx, by = sy;
  };
  for (int sy = -(G / 3) * 3; sy <= G; sy += 3)
    for (int sx = -(G / 3) * 3; sx <= G; sx += 3) consider(sx, sy);
  const int cx = bx, cy = by;
  for (int sy = cy - 2; sy <= cy + 2; ++sy)
    for (int sx = cx - 2; sx <= cx + 2; ++sx) consider(sx, sy);
  out.shift = Vec2(bx, by);
  out.cost = best;
  return out;
}

}  // namespace

PixelRect SearchRegion(const Eigen::AlignedBox2d& object, const FeatureParams& p, int width,
                       int height) {
  if (object.isEmpty() || !object.min().allFinite() || !object.max().allFinite()) return {};
  const int search = p.global_search_radius > 0
                         ? p.global_search_radius + p.search_radius +
                               static_cast<int>(std::ceil(p.global_truncation)) + 1
                         : p.search_radius;
  const double margin = p.piece_radius + search + kRegionBorder;
  const auto at = [](double v) { return static_cast<int>(std::clamp(v, -1e6, 1e6)); };
  return PixelRect{
      at(std::floor(object.min().x() - margin)), at(std::floor(object.min().y() - margin)),
      at(std::ceil(object.max().x() + margin)) + 1, at(std::ceil(object.max().y() + margin)) + 1}
      .ClippedTo(width, height);
}

PixelRect DrawnRegion(const Eigen::AlignedBox2d& object, const FeatureParams& p, int width,
                      int height) {
  FeatureParams none = p;
  none.global_search_radius = 0;
  none.search_radius = 3;  // the object mask's growth (MatchFeatures' virtual edges)
  return SearchRegion(object, none, width, height);
}

std::vector<Vec2> EdgeCorners(const Image8& edges, const FeatureParams& p) {
  p.Validate();
  INHAND_CHECK(edges.channels == 1, "EdgeCorners takes a grey edge image");
  return HarrisCorners(Wrap(edges), p, nullptr, nullptr);
}

namespace {

// The five steps over the whole of the images (MatchFeatures crops a region first).
// `origin`: where these images lie in the whole ones; the matches are reported there (the same
// arithmetic as on the whole images: the same pixels to the bit), the debug output here.
MatchResult MatchWhole(const Image8& real, const Image8& virtual_image,
                       const std::vector<std::uint8_t>* object_mask, const FeatureParams& p,
                       const std::vector<std::uint8_t>* occluder_mask, bool camera_corners,
                       const Vec2& origin) {
  MatchResult result;
  MatchDebug& dbg = result.debug;
  const int W = real.width, H = real.height, R = p.piece_radius, S = p.search_radius;
  // 1. Canny. In the virtual image only near the object (its mask's box grown by a piece and the
  // mask's growth below): all that a piece, step 0 or a corner on the object reads. The corners'
  // threshold is thus a share of the strongest near the object, not of the hand's far away, and
  // a view drawn only around the object (DrawnRegion) has the same edges as a whole one.
  cv::Rect around(0, 0, W, H);
  if (object_mask) {
    INHAND_CHECK(object_mask->size() == std::size_t(W) * H, "object mask of another size");
    int x0 = W, y0 = H, x1 = -1, y1 = -1;
    for (int y = 0; y < H; ++y) {
      const std::uint8_t* row = object_mask->data() + std::size_t(y) * W;
      for (int x = 0; x < W; ++x)
        if (row[x]) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = y;
    }
    around = x1 < 0 ? cv::Rect()
                    : cv::Rect(x0 - R - 3, y0 - R - 3, x1 - x0 + 2 * R + 7, y1 - y0 + 2 * R + 7) &
                          cv::Rect(0, 0, W, H);
  }
  const EdgeData re = Edges(Wrap(real), p), ve = EdgesWithin(virtual_image, around, p);
  dbg.real_edges = ToImage(re.edges);
  dbg.virtual_edges = ToImage(ve.edges);
  // The object mask, grown a little: silhouette edges lie on its border.
  // Less the neighbourhood of occluders, whose junctions with the object are not its features.
  std::vector<std::uint8_t> grown;
  if (object_mask) {
    cv::Mat m(virtual_image.height, virtual_image.width, CV_8U,
              const_cast<std::uint8_t*>(object_mask->data())),
        g;
    cv::dilate(m, g, cv::Mat::ones(5, 5, CV_8U));
    if (occluder_mask && p.occluder_clearance > 0) {
      INHAND_CHECK(occluder_mask->size() == g.total(), "occluder mask of another size");
      cv::Mat o(virtual_image.height, virtual_image.width, CV_8U,
                const_cast<std::uint8_t*>(occluder_mask->data())),
          near;
      const int k = 2 * p.occluder_clearance + 1;
      cv::dilate(o, near, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
      g.setTo(0, near);
    }
    grown.assign(g.data, g.data + g.total());
  }
  // 0. One shift of the whole object, when asked to search far: the local searches start there.
  int ox = 0, oy = 0;
  if (p.global_search_radius > 0) {
    const GlobalResult g = GlobalShift(re, ve, object_mask ? &grown : nullptr, p);
    dbg.global_shift = g.shift;
    dbg.global_cost = g.cost;
    dbg.global_cost_unshifted = g.cost_unshifted;
    ox = static_cast<int>(g.shift.x()), oy = static_cast<int>(g.shift.y());
  }
  // 2. Harris on the edge images.
  if (camera_corners) dbg.real_corners = HarrisCorners(re.edges, p, nullptr, nullptr);
  dbg.virtual_corners = HarrisCorners(ve.edges, p, object_mask ? &grown : nullptr,
                                      &dbg.virtual_corners_rejected, around);
  // 3. Contour pieces: virtual edge pixels around each corner (offsets and orientation bins).
  struct PieceEdge {
    int dx, dy, bin;
  };
  std::vector<std::vector<PieceEdge>> pieces(dbg.virtual_corners.size());
  dbg.pieces.resize(dbg.virtual_corners.size());
  for (std::size_t i = 0; i < dbg.virtual_corners.size(); ++i) {
    const int cx = static_cast<int>(dbg.virtual_corners[i].x()),
              cy = static_cast<int>(dbg.virtual_corners[i].y());
    for (int dy = -R; dy <= R; ++dy)
      for (int dx = -R; dx <= R; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if (dx * dx + dy * dy > R * R || x < 0 || y < 0 || x >= W || y >= H) continue;
        if (!ve.edges.at<std::uint8_t>(y, x)) continue;
        pieces[i].push_back({dx, dy, ve.orientation.at<std::uint8_t>(y, x)});
        dbg.pieces[i].emplace_back(dx, dy);
      }
  }
  // 4. Generalized Hough transform, local: each real edge pixel near the corner votes for the
  // corner positions that would put one of the piece's edge pixels (same orientation) on it.
  dbg.votes.resize(dbg.virtual_corners.size());
  const int A = 2 * S + 1;
  std::vector<int> acc(static_cast<std::size_t>(A * A));
  std::vector<std::vector<PieceEdge>> real_by_bin(static_cast<std::size_t>(p.orientation_bins));
  for (std::size_t i = 0; i < dbg.virtual_corners.size(); ++i) {
    if (static_cast<int>(pieces[i].size()) < p.min_piece_pixels) {
      dbg.piece_rejected.push_back(static_cast<int>(i));
      continue;
    }
    // The search window is centred at the corner moved by step 0's shift.
    const int cx = static_cast<int>(dbg.virtual_corners[i].x()) + ox,
              cy = static_cast<int>(dbg.virtual_corners[i].y()) + oy;
    std::fill(acc.begin(), acc.end(), 0);
    // The real edge pixels any piece pixel can reach (within R + S of the corner), listed once
    // per corner by orientation bin: each vote pairs one of them with a piece pixel of an
    // agreeing orientation (±1 bin) whose shift lies in the search window.
    for (auto& list : real_by_bin) list.clear();
    for (int y = std::max(0, cy - R - S); y <= std::min(H - 1, cy + R + S); ++y) {
      const std::uint8_t* row = re.edges.ptr<std::uint8_t>(y);
      const std::uint8_t* orow = re.orientation.ptr<std::uint8_t>(y);
      for (int x = std::max(0, cx - R - S); x <= std::min(W - 1, cx + R + S); ++x)
        if (row[x]) real_by_bin[orow[x]].push_back({x - cx, y - cy, 0});
    }
    for (const PieceEdge& e : pieces[i])
      for (int bin = 0; bin < p.orientation_bins; ++bin) {
        if (!BinsAgree(bin, e.bin, p.orientation_bins)) continue;
        for (const PieceEdge& r : real_by_bin[static_cast<std::size_t>(bin)]) {
          const int sx = r.dx - e.dx, sy = r.dy - e.dy;
          if (sx < -S || sx > S || sy < -S || sy > S) continue;
          ++acc[static_cast<std::size_t>((sy + S) * A + (sx + S))];
        }
      }
    // Peak (ties broken towards the smallest shift: deterministic), refined by a 3x3 centroid.
    int best = -1, bx = 0, by = 0;
    for (int sy = -S; sy <= S; ++sy)
      for (int sx = -S; sx <= S; ++sx) {
        const int v = acc[static_cast<std::size_t>((sy + S) * A + (sx + S))];
        if (v > best || (v == best && sx * sx + sy * sy < bx * bx + by * by))
          best = v, bx = sx, by = sy;
      }
    double wsum = 0, mx = 0, my = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int sx = bx + dx, sy = by + dy;
        if (std::abs(sx) > S || std::abs(sy) > S) continue;
        const double v = acc[static_cast<std::size_t>((sy + S) * A + (sx + S))];
        wsum += v, mx += v * sx, my += v * sy;
      }
    Image8 votes(A, A, 1);
    for (int k = 0; k < A * A; ++k)
      votes.data[static_cast<std::size_t>(k)] =
          static_cast<std::uint8_t>(best > 0 ? 255 * acc[static_cast<std::size_t>(k)] / best : 0);
    dbg.votes[i] = votes;
    const double fraction = double(best) / double(pieces[i].size());
    if (fraction < p.min_vote_fraction) {
      dbg.vote_rejected.push_back(static_cast<int>(i));
      continue;
    }
    FeatureMatch m;
    m.id = static_cast<int>(i);
    m.virtual_px = dbg.virtual_corners[i] + origin;
    m.real_px = m.virtual_px + Vec2(ox + mx / wsum, oy + my / wsum);
    m.vote_fraction = fraction;
    result.matches.push_back(m);
  }
  // 5. RANSAC: a 2-D similarity (4 DoF) from two matches, the largest consensus wins; refit on it.
  const std::size_t n = result.matches.size();
  if (n >= 2) {
    std::mt19937 rng(p.seed);
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    const auto fit = [&](const std::vector<std::size_t>& idx) {
      // Least squares over [a -b tx; b a ty].
      Eigen::MatrixXd M(2 * idx.size(), 4);
      Eigen::VectorXd b(2 * idx.size());
      for (std::size_t k = 0; k < idx.size(); ++k) {
        const Vec2& v = result.matches[idx[k]].virtual_px;
        const Vec2& r = result.matches[idx[k]].real_px;
        M.row(2 * k) << v.x(), -v.y(), 1, 0;
        M.row(2 * k + 1) << v.y(), v.x(), 0, 1;
        b.segment<2>(2 * k) = r;
      }
      const Eigen::Vector4d s = M.colPivHouseholderQr().solve(b);
      Eigen::Matrix<double, 2, 3> T;
      T << s[0], -s[1], s[2], s[1], s[0], s[3];
      return T;
    };
    const auto residual = [&](const Eigen::Matrix<double, 2, 3>& T, const FeatureMatch& m) {
      return (T.leftCols<2>() * m.virtual_px + T.col(2) - m.real_px).norm();
    };
    std::vector<std::size_t> best_set;
    for (int it = 0; it < p.ransac_iterations; ++it) {
      const std::size_t a = pick(rng), b = pick(rng);
      if (a == b || (result.matches[a].virtual_px - result.matches[b].virtual_px).norm() < 5.0)
        continue;
      const auto T = fit({a, b});
      std::vector<std::size_t> set;
      for (std::size_t k = 0; k < n; ++k)
        if (residual(T, result.matches[k]) < p.ransac_threshold) set.push_back(k);
      if (set.size() > best_set.size()) best_set = set;
    }
    if (best_set.size() >= 2) {
      dbg.similarity = fit(best_set);
      for (std::size_t k = 0; k < n; ++k)
        result.matches[k].inlier = residual(dbg.similarity, result.matches[k]) < p.ransac_threshold;
    }
  } else if (n == 1) {
    result.matches[0].inlier = false;  // one match cannot be checked against anything
  }
  return result;
}

Image8 Crop(const Image8& im, const PixelRect& r) {
  Image8 out(r.width(), r.height(), im.channels);
  const std::size_t row = std::size_t(r.width()) * im.channels;
  for (int y = 0; y < r.height(); ++y) std::copy_n(im.pixel(r.x0, r.y0 + y), row, out.pixel(0, y));
  return out;
}

std::vector<std::uint8_t> Crop(const std::vector<std::uint8_t>& mask, int width,
                               const PixelRect& r) {
  std::vector<std::uint8_t> out(std::size_t(r.width()) * r.height());
  for (int y = 0; y < r.height(); ++y)
    std::copy_n(&mask[std::size_t(r.y0 + y) * width + r.x0], r.width(),
                &out[std::size_t(y) * r.width()]);
  return out;
}

// An edge image of the region, put back in a whole image of zeros.
Image8 Uncrop(const Image8& part, int width, int height, const PixelRect& r) {
  Image8 out(width, height, part.channels);
  if (part.empty()) return out;
  const std::size_t row = std::size_t(r.width()) * part.channels;
  for (int y = 0; y < r.height(); ++y)
    std::copy_n(part.pixel(0, y), row, out.pixel(r.x0, r.y0 + y));
  return out;
}

}  // namespace

MatchResult MatchFeatures(const Image8& real, const Image8& virtual_image,
                          const std::vector<std::uint8_t>* object_mask, const FeatureParams& p,
                          const std::vector<std::uint8_t>* occluder_mask, bool camera_corners,
                          const PixelRect& region) {
  p.Validate();
  INHAND_CHECK(real.width == virtual_image.width && real.height == virtual_image.height,
               "images of different sizes");
  const int W = real.width, H = real.height;
  const PixelRect r = region.empty() ? PixelRect{0, 0, W, H} : region.ClippedTo(W, H);
  if (r.width() == W && r.height() == H)
    return MatchWhole(real, virtual_image, object_mask, p, occluder_mask, camera_corners,
                      Vec2::Zero());
  if (r.empty()) {  // a region outside the images: nothing read, nothing found
    MatchResult none;
    none.debug.real_edges = Image8(W, H, 1);
    none.debug.virtual_edges = Image8(W, H, 1);
    return none;
  }
  INHAND_CHECK(!object_mask || object_mask->size() == std::size_t(W) * H,
               "object mask of another size");
  INHAND_CHECK(!occluder_mask || occluder_mask->size() == std::size_t(W) * H,
               "occluder mask of another size");
  std::vector<std::uint8_t> object, occluder;
  if (object_mask) object = Crop(*object_mask, W, r);
  if (occluder_mask) occluder = Crop(*occluder_mask, W, r);
  const Vec2 o(r.x0, r.y0);
  MatchResult m = MatchWhole(Crop(real, r), Crop(virtual_image, r), object_mask ? &object : nullptr,
                             p, occluder_mask ? &occluder : nullptr, camera_corners, o);
  // The corners back to the whole image's pixels (whole numbers: exact).
  MatchDebug& d = m.debug;
  for (auto* points : {&d.real_corners, &d.virtual_corners, &d.virtual_corners_rejected})
    for (Vec2& q : *points) q += o;
  d.real_edges = Uncrop(d.real_edges, W, H, r);
  d.virtual_edges = Uncrop(d.virtual_edges, W, H, r);
  return m;
}

}  // namespace inhand
