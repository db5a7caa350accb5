#include "gui_gl.hpp"

#include <imgui.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "inhand/sessions/image_io.hpp"

namespace inhand::app {

void Texture::Upload(const GuiGl& gl, const Image8& im) {
  if (im.empty()) return;
  if (id == 0) gl.GenTextures(1, &id);
  gl.BindTexture(GL_TEXTURE_2D, id);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const GLenum format = im.channels == 1 ? GL_LUMINANCE : GL_RGB;
  gl.TexImage2D(GL_TEXTURE_2D, 0, im.channels == 1 ? GL_LUMINANCE : GL_RGB, im.width, im.height, 0,
                format, GL_UNSIGNED_BYTE, im.data.data());
  width = im.width;
  height = im.height;
}

void Texture::Show(float max_width) const {
  if (id == 0) {
    ImGui::TextDisabled("(no image yet)");
    return;
  }
  const float w = std::min(max_width, static_cast<float>(width));
  ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(id)),
               ImVec2(w, w * height / width));
}

void SaveScreenshot(const GuiGl& gl, int width, int height, const std::string& path) {
  Image8 img(width, height, 3);
  std::vector<std::uint8_t> rows(static_cast<std::size_t>(width) * height * 3);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  for (int y = 0; y < height; ++y)
    std::copy_n(&rows[static_cast<std::size_t>(height - 1 - y) * width * 3], width * 3,
                img.pixel(0, y));
  WriteImage(path, img);
}

void OffscreenImGuiRenderer::UploadFonts() {
  ImGuiIO& io = ImGui::GetIO();
  io.BackendRendererName = "inhand_offscreen_gl";
  unsigned char* pixels = nullptr;
  int width = 0, height = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &width, &height);
  GenTextures(1, &font_texture_);
  BindTexture(GL_TEXTURE_2D, font_texture_);
  TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  PixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
  io.Fonts->SetTexID(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(font_texture_)));
}

void OffscreenImGuiRenderer::Render(const ImDrawData* data) const {
  const int fb_width = static_cast<int>(data->DisplaySize.x * data->FramebufferScale.x);
  const int fb_height = static_cast<int>(data->DisplaySize.y * data->FramebufferScale.y);
  if (fb_width <= 0 || fb_height <= 0) return;
  // Alpha blending, no culling or depth, scissor per command, textured vertex colours; an
  // orthographic projection over ImGui's display rectangle (y down).
  Enable(GL_BLEND);
  BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  for (GLenum off : {GL_CULL_FACE, GL_DEPTH_TEST, GL_STENCIL_TEST, GL_LIGHTING, GL_COLOR_MATERIAL})
    Disable(off);
  Enable(GL_SCISSOR_TEST);
  Enable(GL_TEXTURE_2D);
  EnableClientState(GL_VERTEX_ARRAY);
  EnableClientState(GL_TEXTURE_COORD_ARRAY);
  EnableClientState(GL_COLOR_ARRAY);
  PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  ShadeModel(GL_SMOOTH);
  TexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE);
  Viewport(0, 0, fb_width, fb_height);
  const ImVec2 pos = data->DisplayPos, size = data->DisplaySize, scale = data->FramebufferScale;
  MatrixMode(GL_PROJECTION);
  LoadIdentity();
  Ortho(pos.x, pos.x + size.x, pos.y + size.y, pos.y, -1.0, 1.0);
  MatrixMode(GL_MODELVIEW);
  LoadIdentity();
  const GLenum index_type = sizeof(ImDrawIdx) == 2 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
  for (int n = 0; n < data->CmdListsCount; ++n) {
    const ImDrawList* list = data->CmdLists[n];
    const auto* vertices = reinterpret_cast<const char*>(list->VtxBuffer.Data);
    VertexPointer(2, GL_FLOAT, sizeof(ImDrawVert), vertices + offsetof(ImDrawVert, pos));
    TexCoordPointer(2, GL_FLOAT, sizeof(ImDrawVert), vertices + offsetof(ImDrawVert, uv));
    ColorPointer(4, GL_UNSIGNED_BYTE, sizeof(ImDrawVert), vertices + offsetof(ImDrawVert, col));
    for (const ImDrawCmd& cmd : list->CmdBuffer) {
      if (cmd.UserCallback) {  // the interface adds none but ImGui's own reset
        if (cmd.UserCallback != ImDrawCallback_ResetRenderState) cmd.UserCallback(list, &cmd);
        continue;
      }
      const float x0 = (cmd.ClipRect.x - pos.x) * scale.x, y0 = (cmd.ClipRect.y - pos.y) * scale.y;
      const float x1 = (cmd.ClipRect.z - pos.x) * scale.x, y1 = (cmd.ClipRect.w - pos.y) * scale.y;
      if (x1 <= x0 || y1 <= y0) continue;
      Scissor(static_cast<int>(x0), static_cast<int>(fb_height - y1), static_cast<int>(x1 - x0),
              static_cast<int>(y1 - y0));
      BindTexture(GL_TEXTURE_2D,
                  static_cast<GLuint>(reinterpret_cast<std::uintptr_t>(cmd.GetTexID())));
      DrawElements(GL_TRIANGLES, static_cast<GLsizei>(cmd.ElemCount), index_type,
                   list->IdxBuffer.Data + cmd.IdxOffset);
    }
  }
  // The next frame clears the whole framebuffer.
  DisableClientState(GL_COLOR_ARRAY);
  DisableClientState(GL_TEXTURE_COORD_ARRAY);
  DisableClientState(GL_VERTEX_ARRAY);
  Disable(GL_SCISSOR_TEST);
}

}  // namespace inhand::app
