#pragma once
// The annotated pictures of one camera frame (the paper's Fig. 1 and more): camera image with
// every set's overlays | virtual view at the estimate of the last set | external 3-D view.
#include <memory>

#include "inhand/app/player.hpp"
#include "inhand/renderer/overlay.hpp"
#include "inhand/renderer/views.hpp"

namespace inhand::app {

class FrameComposer {
 public:
  explicit FrameComposer(const SessionPlayer& player);
  Image8 Compose(int camera_frame, double t, const OverlayLayers& layers = {});
  // The external 3-D view's orbit around the object (the GUI drags it).
  struct Orbit {
    double azimuth = -2.2;   // [rad]
    double elevation = 0.55; // [rad]
    double distance = 0.42;  // [m]
  } orbit;

 private:
  const SessionPlayer& p_;
  Renderer renderer_;
  HandMeshes hand_meshes_;
  std::vector<int> object_meshes_;
  std::unique_ptr<OverlayPainter> painter_;
};

}  // namespace inhand::app
