#pragma once
// The simulated camera of the `realistic` profile (realism.hpp): image formation independent of
// the estimator's virtual view.
#include <random>
#include <vector>

#include "inhand/core/image.hpp"
#include "inhand/core/intrinsics.hpp"
#include "inhand/renderer/renderer.hpp"
#include "inhand/sessions/realism.hpp"

namespace inhand {

// A point lamp with cast shadows, a fill light and ambient light, in the scene's frame.
struct LightRig {
  Vec3 lamp = Vec3(0.45, -0.35, 0.95);
  Vec3 lamp_target = Vec3(0.0, 0.0, 0.1);
  Vec3 lamp_colour = Vec3(1.0, 0.92, 0.80);     // warm
  double lamp_power = 1.15;                     // irradiance factor at the target's distance
  Vec3 fill_direction = Vec3(-0.6, -0.2, 0.5);  // towards the fill light (no shadows)
  Vec3 fill_colour = Vec3(0.22, 0.25, 0.30);    // cool
  Vec3 ambient = Vec3(0.10, 0.11, 0.13);
  double specular = 0.35;
  double shininess = 60.0;
};

// Image formation of the simulated camera, independent of the estimator's virtual view: the
// renderer only provides albedo (unlit) and depth; light, shadows, highlights and the camera's
// own effects are computed here.
class CameraSimulator {
 public:
  // `K_true`: the true intrinsics, with the true lens distortion in K_true.distortion.
  CameraSimulator(Renderer& renderer, const Intrinsics& K_true, const RealismParams& params,
                  const Effects& effects, const LightRig& light, unsigned seed);
  // `subframes`: the scene at the exposure's sample times, oldest first (one when motion blur
  // is off); all with the same K (K_true without distortion) and background. Writes RGB.
  void Capture(const std::vector<Scene>& subframes, Image8& out);
  // The ideal (undistorted, unblurred) linear radiance of one scene, for tests: RGB floats.
  std::vector<float> Radiance(const Scene& scene);
  // Pixels of the ideal image that the distorted output needs around the true image.
  int margin() const { return margin_; }
  double last_exposure() const { return exposure_; }

 private:
  static constexpr int kShadowSize = 1024;  // [texels] of the lamp's shadow map
  void RenderShadowMap(const Scene& scene);
  void RenderPadded(const Scene& scene, std::vector<float>& rgb);
  Renderer& renderer_;
  Intrinsics K_;  // true, with distortion
  RealismParams params_;
  Effects effects_;
  LightRig light_;
  std::mt19937 rng_;
  int margin_ = 0;
  std::vector<float> map_x_, map_y_;  // output pixel -> padded ideal pixel
  double exposure_ = 1.0;
  Vec3 white_balance_ = Vec3::Ones();
  bool started_ = false;
  Scene shadow_scene_;
  std::vector<float> shadow_depth_;
  std::vector<Vec3> points_;  // scratch
  std::vector<float> rgb_;    // scratch
};

}  // namespace inhand
