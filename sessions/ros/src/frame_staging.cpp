#include "frame_staging.hpp"

#include <algorithm>
#include <fstream>

#include "inhand/core/error.hpp"
#include "inhand/ros/camera_messages.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"

namespace fs = std::filesystem;

namespace inhand::ros {

Encoded EncodeFrame(const Payload& payload, const std::string& context) {
  if (const auto* raw = std::get_if<ImageMsg>(&payload)) {
    const int w = static_cast<int>(raw->width), h = static_cast<int>(raw->height);
    if (raw->encoding == "rgb8" && w > 0 && h > 0 && raw->step >= raw->width * 3 &&
        raw->data.size() >= std::size_t{raw->step} * raw->height)
      return {EncodePng(raw->data.data(), w, h, 3, raw->step), "png", w,
              h};  // straight from the message
    return {EncodePng(ImageOf(*raw, context)), "png", w, h};
  }
  const auto& c = std::get<CompressedImageMsg>(payload);
  const Image8 img = ImageOf(c, context);
  // The bytes' own signature decides the extension (a "jpeg" message holding a PNG happens).
  const bool is_png = c.data.size() > 4 && c.data[0] == 0x89 && c.data[1] == 'P';
  return {c.data, is_png ? "png" : "jpg", img.width, img.height};
}

FrameStaging::FrameStaging(const std::string& out)
    : dir_(PrepareStaging(fs::absolute(out).lexically_normal().string() + "-frames")) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw InputError(dir_.string() + ": cannot create (" + ec.message() + ")");
}

FrameStaging::~FrameStaging() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

StagedFrame FrameStaging::Stage(std::uint64_t message, const Encoded& e) const {
  const std::string file =
      (dir_ / ("message_" + std::to_string(message) + "." + e.extension)).string();
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(e.bytes.data()),
            static_cast<std::streamsize>(e.bytes.size()));
  out.close();
  if (!out) throw InputError(file + ": cannot write");
  return {file, e.extension, e.width, e.height};
}

}  // namespace inhand::ros
