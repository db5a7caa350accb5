#include "gui_gl.hpp"

#include <imgui.h>

#include <algorithm>
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

}  // namespace inhand::app
