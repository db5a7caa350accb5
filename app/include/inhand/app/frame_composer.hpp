#pragma once
// The annotated pictures of one camera frame (the paper's Fig. 1 and more): camera image with
// every set's overlays | virtual view at the estimate of the last set | external 3-D view. For
// sessions without a camera, the external 3-D view alone, with contacts and forces drawn in.
#include <memory>

#include "inhand/app/player.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand::app {

class FrameComposer {
 public:
  explicit FrameComposer(const SessionPlayer& player);
  Image8 Compose(int camera_frame, double t, const OverlayLayers& layers = {});
  // The external 3-D view at the player's current state (hand, every set's estimate, truth,
  // contacts, forces and a HUD), width x height pixels.
  Image8 ComposeExternal(double t, int width = 960, int height = 720, const OverlayLayers& layers = {});
  // The external 3-D view's orbit around the object (the GUI drags it).
  struct Orbit {
    double azimuth = -2.2;   // [rad]
    double elevation = 0.55; // [rad]
    double distance = 0.42;  // [m]
  } orbit;

 private:
  // Every set's estimate with its contacts, and the HUD lines, as the overlays take them.
  void AddEstimates(OverlayFrame* frame, double t) const;
  // The 3-D scene around the palm: hand, truth dark, estimates translucent, seen through K.
  Scene ExternalScene(double t, const Intrinsics& K) const;
  const SessionPlayer& p_;
  Renderer renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::unique_ptr<OverlayPainter> painter_;
};

}  // namespace inhand::app
