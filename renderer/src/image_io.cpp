#include "inhand/renderer/image_io.hpp"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "inhand/core/error.hpp"

namespace inhand {

Image8 ReadImage(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": image file not found");
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) throw InputError(path + ": not a readable image");
  Image8 out(bgr.cols, bgr.rows, 3);
  cv::Mat rgb(bgr.rows, bgr.cols, CV_8UC3, out.data.data());
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return out;
}

void WriteImage(const std::string& path, const Image8& image) {
  const int type = image.channels == 1 ? CV_8UC1 : image.channels == 3 ? CV_8UC3 : CV_8UC4;
  const cv::Mat in(image.height, image.width, type, const_cast<std::uint8_t*>(image.data.data()));
  cv::Mat bgr;
  if (image.channels == 3) cv::cvtColor(in, bgr, cv::COLOR_RGB2BGR);
  else if (image.channels == 4) cv::cvtColor(in, bgr, cv::COLOR_RGBA2BGRA);
  else bgr = in;
  bool ok = false;
  try {
    ok = cv::imwrite(path, bgr);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw InputError(path + ": cannot write image");
}

}  // namespace inhand
