#pragma once
// Internal (the GUI): the GL entry points of the interface's own context, its textures, the
// thread the player's offscreen renderers live on, and screenshots of the interface.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>

#include "inhand/core/image.hpp"

namespace inhand::app {

// GL entry points of the context that draws the interface: the window's (libGL, through GLFW)
// or the offscreen one (OSMesa, through the renderer's loader).
struct GuiGl {
  void (*GenTextures)(GLsizei, GLuint*) = nullptr;
  void (*BindTexture)(GLenum, GLuint) = nullptr;
  void (*TexImage2D)(GLenum, GLint, GLint, GLsizei, GLsizei, GLint, GLenum, GLenum,
                     const void*) = nullptr;
  void (*TexParameteri)(GLenum, GLenum, GLint) = nullptr;
  void (*PixelStorei)(GLenum, GLint) = nullptr;
  void (*Viewport)(GLint, GLint, GLsizei, GLsizei) = nullptr;
  void (*ClearColor)(GLfloat, GLfloat, GLfloat, GLfloat) = nullptr;
  void (*Clear)(GLbitfield) = nullptr;
  void (*ReadPixels)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void*) = nullptr;
  void (*ReadBuffer)(GLenum) = nullptr;
  void (*Finish)() = nullptr;

  template <typename Loader>
  void Load(Loader load) {
    const auto get = [&](auto& fn, const char* name) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(load(name));
    };
    get(GenTextures, "glGenTextures");
    get(BindTexture, "glBindTexture");
    get(TexImage2D, "glTexImage2D");
    get(TexParameteri, "glTexParameteri");
    get(PixelStorei, "glPixelStorei");
    get(Viewport, "glViewport");
    get(ClearColor, "glClearColor");
    get(Clear, "glClear");
    get(ReadPixels, "glReadPixels");
    get(ReadBuffer, "glReadBuffer");
    get(Finish, "glFinish");
  }
};

// An image shown in the interface: uploaded to the interface's GL context, drawn by ImGui.
struct Texture {
  GLuint id = 0;
  int width = 0, height = 0;
  void Upload(const GuiGl& gl, const Image8& im);
  void Show(float max_width) const;  // at most max_width wide, its aspect kept
};

// Runs tasks on one thread of its own, waiting for each. The player's OSMesa renderers live
// there: Mesa's dispatch is per thread, so they never disturb the window's GLX context.
class RenderThread {
 public:
  RenderThread() : thread_([this] { Loop(); }) {}
  ~RenderThread() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void Run(const std::function<void()>& task) {
    std::unique_lock<std::mutex> lock(mutex_);
    task_ = task;
    done_ = false;
    error_ = nullptr;
    cv_.notify_all();
    cv_.wait(lock, [this] { return done_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      cv_.wait(lock, [this] { return stop_ || task_; });
      if (stop_) return;
      std::function<void()> task = std::move(task_);
      task_ = nullptr;
      lock.unlock();
      std::exception_ptr error;
      try {
        task();
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      error_ = error;
      done_ = true;
      cv_.notify_all();
    }
  }
  std::mutex mutex_;
  std::condition_variable cv_;
  std::function<void()> task_;
  bool done_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

// The interface's framebuffer (width x height, bottom row first in GL) as a PNG at `path`.
void SaveScreenshot(const GuiGl& gl, int width, int height, const std::string& path);

// Draws ImGui's draw lists in the offscreen interface's context (OSMesa, compatibility profile)
// with OpenGL 1.1 vertex arrays, the way ImGui's OpenGL2 backend does, but through functions
// looked up at run time: ImGui's backend calls GL directly, which would make every process load
// OSMesa at start.
class OffscreenImGuiRenderer {
 public:
  // `load` returns the address of a GL function by name. Builds ImGui's font atlas and uploads it.
  template <typename Loader>
  explicit OffscreenImGuiRenderer(Loader load) {
    const auto get = [&](auto& fn, const char* name) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(load(name));
    };
    get(Enable, "glEnable");
    get(Disable, "glDisable");
    get(BlendFunc, "glBlendFunc");
    get(EnableClientState, "glEnableClientState");
    get(DisableClientState, "glDisableClientState");
    get(PolygonMode, "glPolygonMode");
    get(ShadeModel, "glShadeModel");
    get(TexEnvi, "glTexEnvi");
    get(Viewport, "glViewport");
    get(MatrixMode, "glMatrixMode");
    get(LoadIdentity, "glLoadIdentity");
    get(Ortho, "glOrtho");
    get(VertexPointer, "glVertexPointer");
    get(TexCoordPointer, "glTexCoordPointer");
    get(ColorPointer, "glColorPointer");
    get(Scissor, "glScissor");
    get(BindTexture, "glBindTexture");
    get(DrawElements, "glDrawElements");
    get(GenTextures, "glGenTextures");
    get(TexParameteri, "glTexParameteri");
    get(PixelStorei, "glPixelStorei");
    get(TexImage2D, "glTexImage2D");
    UploadFonts();
  }
  // Draws one frame's lists into the current framebuffer (fb_width x fb_height pixels).
  void Render(const struct ImDrawData* data) const;

 private:
  void UploadFonts();
  void (*Enable)(GLenum) = nullptr;
  void (*Disable)(GLenum) = nullptr;
  void (*BlendFunc)(GLenum, GLenum) = nullptr;
  void (*EnableClientState)(GLenum) = nullptr;
  void (*DisableClientState)(GLenum) = nullptr;
  void (*PolygonMode)(GLenum, GLenum) = nullptr;
  void (*ShadeModel)(GLenum) = nullptr;
  void (*TexEnvi)(GLenum, GLenum, GLint) = nullptr;
  void (*Viewport)(GLint, GLint, GLsizei, GLsizei) = nullptr;
  void (*MatrixMode)(GLenum) = nullptr;
  void (*LoadIdentity)() = nullptr;
  void (*Ortho)(GLdouble, GLdouble, GLdouble, GLdouble, GLdouble, GLdouble) = nullptr;
  void (*VertexPointer)(GLint, GLenum, GLsizei, const void*) = nullptr;
  void (*TexCoordPointer)(GLint, GLenum, GLsizei, const void*) = nullptr;
  void (*ColorPointer)(GLint, GLenum, GLsizei, const void*) = nullptr;
  void (*Scissor)(GLint, GLint, GLsizei, GLsizei) = nullptr;
  void (*BindTexture)(GLenum, GLuint) = nullptr;
  void (*DrawElements)(GLenum, GLsizei, GLenum, const void*) = nullptr;
  void (*GenTextures)(GLsizei, GLuint*) = nullptr;
  void (*TexParameteri)(GLenum, GLenum, GLint) = nullptr;
  void (*PixelStorei)(GLenum, GLint) = nullptr;
  void (*TexImage2D)(GLenum, GLint, GLint, GLsizei, GLsizei, GLint, GLenum, GLenum,
                     const void*) = nullptr;
  GLuint font_texture_ = 0;
};

}  // namespace inhand::app
