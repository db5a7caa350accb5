#include "inhand/app/match_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace inhand::app {

namespace {

cv::Mat RgbMat(const Image8& im) {
  const cv::Mat m(im.height, im.width, im.channels == 1 ? CV_8UC1 : CV_8UC3,
                  const_cast<std::uint8_t*>(im.data.data()));
  cv::Mat out;
  if (im.channels == 1)
    cv::cvtColor(m, out, cv::COLOR_GRAY2RGB);
  else
    out = m.clone();
  return out;
}

Image8 ToImage(const cv::Mat& rgb) {
  Image8 out(rgb.cols, rgb.rows, 3);
  for (int y = 0; y < rgb.rows; ++y)
    std::copy_n(rgb.ptr<std::uint8_t>(y), rgb.cols * 3, out.pixel(0, y));
  return out;
}

cv::Point P(const Vec2& v) {
  return cv::Point(static_cast<int>(std::lround(v.x())), static_cast<int>(std::lround(v.y())));
}

void Caption(cv::Mat& m, const std::string& text) {
  cv::rectangle(m, cv::Rect(0, 0, m.cols, 20), cv::Scalar(30, 30, 30), cv::FILLED);
  cv::putText(m, text, cv::Point(6, 14), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255),
              1, cv::LINE_AA);
}

cv::Scalar PieceColour(int i) {
  static const cv::Scalar palette[] = {
      {230, 25, 75},  {60, 180, 75},  {255, 225, 25}, {0, 130, 200},  {245, 130, 48},
      {145, 30, 180}, {70, 240, 240}, {240, 50, 230}, {210, 245, 60}, {250, 190, 212}};
  return palette[i % 10];
}

Image8 Difference(const Image8& a, const Image8& b) {
  if (a.empty() || b.empty() || a.width != b.width || a.height != b.height) return Image8();
  Image8 d(a.width, a.height, 3);
  for (std::size_t i = 0; i < d.data.size(); ++i) {
    const int ca = a.channels == 3 ? a.data[i] : a.data[i / 3],
              cb = b.channels == 3 ? b.data[i] : b.data[i / 3];
    d.data[i] = static_cast<std::uint8_t>(std::min(255, 2 * std::abs(ca - cb)));
  }
  return d;
}

}  // namespace

MatchPictures DrawMatchPictures(const Image8& camera_image, const VisualStep& fs) {
  const MatchResult& r = fs.match;
  const MatchDebug& d = r.debug;
  MatchPictures out;
  if (camera_image.empty() || fs.virtual_view.colour.empty()) return out;
  cv::Mat camera = RgbMat(camera_image), virt = RgbMat(fs.virtual_view.colour);
  cv::Mat real_edges = RgbMat(d.real_edges), virtual_edges = RgbMat(d.virtual_edges);
  cv::Mat corners_real = camera.clone(), corners_virtual = virt.clone();
  for (const Vec2& c : d.real_corners)
    cv::circle(corners_real, P(c), 4, cv::Scalar(255, 230, 0), 1, cv::LINE_AA);
  for (const Vec2& c : d.virtual_corners_rejected)
    cv::circle(corners_virtual, P(c), 2, cv::Scalar(220, 40, 40), cv::FILLED);
  for (const Vec2& c : d.virtual_corners)
    cv::circle(corners_virtual, P(c), 5, cv::Scalar(40, 220, 40), 2, cv::LINE_AA);
  cv::Mat pieces = virtual_edges.clone() * 0.35;
  for (std::size_t i = 0; i < d.pieces.size(); ++i) {
    const Vec2& c = d.virtual_corners[i];
    for (const Vec2& o : d.pieces[i]) {
      const cv::Point q = P(c + o);
      if (q.x >= 0 && q.y >= 0 && q.x < pieces.cols && q.y < pieces.rows) {
        const cv::Scalar col = PieceColour(static_cast<int>(i));
        pieces.at<cv::Vec3b>(q) =
            cv::Vec3b(static_cast<std::uint8_t>(col[0]), static_cast<std::uint8_t>(col[1]),
                      static_cast<std::uint8_t>(col[2]));
      }
    }
    cv::putText(pieces, std::to_string(i), P(c) + cv::Point(4, -4), cv::FONT_HERSHEY_SIMPLEX, 0.35,
                PieceColour(static_cast<int>(i)), 1, cv::LINE_AA);
  }
  // Hough accumulators, tiled, marked by their fate.
  const int tile = 96, per_row = 8;
  const int n = static_cast<int>(d.votes.size());
  cv::Mat votes(std::max(1, (n + per_row - 1) / per_row) * tile, per_row * tile, CV_8UC3,
                cv::Scalar(20, 20, 20));
  for (int i = 0; i < n; ++i) {
    if (d.votes[static_cast<std::size_t>(i)].empty()) continue;
    cv::Mat heat;
    cv::applyColorMap(RgbMat(d.votes[static_cast<std::size_t>(i)]), heat, cv::COLORMAP_INFERNO);
    cv::resize(heat, heat, cv::Size(tile - 4, tile - 4), 0, 0, cv::INTER_NEAREST);
    heat.copyTo(
        votes(cv::Rect((i % per_row) * tile + 2, (i / per_row) * tile + 2, tile - 4, tile - 4)));
    const bool rejected =
        std::find(d.vote_rejected.begin(), d.vote_rejected.end(), i) != d.vote_rejected.end();
    cv::putText(votes, std::to_string(i) + (rejected ? " weak" : ""),
                cv::Point((i % per_row) * tile + 4, (i / per_row) * tile + 14),
                cv::FONT_HERSHEY_SIMPLEX, 0.38,
                rejected ? cv::Scalar(255, 80, 80) : cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  cv::Mat matches = camera.clone();
  // The region the step read (the virtual view is drawn only around the object, within it).
  if (!fs.region.empty()) {
    const cv::Rect box(fs.region.x0, fs.region.y0, fs.region.width(), fs.region.height());
    for (cv::Mat* m : {&matches, &real_edges}) {
      cv::rectangle(*m, box, cv::Scalar(0, 200, 255), 1);
      cv::putText(*m, "searched", box.tl() + cv::Point(3, 24), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  cv::Scalar(0, 200, 255), 1, cv::LINE_AA);
    }
  }
  for (const FeatureMatch& m : r.matches) {
    const cv::Scalar col = m.inlier ? cv::Scalar(40, 230, 40) : cv::Scalar(230, 40, 40);
    cv::arrowedLine(matches, P(m.virtual_px), P(m.real_px), col, 1, cv::LINE_AA, 0, 0.3);
    cv::circle(matches, P(m.real_px), 3, col, 1, cv::LINE_AA);
  }
  // Step 0, when it ran: the whole object's shift, drawn from the virtual corners' centroid.
  const bool global = std::isfinite(d.global_cost) && !d.virtual_corners.empty();
  if (global) {
    Vec2 c = Vec2::Zero();
    for (const Vec2& v : d.virtual_corners) c += v;
    c /= static_cast<double>(d.virtual_corners.size());
    cv::arrowedLine(matches, P(c), P(c + d.global_shift), cv::Scalar(255, 220, 0), 2, cv::LINE_AA,
                    0, 0.2);
    char text[96];
    std::snprintf(text, sizeof text, "0. shift (%+.0f, %+.0f) px, chamfer %.1f px (unshifted %.1f)",
                  d.global_shift.x(), d.global_shift.y(), d.global_cost, d.global_cost_unshifted);
    cv::putText(matches, text, cv::Point(8, matches.rows - 10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(255, 220, 0), 1, cv::LINE_AA);
  }

  {
    // Everything in one picture: 2 rows x 3 columns at half size.
    std::vector<std::pair<std::string, cv::Mat>> grid = {
        {"1. camera edges (Canny)", real_edges},
        {"1. virtual edges (Canny)", virtual_edges},
        {"2. Harris corners (virtual: kept green)", corners_virtual},
        {"3. contour pieces", pieces},
        {global ? "0. shift, 4+5. matches (inliers green)" : "4+5. matches (inliers green)",
         matches},
        {"virtual view at the jtf estimate", virt}};
    std::vector<cv::Mat> rows, cells;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      cv::Mat c;
      cv::resize(grid[i].second, c,
                 cv::Size(grid[i].second.cols / 2 * 2 / 2, grid[i].second.rows / 2), 0, 0,
                 cv::INTER_AREA);
      Caption(c, grid[i].first);
      cells.push_back(c);
      if (cells.size() == 3) {
        cv::Mat row;
        cv::hconcat(cells, row);
        rows.push_back(row);
        cells.clear();
      }
    }
    cv::Mat all;
    cv::vconcat(rows, all);
    out.stages = ToImage(all);
  }
  out.edges_camera = ToImage(real_edges);
  out.edges_virtual = ToImage(virtual_edges);
  out.corners_camera = ToImage(corners_real);
  out.corners_virtual = ToImage(corners_virtual);
  out.pieces = ToImage(pieces);
  out.votes = ToImage(votes);
  out.matches = ToImage(matches);
  out.difference = Difference(camera_image, fs.virtual_view.colour);
  return out;
}

}  // namespace inhand::app
