#include "frame_staging.hpp"

#include <algorithm>
#include <fstream>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"
#include "inhand/sessions/output_folder.hpp"

namespace fs = std::filesystem;

namespace inhand::ros {
namespace {

// A sensor_msgs/Image as RGB. Throws InputError naming the encoding when it is not supported.
Image8 ToRgb(const ImageMsg& m, const std::string& context) {
  const std::string& e = m.encoding;
  const int w = static_cast<int>(m.width), h = static_cast<int>(m.height);
  int bytes_per_pixel = 0;
  if (e == "rgb8" || e == "bgr8")
    bytes_per_pixel = 3;
  else if (e == "rgba8" || e == "bgra8")
    bytes_per_pixel = 4;
  else if (e == "mono8" || e == "8UC1")
    bytes_per_pixel = 1;
  else if (e == "mono16" || e == "16UC1")
    bytes_per_pixel = 2;
  else
    throw InputError(context + ": image encoding '" + e +
                     "' is not supported (expected rgb8, bgr8, rgba8, bgra8, mono8 or mono16)");
  if (w <= 0 || h <= 0 || m.step < static_cast<std::uint64_t>(w) * bytes_per_pixel ||
      m.data.size() < static_cast<std::uint64_t>(m.step) * (h - 1) +
                          static_cast<std::uint64_t>(w) * bytes_per_pixel)
    throw InputError(context + ": " + std::to_string(m.data.size()) + " bytes do not hold a " +
                     std::to_string(w) + "x" + std::to_string(h) + " " + e +
                     " image with a row step of " + std::to_string(m.step));
  Image8 out(w, h, 3);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = m.data.data() + static_cast<std::size_t>(y) * m.step;
    std::uint8_t* o = out.pixel(0, y);
    if (e == "rgb8") {
      std::copy(row, row + 3 * w, o);
    } else if (bytes_per_pixel >= 3) {
      const bool bgr = e[0] == 'b';
      for (int x = 0; x < w; ++x, row += bytes_per_pixel, o += 3)
        o[0] = row[bgr ? 2 : 0], o[1] = row[1], o[2] = row[bgr ? 0 : 2];
    } else if (bytes_per_pixel == 1) {
      for (int x = 0; x < w; ++x, o += 3) o[0] = o[1] = o[2] = row[x];
    } else {
      for (int x = 0; x < w; ++x, o += 3) {
        const int v =
            m.is_bigendian ? row[2 * x] << 8 | row[2 * x + 1] : row[2 * x + 1] << 8 | row[2 * x];
        o[0] = o[1] = o[2] = static_cast<std::uint8_t>((v + 128) / 257);
      }
    }
  }
  return out;
}

}  // namespace

Encoded EncodeFrame(const Payload& payload, const std::string& context) {
  if (const auto* raw = std::get_if<ImageMsg>(&payload)) {
    const int w = static_cast<int>(raw->width), h = static_cast<int>(raw->height);
    if (raw->encoding == "rgb8" && w > 0 && h > 0 && raw->step >= raw->width * 3 &&
        raw->data.size() >= std::size_t{raw->step} * raw->height)
      return {EncodePng(raw->data.data(), w, h, 3, raw->step), "png", w,
              h};  // straight from the message
    return {EncodePng(ToRgb(*raw, context)), "png", w, h};
  }
  const auto& c = std::get<CompressedImageMsg>(payload);
  std::string f = c.format;
  std::transform(f.begin(), f.end(), f.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  const bool png = f.find("png") != std::string::npos,
             jpeg = f.find("jpeg") != std::string::npos || f.find("jpg") != std::string::npos;
  if (!png && !jpeg)
    throw InputError(context + ": compressed image format '" + c.format +
                     "' is not supported (expected jpeg or png)");
  const Image8 img = DecodeImage(c.data.data(), c.data.size(), context);
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
