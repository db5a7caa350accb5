#pragma once
// The interactive session: Dear ImGui over the pipeline. A GLFW + OpenGL3 window when a display
// exists; without one, --screenshot renders the same interface offscreen (OSMesa + ImGui's
// OpenGL2 backend). GUI state lives in a struct; user actions are queued and applied between
// frames; the pipeline knows nothing of the GUI.
#include <string>

namespace inhand::app {

struct GuiCommand {
  std::string session;
  std::string params;      // TrackerParams JSON
  std::string modalities;  // "" = every set the session supports
  int frames = -1;         // quit after this many frames (-1: run until closed)
  std::string screenshot;  // save the last frame as PNG
  double time = -1.0;      // start at this session time [s] (-1: the beginning)
  bool play = false;       // start playing
  // A script of inputs and checks run in the window, one command per frame or more (RunGui):
  // the session ends with it, exit 1 when a check failed.
  std::string script;
  int width = 1280, height = 800;
};
int RunGui(const GuiCommand& cmd);

}  // namespace inhand::app
