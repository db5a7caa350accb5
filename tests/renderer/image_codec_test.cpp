// ReadImage/DecodeImage/EncodeJpeg/WriteImage (libpng and libjpeg called directly) against
// OpenCV's imgcodecs, an independent implementation: every PNG colour type and bit depth decodes
// to the pixels OpenCV's IMREAD_COLOR gives, JPEGs decode to the same pixels, our JPEG encoder
// writes what OpenCV's writes at the same quality, and bad bytes are refused with the name.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdlib>
#include <fstream>
#include <random>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"
#include "test_support.hpp"

namespace inhand {
namespace {

cv::Mat Noise(int rows, int cols, int type, unsigned seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  cv::GaussianBlur(m, m, cv::Size(5, 5), 1.5);  // some structure, as in a photograph
  return m;
}

// OpenCV's decode of the same bytes, as RGB.
cv::Mat Theirs(const std::vector<std::uint8_t>& bytes) {
  cv::Mat bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

void ExpectSamePixels(const Image8& ours, const cv::Mat& theirs, const std::string& what) {
  ASSERT_EQ(ours.channels, 3) << what;
  ASSERT_EQ(ours.width, theirs.cols) << what;
  ASSERT_EQ(ours.height, theirs.rows) << what;
  const cv::Mat o(ours.height, ours.width, CV_8UC3, const_cast<std::uint8_t*>(ours.data.data()));
  EXPECT_EQ(cv::norm(o, theirs, cv::NORM_INF), 0.0) << what;
}

TEST(ImageCodec, EveryPngKindDecodesAsOpenCvDecodesIt) {
  struct Case {
    const char* name;
    cv::Mat image;
  };
  cv::Mat rgba = Noise(37, 53, CV_8UC4, 4);
  rgba.forEach<cv::Vec4b>([](cv::Vec4b& p, const int* at) { p[3] = (at[0] * 7) % 256; });
  const std::vector<Case> cases = {
      {"grey 8", Noise(31, 47, CV_8UC1, 1)},  {"grey 16", Noise(29, 41, CV_16UC1, 2)},
      {"rgb 8", Noise(33, 45, CV_8UC3, 3)},   {"rgba 8", rgba},
      {"rgb 16", Noise(27, 39, CV_16UC3, 5)}, {"rgba 16", Noise(25, 35, CV_16UC4, 6)},
  };
  for (const Case& c : cases)
    for (int level : {0, 1, 9}) {
      std::vector<std::uint8_t> png;
      ASSERT_TRUE(cv::imencode(".png", c.image, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
      ExpectSamePixels(DecodeImage(png.data(), png.size(), c.name), Theirs(png),
                       std::string(c.name) + " level " + std::to_string(level));
    }
  // Palette, 1-bit grey and interlaced files, as other writers make them.
  const test::TempDir dir;
  const std::string file = dir / "p.png";
  for (const std::string& args :
       {std::string("-type Palette"), std::string("-colorspace Gray -depth 1"),
        std::string("-interlace PNG")}) {
    const std::string cmd =
        "convert -seed 3 -size 40x30 plasma:fractal " + args + " png:" + file + " 2>/dev/null";
    if (std::system(cmd.c_str()) != 0) GTEST_SKIP() << "ImageMagick's convert is not available";
    std::ifstream in(file, std::ios::binary);
    const std::vector<std::uint8_t> png((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
    ExpectSamePixels(ReadImage(file), Theirs(png), args);
  }
}

TEST(ImageCodec, JpegDecodesAndEncodesAsOpenCvDoes) {
  const cv::Mat bgr = Noise(48, 64, CV_8UC3, 7);
  for (int quality : {30, 75, 95}) {
    std::vector<std::uint8_t> theirs_jpg;
    ASSERT_TRUE(cv::imencode(".jpg", bgr, theirs_jpg, {cv::IMWRITE_JPEG_QUALITY, quality}));
    const std::string what = "quality " + std::to_string(quality);
    ExpectSamePixels(DecodeImage(theirs_jpg.data(), theirs_jpg.size(), what), Theirs(theirs_jpg),
                     what);
    Image8 rgb(bgr.cols, bgr.rows, 3);
    cv::Mat rgb_view(rgb.height, rgb.width, CV_8UC3, rgb.data.data());
    cv::cvtColor(bgr, rgb_view, cv::COLOR_BGR2RGB);
    const std::vector<std::uint8_t> ours_jpg = EncodeJpeg(rgb, quality);
    // The same encoder settings: the same pixels after decoding (the bytes may differ in markers).
    const cv::Mat a = Theirs(ours_jpg), b = Theirs(theirs_jpg);
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << what;
  }
  std::vector<std::uint8_t> grey_jpg;
  ASSERT_TRUE(cv::imencode(".jpg", Noise(20, 30, CV_8UC1, 8), grey_jpg));
  ExpectSamePixels(DecodeImage(grey_jpg.data(), grey_jpg.size(), "grey"), Theirs(grey_jpg),
                   "grey jpeg");
}

TEST(ImageCodec, WrittenFilesReadBackThroughOpenCv) {
  const test::TempDir dir;
  Image8 rgb(21, 17, 3);
  for (std::size_t i = 0; i < rgb.data.size(); ++i) rgb.data[i] = static_cast<std::uint8_t>(i * 31);
  const std::string png = dir / "a.png";
  WriteImage(png, rgb);
  cv::Mat back = cv::imread(png, cv::IMREAD_COLOR);
  cv::cvtColor(back, back, cv::COLOR_BGR2RGB);
  ExpectSamePixels(rgb, back, "written png");
  ExpectSamePixels(ReadImage(png), back, "read png");
  Image8 rgba(9, 7, 4);
  for (std::size_t i = 0; i < rgba.data.size(); ++i) rgba.data[i] = static_cast<std::uint8_t>(i);
  WriteImage(png, rgba);
  const cv::Mat unchanged = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(unchanged.channels(), 4);
  EXPECT_EQ(unchanged.at<cv::Vec4b>(6, 8)[3], rgba.pixel(8, 6)[3]);
  const std::string jpg = dir / "a.JPG";
  WriteImage(jpg, rgb);
  EXPECT_FALSE(cv::imread(jpg, cv::IMREAD_COLOR).empty());
  EXPECT_THROW(WriteImage(dir / "a.bmp", rgb), InputError);
}

TEST(ImageCodec, BadBytesAreRefusedWithTheirName) {
  const auto message = [](const std::vector<std::uint8_t>& bytes) {
    try {
      DecodeImage(bytes.data(), bytes.size(), "frame_7.png");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", Noise(30, 30, CV_8UC3, 9), png));
  std::vector<std::uint8_t> truncated(png.begin(), png.begin() + png.size() / 2);
  EXPECT_NE(message(truncated).find("frame_7.png: not a readable image"), std::string::npos)
      << message(truncated);
  std::vector<std::uint8_t> huge = png;  // IHDR claims 60000 x 60000
  for (int at : {16, 20}) huge[at] = 0, huge[at + 1] = 0, huge[at + 2] = 0xEA, huge[at + 3] = 0x60;
  EXPECT_NE(message(huge).find("60000x60000"), std::string::npos) << message(huge);
  std::vector<std::uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", Noise(30, 30, CV_8UC3, 9), jpg));
  jpg.resize(40);
  EXPECT_NE(message(jpg).find("JPEG"), std::string::npos) << message(jpg);
  EXPECT_NE(message({'B', 'M', 0, 0}).find("expected PNG or JPEG"), std::string::npos);
  EXPECT_NE(message({}).find("frame_7.png"), std::string::npos);
}

}  // namespace
}  // namespace inhand
