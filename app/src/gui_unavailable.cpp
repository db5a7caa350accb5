// `inhand gui` in a build configured with INHAND_BUILD_GUI=OFF (no GLFW, no Dear ImGui).
#include "inhand/app/gui.hpp"
#include "inhand/core/error.hpp"

namespace inhand::app {

int RunGui(const GuiCommand&) {
  throw InputError(
      "gui: this inhand was built without the GUI (configure with -DINHAND_BUILD_GUI=ON)");
}

}  // namespace inhand::app
