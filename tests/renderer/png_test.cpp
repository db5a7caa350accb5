// EncodePng (our fast encoder) against libpng: every image decodes, through OpenCV's libpng, to
// exactly the pixels encoded; and a camera-like frame is about as small as libpng makes it.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <random>

#include "inhand/sessions/image_io.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

Image8 CameraLike(int w, int h, int channels, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 2.0);
  Image8 img(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) {
        const bool inside = std::hypot(x - w / 2, y - h / 2) < h / 4;
        const double v = (inside ? 180 : 60) + 40 * std::sin(0.01 * x + c) +
                         30 * std::cos(0.013 * y) + noise(rng);
        img.pixel(x, y)[c] = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
      }
  return img;
}

void ExpectDecodesTo(const Image8& img, const std::string& what) {
  const std::vector<std::uint8_t> png = EncodePng(img);
  const cv::Mat decoded = cv::imdecode(
      cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<std::uint8_t*>(png.data())),
      cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(decoded.empty()) << what;
  ASSERT_EQ(decoded.cols, img.width) << what;
  ASSERT_EQ(decoded.rows, img.height) << what;
  ASSERT_EQ(decoded.channels(), img.channels) << what;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < img.channels; ++c) {
        const std::uint8_t got = decoded.ptr<std::uint8_t>(
            y)[x * img.channels + (img.channels == 3 ? 2 - c : 0)];  // BGR
        ASSERT_EQ(got, img.pixel(x, y)[c]) << what << " at " << x << "," << y << " channel " << c;
      }
}

TEST(EncodePng, LibpngDecodesExactlyWhatWasEncoded) {
  ExpectDecodesTo(CameraLike(640, 480, 3, 1), "camera-like RGB");
  ExpectDecodesTo(CameraLike(37, 11, 1, 2), "camera-like grey, odd size");
  ExpectDecodesTo(Image8(1, 1, 3), "one black pixel");
  Image8 flat(64, 48, 3);
  std::fill(flat.data.begin(), flat.data.end(), 200);
  ExpectDecodesTo(flat, "flat (one residual symbol)");
  Image8 noise(128, 96, 3);
  std::mt19937 rng(3);
  for (auto& b : noise.data) b = static_cast<std::uint8_t>(rng());
  ExpectDecodesTo(noise, "uniform noise (every symbol, long codes)");
  Image8 skewed(300, 200, 3);  // a few very rare residuals among very common ones: deep trees
  for (std::size_t i = 0; i < skewed.data.size(); ++i)
    skewed.data[i] = static_cast<std::uint8_t>(i % 9973 == 0 ? (i * 7) & 255 : (i / 3) % 2);
  ExpectDecodesTo(skewed, "skewed residuals");
}

TEST(EncodePng, AboutAsSmallAsLibpng) {
  const Image8 img = CameraLike(640, 480, 3, 4);
  const std::vector<std::uint8_t> ours = EncodePng(img);
  std::vector<std::uint8_t> theirs;
  const cv::Mat m(img.height, img.width, CV_8UC3, const_cast<std::uint8_t*>(img.data.data()));
  cv::imencode(".png", m, theirs, {cv::IMWRITE_PNG_COMPRESSION, 1});
  EXPECT_LT(ours.size(), img.data.size() * 3 / 5) << "no better than storing";
  EXPECT_LT(static_cast<double>(ours.size()), 1.15 * static_cast<double>(theirs.size()))
      << ours.size() << " vs libpng's " << theirs.size();
}

}  // namespace
}  // namespace inhand
