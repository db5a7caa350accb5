#include "inhand/sessions/image_io.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

// libpng and libjpeg print their own complaints ("libpng error: Read Error") to stderr before
// OpenCV returns an empty image: the user gets ours, naming the file, instead.
class QuietStderr {
 public:
  QuietStderr() : lock_(Mutex()) {
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null_fd = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null_fd >= 0) ::dup2(null_fd, STDERR_FILENO);
    if (null_fd >= 0) ::close(null_fd);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) ::dup2(saved_, STDERR_FILENO), ::close(saved_);
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  static std::mutex& Mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int saved_ = -1;
};

constexpr double kMaxPixels = 1 << 28;  // 268 megapixels

// A PNG's header says its size: refuse an absurd one before decoding (a 60000 x 60000 header
// made OpenCV assert without naming the file).
void CheckPngHeader(const unsigned char* head, std::size_t n, const std::string& what) {
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n < 24 || !std::equal(kPng, kPng + 8, head)) return;
  const auto be32 = [&](int at) {
    return (double(head[at]) * 256 + head[at + 1]) * 65536 + double(head[at + 2]) * 256 +
           head[at + 3];
  };
  const double w = be32(16), h = be32(20);
  if (w < 1 || h < 1 || w * h > kMaxPixels)
    throw InputError(what + ": the PNG header says " + std::to_string(static_cast<long long>(w)) +
                     "x" + std::to_string(static_cast<long long>(h)) +
                     " px; expected 1 to 268 million pixels");
}

// An OpenCV decode (BGR) as an RGB Image8, its failures as InputError naming `what`.
template <class Decode>
Image8 DecodedRgb(const std::string& what, Decode decode) {
  cv::Mat bgr;
  try {
    bgr = decode();
  } catch (const cv::Exception& e) {
    throw InputError(what + ": not a readable image (" + e.err + ")");
  }
  if (bgr.empty())
    throw InputError(what + ": not a readable image (unknown format, truncated or corrupt)");
  Image8 out(bgr.cols, bgr.rows, 3);
  cv::Mat rgb(bgr.rows, bgr.cols, CV_8UC3, out.data.data());
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return out;
}

}  // namespace

Image8 ReadImage(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": image file not found");
  unsigned char head[24] = {};
  std::ifstream(path, std::ios::binary).read(reinterpret_cast<char*>(head), sizeof(head));
  CheckPngHeader(head, sizeof(head), path);
  return DecodedRgb(path, [&] {
    const QuietStderr quiet;
    return cv::imread(path, cv::IMREAD_COLOR);
  });
}

void WriteImage(const std::string& path, const Image8& image) {
  const int type = image.channels == 1 ? CV_8UC1 : image.channels == 3 ? CV_8UC3 : CV_8UC4;
  const cv::Mat in(image.height, image.width, type, const_cast<std::uint8_t*>(image.data.data()));
  cv::Mat bgr;
  if (image.channels == 3)
    cv::cvtColor(in, bgr, cv::COLOR_RGB2BGR);
  else if (image.channels == 4)
    cv::cvtColor(in, bgr, cv::COLOR_RGBA2BGRA);
  else
    bgr = in;
  bool ok = false;
  try {
    ok = cv::imwrite(path, bgr);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw InputError(path + ": cannot write image");
}

Image8 DecodeImage(const std::uint8_t* data, std::size_t size, const std::string& context) {
  CheckPngHeader(data, size, context);
  return DecodedRgb(context, [&] {
    return cv::imdecode(
        cv::Mat(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data)),
        cv::IMREAD_COLOR);
  });
}

}  // namespace inhand
