#include "inhand/ros/camera_messages.hpp"

#include <algorithm>
#include <cctype>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand::ros {

namespace {

// Whether a CompressedImage's format names a codec inhand decodes (jpeg or png).
bool IsDecodableFormat(const std::string& format) {
  std::string f = format;
  std::transform(f.begin(), f.end(), f.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return f.find("png") != std::string::npos || f.find("jpeg") != std::string::npos ||
         f.find("jpg") != std::string::npos;
}

}  // namespace

// A sensor_msgs/Image as RGB. Throws InputError naming the encoding when it is not supported.
Image8 ImageOf(const ImageMsg& m, const std::string& context) {
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

Image8 ImageOf(const CompressedImageMsg& m, const std::string& context) {
  if (!IsDecodableFormat(m.format))
    throw InputError(context + ": compressed image format '" + m.format +
                     "' is not supported (expected jpeg or png)");
  return DecodeImage(m.data.data(), m.data.size(), context);
}

Intrinsics IntrinsicsOf(const CameraInfoMsg& m, const std::string& context) {
  Intrinsics K;
  K.width = static_cast<int>(m.width);
  K.height = static_cast<int>(m.height);
  K.fx = m.k[0];
  K.fy = m.k[4];
  K.cx = m.k[2];
  K.cy = m.k[5];
  if (m.k[1] != 0.0)
    throw InputError(context + ": K has a skew term (" + std::to_string(m.k[1]) +
                     "), which inhand's pinhole model does not have");
  const bool zeros = std::all_of(m.d.begin(), m.d.end(), [](double v) { return v == 0.0; });
  if (!zeros) {
    if (m.distortion_model == "plumb_bob" || m.distortion_model == "rational_polynomial") {
      // plumb_bob: k1 k2 t1 t2 k3 (OpenCV's order); rational_polynomial adds k4 k5 k6.
      for (std::size_t i = 5; i < m.d.size(); ++i)
        if (m.d[i] != 0.0)
          throw InputError(context + ": distortion coefficient " + std::to_string(i) + " of " +
                           m.distortion_model +
                           " is not zero; inhand supports plumb_bob (k1, k2, p1, p2, k3)");
      for (std::size_t i = 0; i < 5 && i < m.d.size(); ++i) K.distortion[i] = m.d[i];
    } else {
      throw InputError(context + ": distortion model '" + m.distortion_model +
                       "' is not supported (expected plumb_bob)");
    }
  }
  K.Validate(context);
  return K;
}

}  // namespace inhand::ros
