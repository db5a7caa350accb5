#pragma once
// Annotated frames like the paper's Fig. 1: each estimate drawn over the camera image as a
// translucent silhouette with an outline in its modality's colour (ground truth black, dashed),
// with contacts, forces, friction cones, feature matches, object axes, the projected position
// uncertainty and a text HUD. Plain input data: the app converts filter traces into it.
#include <string>
#include <vector>

#include "inhand/renderer/renderer.hpp"

namespace inhand {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
// The paper's colours: joints red, + torques blue, + AprilTag orange, + features green.
constexpr Rgb kColourJoints{214, 39, 40};
constexpr Rgb kColourTorques{31, 119, 220};
constexpr Rgb kColourTags{255, 140, 0};
constexpr Rgb kColourFeatures{44, 160, 44};
constexpr Rgb kColourTruth{0, 0, 0};
// The other combinations of j with t, a, f (hands without torque sensors: ja, jf), distinct
// from the paper's four and from each other.
constexpr Rgb kColourJointsTags{148, 103, 189};          // ja: purple
constexpr Rgb kColourJointsFeatures{140, 86, 75};        // jf: brown
constexpr Rgb kColourJointsTagsFeatures{227, 119, 194};  // jaf: pink
constexpr Rgb kColourAll{23, 190, 207};                  // jtaf: cyan

struct OverlayLayers {
  bool silhouette = true;  // translucent fill
  bool outline = true;
  bool contacts = true;
  bool forces = true;
  bool cones = true;
  bool features = true;
  bool axes = true;
  bool uncertainty = true;
  bool hud = true;
  bool gaps = true;  // OverlayFrame::gaps
};

struct OverlayContact {
  enum class Kind { kKinematic, kTorque, kRejected, kCandidate };
  Kind kind = Kind::kCandidate;
  Vec3 c_o_P = Vec3::Zero();
  Vec3 c_f_P = Vec3::Zero();
  Vec3 normal_P = Vec3::UnitZ();  // link → object
  Vec3 force_P = Vec3::Zero();    // [N]
  bool selected = false;          // ringed in the selection's colour (the GUI's inspector)
};

struct OverlayFeature {
  Vec2 measured = Vec2::Zero();   // [px]
  Vec2 predicted = Vec2::Zero();  // [px]
  bool inlier = true;
  bool selected = false;  // ringed in the selection's colour (the GUI's inspector)
};

struct OverlayEstimate {
  std::string name;
  Rgb colour;
  Transform T_PO = Transform::Identity();
  Mat3 position_covariance = Mat3::Zero();  // [m²]
  bool dashed = false;                      // ground truth style
  std::vector<OverlayContact> contacts;
  std::vector<OverlayFeature> features;
};

// How far a link is from the object (a depth cue for views that cannot show it): a segment from
// the link's nearest point to the object's, coloured by the distance (within 1 mm "touch" green,
// 1 mm or more inside red, within 10 mm orange, farther grey), labelled with it.
struct OverlayGap {
  Vec3 link_P = Vec3::Zero();
  Vec3 object_P = Vec3::Zero();
  double distance = 0.0;  // [m] signed (< 0: inside)
};

struct OverlayFrame {
  Image8 camera;  // RGB background, the size of K
  Transform T_PC = Transform::Identity();
  Intrinsics K;
  std::vector<OverlayEstimate> estimates;  // drawn in order; put ground truth first
  std::vector<std::string> hud;
  std::vector<OverlayGap> gaps;
  double friction_cone_deg = 45.0;
  double force_scale = 0.004;  // [m/N] arrow length per newton
  double axes_length = 0.03;   // [m]
};

class OverlayPainter {
 public:
  // `object_meshes` are the object's meshes uploaded to `renderer`.
  OverlayPainter(Renderer& renderer, std::vector<int> object_meshes);
  Image8 Paint(const OverlayFrame& frame, const OverlayLayers& layers = {});
  // The object's silhouette mask (1 inside) at T_PO: also used for tests.
  std::vector<std::uint8_t> Silhouette(const Transform& T_PO, const Transform& T_PC,
                                       const Intrinsics& K);

 private:
  Renderer& renderer_;
  std::vector<int> object_meshes_;
  RenderOutput scratch_;
  std::vector<std::uint16_t> masks_;
};

// A HUD line broken between words so that every piece is at most `max_width` pixels wide in the
// HUD's font (a single word wider than that stays whole); pieces after the first are indented.
std::vector<std::string> WrapHudLine(const std::string& line, int max_width);

// `small` framed in the lower right corner of `big`, a caption bar above it.
void Inset(Image8& big, const Image8& small, const std::string& caption);

// Places images side by side, scaled to the first one's height, with a caption bar each.
Image8 SideBySide(const std::vector<const Image8*>& images,
                  const std::vector<std::string>& captions = {});

// `main` at its own size on the left; the images of `column` stacked on its right, each scaled to
// 1/n of its height (n of them), their captions broken between words to fit. captions[0] is
// main's, then the column's in order. Even sizes (H.264).
Image8 MainAndColumn(const Image8& main, const std::vector<const Image8*>& column,
                     const std::vector<std::string>& captions = {});

}  // namespace inhand
