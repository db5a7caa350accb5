#include "inhand/renderer/overlay.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cv_colour.hpp"
#include "inhand/core/error.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand {

namespace {

// Projects a palm-frame point; false when behind the camera.
bool ProjectP(const Transform& T_CP, const Intrinsics& K, const Vec3& X_P, Vec2& uv) {
  const Vec3 X_C = T_CP * X_P;
  if (X_C.z() <= 1e-4) return false;
  uv = K.Project(X_C);
  return true;
}

// cv drawing takes fixed-point coordinates with `shift` fractional bits: sub-pixel accuracy.
constexpr int kShift = 4;
constexpr double kHudScale = 0.45;  // the HUD's font size (cv::FONT_HERSHEY_SIMPLEX)
cv::Point Fx(const Vec2& p) {
  return cv::Point(static_cast<int>(std::lround((p.x()) * (1 << kShift))),
                   static_cast<int>(std::lround((p.y()) * (1 << kShift))));
}

void Line(cv::Mat& img, const Vec2& a, const Vec2& b, const cv::Scalar& c, int thickness) {
  cv::line(img, Fx(a), Fx(b), c, thickness, cv::LINE_AA, kShift);
}

void DrawDashedContours(cv::Mat& img, const std::vector<std::vector<cv::Point>>& contours,
                        const cv::Scalar& c) {
  constexpr int kOn = 7, kPeriod = 12;
  for (const auto& contour : contours) {
    for (std::size_t i = 0; i < contour.size(); ++i)
      if (static_cast<int>(i) % kPeriod < kOn) {
        const cv::Point& a = contour[i];
        const cv::Point& b = contour[(i + 1) % contour.size()];
        cv::line(img, a, b, c, 2, cv::LINE_AA);
      }
  }
}

}  // namespace

OverlayPainter::OverlayPainter(Renderer& renderer, std::vector<int> object_meshes)
    : renderer_(renderer), object_meshes_(std::move(object_meshes)) {}

std::vector<std::uint8_t> OverlayPainter::Silhouette(const Transform& T_PO, const Transform& T_PC,
                                                     const Intrinsics& K) {
  Scene scene;
  scene.K = K;
  scene.T_PC = T_PC;
  ObjectStyle style;
  style.rgba = Eigen::Vector4d(1, 1, 1, 1);  // opaque even for transparent bodies
  style.unlit = true;
  AddObject(scene, object_meshes_, T_PO, style);
  renderer_.Render(scene, scratch_, true);
  std::vector<std::uint8_t> mask(scratch_.label.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = scratch_.label[i] == kObjectLabel;
  return mask;
}

namespace {

// One estimate's silhouette (its bit in `masks`): tinted and/or outlined inside its bounding box;
// dashed outlines for the ground truth.
void DrawSilhouette(cv::Mat& img, const std::vector<std::uint16_t>& masks,
                    std::vector<std::uint8_t>& mask_data, const Intrinsics& K,
                    const OverlayEstimate& e, std::uint16_t bit, const OverlayLayers& layers) {
  for (std::size_t p = 0; p < mask_data.size(); ++p) mask_data[p] = (masks[p] & bit) != 0;
  const cv::Mat mask(K.height, K.width, CV_8UC1, mask_data.data());
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) return;
  if (layers.silhouette && !e.dashed) {
    cv::Mat roi = img(box), blended;
    cv::addWeighted(roi, 0.72, cv::Mat(box.size(), CV_8UC3, Colour(e.colour)), 0.28, 0.0, blended);
    blended.copyTo(roi, mask(box));
  }
  if (layers.outline) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask(box).clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE,
                     box.tl());
    if (e.dashed)
      DrawDashedContours(img, contours, Colour(e.colour));
    else
      cv::drawContours(img, contours, -1, Colour(e.colour), 2, cv::LINE_AA);
  }
}

// The 3σ ellipse of the position, projected to first order, around its projection `o`.
void DrawUncertainty(cv::Mat& img, const Transform& T_CP, const Intrinsics& K,
                     const OverlayEstimate& e, const Vec2& o, const cv::Scalar& colour) {
  const Vec3 X_C = T_CP * e.T_PO.translation();
  const Eigen::Matrix<double, 2, 3> J = K.ProjectJacobian(X_C) * T_CP.linear();
  const Eigen::Matrix2d S = J * e.position_covariance * J.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
  const Eigen::Vector2d ev = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  const double angle = std::atan2(axis.y(), axis.x()) * 180.0 / M_PI;
  const cv::Size axes(static_cast<int>(std::lround(3.0 * std::sqrt(ev[1]) * (1 << kShift))),
                      static_cast<int>(std::lround(3.0 * std::sqrt(ev[0]) * (1 << kShift))));
  cv::ellipse(img, Fx(o), axes, angle, 0, 360, colour, 1, cv::LINE_AA, kShift);
}

// A torque contact's friction cone, as its silhouette: two generators in the plane of the normal
// and the view ray, from the contact's projection `p`.
void DrawFrictionCone(cv::Mat& img, const OverlayFrame& frame, const Transform& T_CP,
                      const OverlayContact& c, const Vec2& p, const cv::Scalar& colour) {
  const Intrinsics& K = frame.K;
  const Vec3 view = (c.c_o_P - frame.T_PC.translation()).normalized();
  Vec3 side = c.normal_P.cross(view);
  if (side.norm() > 1e-6) {
    side = side.cross(c.normal_P).normalized();
    const double a = frame.friction_cone_deg * M_PI / 180.0, L = 0.02;
    for (double s : {-1.0, 1.0}) {
      Vec2 q;
      if (ProjectP(T_CP, K, c.c_o_P + L * (std::cos(a) * c.normal_P + s * std::sin(a) * side), q))
        Line(img, p, q, colour, 1);
    }
  }
}

// A contact's marker by kind: kinematic filled, torque ringed, rejected crossed, candidate a dot.
void DrawContactMarker(cv::Mat& img, const OverlayContact& c, const Vec2& p,
                       const cv::Scalar& colour) {
  switch (c.kind) {
    case OverlayContact::Kind::kKinematic:
      cv::circle(img, Fx(p), 5 << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
      cv::circle(img, Fx(p), 5 << kShift, cv::Scalar(255, 255, 255), 1, cv::LINE_AA, kShift);
      break;
    case OverlayContact::Kind::kTorque:
      cv::circle(img, Fx(p), 6 << kShift, colour, 2, cv::LINE_AA, kShift);
      break;
    case OverlayContact::Kind::kRejected:
      Line(img, p + Vec2(-4, -4), p + Vec2(4, 4), colour, 1);
      Line(img, p + Vec2(-4, 4), p + Vec2(4, -4), colour, 1);
      break;
    case OverlayContact::Kind::kCandidate:
      cv::circle(img, Fx(p), 2 << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
      break;
  }
}

// What the inspector has selected: a ring that no other marker uses, dark then yellow, so that it
// reads on light and dark backgrounds alike.
void DrawSelection(cv::Mat& img, const Vec2& p) {
  cv::circle(img, Fx(p), 11 << kShift, cv::Scalar(20, 20, 20), 4, cv::LINE_AA, kShift);
  cv::circle(img, Fx(p), 11 << kShift, cv::Scalar(255, 225, 0), 2, cv::LINE_AA, kShift);
}

// The HUD's lines, wrapped to the picture's width, on darkened boxes from the top-left.
void DrawGap(cv::Mat& img, const Transform& T_CP, const Intrinsics& K, const OverlayGap& g) {
  Vec2 a, b;
  if (!ProjectP(T_CP, K, g.link_P, a) || !ProjectP(T_CP, K, g.object_P, b)) return;
  const double mm = g.distance * 1000;
  const cv::Scalar c = mm <= -1.0   ? cv::Scalar(220, 40, 40)
                       : mm < 1.0   ? cv::Scalar(40, 170, 70)
                       : mm <= 10.0 ? cv::Scalar(235, 130, 20)
                                    : cv::Scalar(110, 110, 120);
  Line(img, a, b, c, 2);
  cv::circle(img, Fx(a), 3 << kShift, c, cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(img, Fx(b), 3 << kShift, c, 1, cv::LINE_AA, kShift);
  char label[32];
  if (std::abs(mm) < 1.0)
    std::snprintf(label, sizeof label, "touch");
  else
    std::snprintf(label, sizeof label, mm < 0.0 ? "%.0f mm in" : "%.0f mm", std::abs(mm));
  int base = 0;
  const cv::Size sz = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &base);
  // Beside the link's end, away from the object.
  const Vec2 away = (a - b).norm() > 1e-6 ? Vec2((a - b).normalized()) : Vec2(1, 0);
  const cv::Point at(static_cast<int>(a.x() + 8 * away.x() - (away.x() < 0 ? sz.width : 0)),
                     static_cast<int>(a.y() + 8 * away.y() + (away.y() > 0 ? sz.height : 0)));
  cv::rectangle(img, cv::Rect(at.x - 2, at.y - sz.height - 2, sz.width + 4, sz.height + 5),
                cv::Scalar(255, 255, 255), cv::FILLED);
  cv::putText(img, label, at, cv::FONT_HERSHEY_SIMPLEX, 0.4, c * 0.8, 1, cv::LINE_AA);
}

void DrawHud(cv::Mat& img, const std::vector<std::string>& hud) {
  int y = 6;
  std::vector<std::string> lines;
  for (const std::string& line : hud)
    for (std::string& piece : WrapHudLine(line, img.cols - 16)) lines.push_back(std::move(piece));
  for (const std::string& line : lines) {
    int base = 0;
    const cv::Size sz = cv::getTextSize(line, cv::FONT_HERSHEY_SIMPLEX, kHudScale, 1, &base);
    cv::Mat roi = img(cv::Rect(4, y, std::min(sz.width + 8, img.cols - 4),
                               std::min(sz.height + base + 6, img.rows - y)));
    roi = roi * 0.35;
    cv::putText(img, line, cv::Point(8, y + sz.height + 3), cv::FONT_HERSHEY_SIMPLEX, kHudScale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    y += sz.height + base + 8;
    if (y > img.rows - 20) break;
  }
}

// The legend: one swatch per estimate, bottom-left.
void DrawLegend(cv::Mat& img, const std::vector<OverlayEstimate>& estimates) {
  int x = 8;
  const int y = img.rows - 10;
  for (const OverlayEstimate& e : estimates) {
    int base = 0;
    const cv::Size sz = cv::getTextSize(e.name, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &base);
    cv::rectangle(img, cv::Rect(x - 3, y - sz.height - 5, sz.width + 26, sz.height + 10),
                  cv::Scalar(255, 255, 255), cv::FILLED);
    if (e.dashed)
      cv::line(img, cv::Point(x, y - 4), cv::Point(x + 14, y - 4), Colour(e.colour), 2);
    else
      cv::rectangle(img, cv::Rect(x, y - 10, 14, 10), Colour(e.colour), cv::FILLED);
    cv::putText(img, e.name, cv::Point(x + 18, y), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    x += sz.width + 34;
  }
}

}  // namespace

Image8 OverlayPainter::Paint(const OverlayFrame& frame, const OverlayLayers& layers) {
  const Intrinsics& K = frame.K;
  INHAND_CHECK(frame.camera.width == K.width && frame.camera.height == K.height &&
                   frame.camera.channels == 3,
               "overlay background must be RGB of the intrinsics' size");
  Image8 out = frame.camera;
  cv::Mat img(out.height, out.width, CV_8UC3, out.data.data());
  const Transform T_CP = frame.T_PC.inverse();

  // Silhouettes and outlines first, then the geometric markers on top. Every estimate's
  // silhouette comes from one render (a bit each, 16 at a time); tint and contours work inside
  // its bounding box.
  std::vector<std::uint8_t> mask_data(static_cast<std::size_t>(K.width) * K.height);
  for (std::size_t e0 = 0; e0 < frame.estimates.size() && (layers.silhouette || layers.outline);
       e0 += 16) {
    Scene scene;
    scene.K = K;
    scene.T_PC = frame.T_PC;
    const std::size_t e1 = std::min(frame.estimates.size(), e0 + 16);
    for (std::size_t i = e0; i < e1; ++i) {
      const std::size_t first = scene.items.size();
      AddObject(scene, object_meshes_, frame.estimates[i].T_PO, ObjectStyle());
      for (std::size_t k = first; k < scene.items.size(); ++k)
        scene.items[k].label = static_cast<std::uint16_t>(1u << (i - e0));
    }
    renderer_.RenderMasks(scene, masks_);
    for (std::size_t i = e0; i < e1; ++i)
      DrawSilhouette(img, masks_, mask_data, K, frame.estimates[i],
                     static_cast<std::uint16_t>(1u << (i - e0)), layers);
  }

  for (const OverlayEstimate& e : frame.estimates) {
    const cv::Scalar colour = Colour(e.colour);
    Vec2 o;
    const bool origin_visible = ProjectP(T_CP, K, e.T_PO.translation(), o);
    if (layers.uncertainty && origin_visible && e.position_covariance.norm() > 0.0)
      DrawUncertainty(img, T_CP, K, e, o, colour);
    if (layers.axes && origin_visible) {
      const Rgb axis_colours[3] = {{230, 30, 30}, {30, 190, 30}, {30, 60, 230}};
      for (int a = 0; a < 3; ++a) {
        Vec2 tip;
        if (ProjectP(T_CP, K, e.T_PO * (frame.axes_length * Vec3::Unit(a)), tip))
          Line(img, o, tip, Colour(axis_colours[a]), e.dashed ? 1 : 2);
      }
    }
    for (const OverlayContact& c : e.contacts) {
      Vec2 p;
      if (!ProjectP(T_CP, K, c.c_o_P, p)) continue;
      if (layers.cones && c.kind == OverlayContact::Kind::kTorque)
        DrawFrictionCone(img, frame, T_CP, c, p, colour);
      // Forces of torque-confirmed contacts only: a rejected candidate's λ̄ is no force.
      if (layers.forces && c.kind == OverlayContact::Kind::kTorque && c.force_P.norm() > 1e-9) {
        Vec2 q;
        if (ProjectP(T_CP, K, c.c_o_P + frame.force_scale * c.force_P, q))
          cv::arrowedLine(img, Fx(p), Fx(q), colour, 2, cv::LINE_AA, kShift, 0.25);
      }
      if (layers.contacts) DrawContactMarker(img, c, p, colour);
      if (c.selected) DrawSelection(img, p);
    }
    if (layers.features) {
      for (const OverlayFeature& f : e.features) {
        const cv::Scalar fc = f.inlier ? colour : cv::Scalar(200, 0, 200);
        Line(img, f.predicted, f.measured, fc, 1);
        cv::circle(img, Fx(f.measured), 4 << kShift, fc, 1, cv::LINE_AA, kShift);
        Line(img, f.predicted + Vec2(-3, 0), f.predicted + Vec2(3, 0), fc, 1);
        Line(img, f.predicted + Vec2(0, -3), f.predicted + Vec2(0, 3), fc, 1);
        if (f.selected) DrawSelection(img, f.measured);
      }
    }
  }

  if (layers.gaps)
    for (const OverlayGap& g : frame.gaps) DrawGap(img, T_CP, K, g);
  if (layers.hud && !frame.hud.empty()) DrawHud(img, frame.hud);
  if (layers.hud && !frame.estimates.empty()) DrawLegend(img, frame.estimates);
  return out;
}

void Inset(Image8& big, const Image8& small, const std::string& caption) {
  INHAND_CHECK(big.channels == 3 && small.channels == 3, "Inset takes RGB images");
  constexpr int kMargin = 6, kCaption = 16;
  const int x0 = big.width - small.width - kMargin, y0 = big.height - small.height - kMargin;
  INHAND_CHECK(x0 >= 1 && y0 - kCaption >= 1, "Inset: the small image does not fit");
  cv::Mat img(big.height, big.width, CV_8UC3, big.data.data());
  const cv::Mat part(small.height, small.width, CV_8UC3,
                     const_cast<std::uint8_t*>(small.data.data()));
  cv::rectangle(img,
                cv::Rect(x0 - 1, y0 - kCaption - 1, small.width + 2, small.height + kCaption + 2),
                cv::Scalar(30, 30, 30), cv::FILLED);
  part.copyTo(img(cv::Rect(x0, y0, small.width, small.height)));
  cv::putText(img, caption, cv::Point(x0 + 4, y0 - 4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

Image8 SideBySide(const std::vector<const Image8*>& images,
                  const std::vector<std::string>& captions) {
  INHAND_CHECK(!images.empty(), "SideBySide needs images");
  const int H = images[0]->height;
  std::vector<cv::Mat> tiles;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const Image8& im = *images[i];
    const cv::Mat m(im.height, im.width, CV_8UC3, const_cast<std::uint8_t*>(im.data.data()));
    cv::Mat scaled;
    if (im.height != H)
      cv::resize(m, scaled,
                 cv::Size(static_cast<int>(std::lround(im.width * double(H) / im.height)), H), 0, 0,
                 cv::INTER_AREA);
    else
      scaled = m.clone();
    if (i < captions.size() && !captions[i].empty()) {
      cv::rectangle(scaled, cv::Rect(0, 0, scaled.cols, 20), cv::Scalar(30, 30, 30), cv::FILLED);
      cv::putText(scaled, captions[i], cv::Point(6, 14), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
    tiles.push_back(scaled);
  }
  cv::Mat all;
  cv::hconcat(tiles, all);
  // Even sizes for H.264.
  if (all.cols % 2)
    cv::copyMakeBorder(all, all, 0, 0, 0, 1, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
  if (all.rows % 2)
    cv::copyMakeBorder(all, all, 0, 1, 0, 0, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
  Image8 out(all.cols, all.rows, 3);
  std::memcpy(out.data.data(), all.data, out.data.size());
  return out;
}

Image8 MainAndColumn(const Image8& main, const std::vector<const Image8*>& column,
                     const std::vector<std::string>& captions) {
  INHAND_CHECK(!main.empty() && !column.empty(), "MainAndColumn needs images");
  const int H = main.height;
  const int h = H / static_cast<int>(column.size());
  int column_width = 0;
  std::vector<cv::Mat> tiles;
  for (const Image8* im : column) {
    const cv::Mat m(im->height, im->width, CV_8UC3, const_cast<std::uint8_t*>(im->data.data()));
    cv::Mat scaled;
    cv::resize(
        m, scaled,
        cv::Size(std::max(1, static_cast<int>(std::lround(im->width * double(h) / im->height))), h),
        0, 0, cv::INTER_AREA);
    column_width = std::max(column_width, scaled.cols);
    tiles.push_back(scaled);
  }
  const int W = (main.width + column_width + 1) / 2 * 2;
  cv::Mat all(H + H % 2, W, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Mat m(main.height, main.width, CV_8UC3, const_cast<std::uint8_t*>(main.data.data()));
  m.copyTo(all(cv::Rect(0, 0, main.width, H)));
  constexpr double kScale = 0.45;
  constexpr int kLine = 18;
  if (!captions.empty() && !captions[0].empty()) {
    cv::rectangle(all, cv::Rect(0, 0, main.width, 20), cv::Scalar(30, 30, 30), cv::FILLED);
    cv::putText(all, captions[0], cv::Point(6, 14), cv::FONT_HERSHEY_SIMPLEX, kScale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    cv::Mat tile = tiles[i];
    if (i + 1 < captions.size() && !captions[i + 1].empty()) {
      // Words as long as they fit the tile, then a new line.
      std::vector<std::string> lines(1);
      std::istringstream words(captions[i + 1]);
      for (std::string word; words >> word;) {
        const std::string longer = lines.back().empty() ? word : lines.back() + " " + word;
        int base = 0;
        if (lines.back().empty() ||
            cv::getTextSize(longer, cv::FONT_HERSHEY_SIMPLEX, kScale, 1, &base).width + 12 <=
                tile.cols)
          lines.back() = longer;
        else
          lines.push_back(word);
      }
      const int bar = std::min(tile.rows, kLine * static_cast<int>(lines.size()) + 4);
      cv::rectangle(tile, cv::Rect(0, 0, tile.cols, bar), cv::Scalar(30, 30, 30), cv::FILLED);
      for (std::size_t l = 0; l < lines.size(); ++l)
        cv::putText(tile, lines[l], cv::Point(6, 14 + kLine * static_cast<int>(l)),
                    cv::FONT_HERSHEY_SIMPLEX, kScale, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
    tile.copyTo(all(cv::Rect(main.width, static_cast<int>(i) * h, tile.cols, tile.rows)));
  }
  Image8 out(all.cols, all.rows, 3);
  std::memcpy(out.data.data(), all.data, out.data.size());
  return out;
}

std::vector<std::string> WrapHudLine(const std::string& line, int max_width) {
  const auto fits = [&](const std::string& text) {
    int base = 0;
    return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, kHudScale, 1, &base).width <= max_width;
  };
  // Clauses end at ", " (which stays with the clause before it); a clause too wide for a line of
  // its own is cut between words.
  std::vector<std::string> parts;
  for (std::size_t i = 0; i < line.size();) {
    std::size_t end = line.find(", ", i);
    end = end == std::string::npos ? line.size() : end + 2;
    const std::string clause = line.substr(i, end - i);
    if (fits("  " + clause)) {
      parts.push_back(clause);
    } else {
      for (std::size_t w = 0; w < clause.size();) {
        std::size_t space = clause.find(' ', w);
        space = space == std::string::npos ? clause.size() : space + 1;
        parts.push_back(clause.substr(w, space - w));
        w = space;
      }
    }
    i = end;
  }
  std::vector<std::string> pieces(1);
  for (const std::string& part : parts) {
    if (pieces.back().find_first_not_of(' ') == std::string::npos || fits(pieces.back() + part)) {
      pieces.back() += part;
    } else {
      while (pieces.back().back() == ' ') pieces.back().pop_back();
      pieces.push_back("  " + part);
    }
  }
  while (!pieces.back().empty() && pieces.back().back() == ' ') pieces.back().pop_back();
  return pieces;
}

}  // namespace inhand
