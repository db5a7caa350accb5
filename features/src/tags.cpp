#include "inhand/features/tags.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/common/pjpeg.h>
#include <apriltag/common/zarray.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand {

void TagDetectorParams::Validate() const {
  const auto fail = [](const std::string& field, const std::string& value,
                       const std::string& expected) {
    throw InputError("tag detector parameter '" + field + "' is " + value + ", expected " +
                     expected);
  };
  if (family != "tag36h11" && family != "tag25h9" && family != "tag16h5" &&
      family != "tagStandard41h12" && family != "tagCircle21h7")
    fail("family", "'" + family + "'",
         "tag36h11, tag25h9, tag16h5, tagStandard41h12 or tagCircle21h7");
  if (!(decimate >= 1.0 && decimate <= 8.0))
    fail("decimate", std::to_string(decimate), "a number in [1, 8]");
  if (!(sigma >= 0.0 && sigma <= 10.0)) fail("sigma", std::to_string(sigma), "a number in [0, 10]");
  if (threads < 1 || threads > 64)
    fail("threads", std::to_string(threads), "an integer in [1, 64]");
  if (max_hamming < 0 || max_hamming > 3)
    fail("max_hamming", std::to_string(max_hamming), "an integer in [0, 3]");
}

namespace {

apriltag_family_t* CreateFamily(const std::string& f) {
  if (f == "tag36h11") return tag36h11_create();
  if (f == "tag25h9") return tag25h9_create();
  if (f == "tag16h5") return tag16h5_create();
  if (f == "tagStandard41h12") return tagStandard41h12_create();
  if (f == "tagCircle21h7") return tagCircle21h7_create();
  throw InputError(
      "tag family '" + f +
      "' is unknown, expected tag36h11, tag25h9, tag16h5, tagStandard41h12 or tagCircle21h7");
}

// Detaches a detector's families without freeing their tables (apriltag_detector_destroy would).
void ReleaseFamilies(apriltag_detector_t* detector) { zarray_clear(detector->tag_families); }

// One family per (name, bits corrected) per process, with its decode table. libapriltag builds
// the table when a family is first added to a detector (134 ms for tag36h11 correcting 2 bits;
// every tracker with tags has two detectors) and frees it when that detector is destroyed; a
// family that already has one is added without building it again. So the table is built here
// once, on a detector that lets go of the family before it is destroyed, and every TagDetector
// adds the shared family and lets go of it the same way. Detection only reads the table: the
// detectors of parallel sets share it safely. Kept for the process's life.
apriltag_family_t* SharedFamily(const std::string& name, int bits_corrected) {
  static std::mutex mutex;
  // Never destroyed: a map destroyed at exit would leave the families unreachable before the
  // leak checker looks (the sanitizer pass), and nothing frees them anyway.
  static auto* const families = new std::map<std::pair<std::string, int>, apriltag_family_t*>();
  const std::lock_guard<std::mutex> lock(mutex);
  apriltag_family_t*& family = (*families)[{name, bits_corrected}];
  if (family == nullptr) {
    family = CreateFamily(name);
    apriltag_detector_t* builder = apriltag_detector_create();
    apriltag_detector_add_family_bits(builder, family, bits_corrected);
    ReleaseFamilies(builder);
    apriltag_detector_destroy(builder);
  }
  return family;
}

}  // namespace

Image8 ReadGreyImage(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": image file not found");
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".jpg" || ext == ".jpeg") {
    int error = 0;
    // The decoder prints notes on unknown markers to stdout: keep stdout clean for JSON.
    std::fflush(stdout);
    const int saved = ::dup(STDOUT_FILENO);
    const int null_fd = ::open("/dev/null", O_WRONLY);
    if (saved >= 0 && null_fd >= 0) ::dup2(null_fd, STDOUT_FILENO);
    pjpeg_t* jpeg = pjpeg_create_from_file(path.c_str(), 0, &error);
    std::fflush(stdout);
    if (saved >= 0 && null_fd >= 0) ::dup2(saved, STDOUT_FILENO);
    if (saved >= 0) ::close(saved);
    if (null_fd >= 0) ::close(null_fd);
    if (jpeg == nullptr)
      throw InputError(path + ": not a readable JPEG (libapriltag's decoder, error " +
                       std::to_string(error) + ")");
    image_u8_t* im = pjpeg_to_u8_baseline(jpeg);
    Image8 out(im->width, im->height, 1);
    for (int y = 0; y < im->height; ++y)
      std::copy_n(im->buf + y * im->stride, im->width, out.pixel(0, y));
    image_u8_destroy(im);
    pjpeg_destroy(jpeg);
    return out;
  }
  Image8 rgb = ReadImage(path);
  Image8 out(rgb.width, rgb.height, 1);
  const cv::Mat in(rgb.height, rgb.width, CV_8UC3, rgb.data.data());
  cv::Mat grey(out.height, out.width, CV_8UC1, out.data.data());
  cv::cvtColor(in, grey, cv::COLOR_RGB2GRAY);
  return out;
}

struct TagDetector::Impl {
  apriltag_detector_t* detector = nullptr;
  std::vector<std::uint8_t> grey;
};

TagDetector::TagDetector(const TagDetectorParams& params)
    : impl_(std::make_unique<Impl>()), params_(params) {
  params_.Validate();
  Impl& d = *impl_;
  apriltag_family_t* family = SharedFamily(params_.family, params_.max_hamming);
  d.detector = apriltag_detector_create();
  apriltag_detector_add_family_bits(d.detector, family, params_.max_hamming);
  d.detector->quad_decimate = static_cast<float>(params_.decimate);
  d.detector->quad_sigma = static_cast<float>(params_.sigma);
  d.detector->refine_edges = params_.refine_edges;
  d.detector->nthreads = params_.threads;
}

TagDetector::~TagDetector() {
  if (!impl_->detector) return;
  ReleaseFamilies(impl_->detector);  // the shared family keeps its table
  apriltag_detector_destroy(impl_->detector);
}

std::vector<TagDetection> TagDetector::Detect(const Image8& image) {
  return Detect(image, PixelRect{0, 0, image.width, image.height});
}

std::vector<TagDetection> TagDetector::Detect(const Image8& image, const PixelRect& region) {
  Impl& d = *impl_;
  INHAND_CHECK(image.channels == 1 || image.channels == 3,
               "tag detection needs a grey or RGB image");
  const PixelRect r = region.ClippedTo(image.width, image.height);
  if (r.empty()) return {};
  const int w = r.width(), h = r.height();
  // libapriltag's quad detection reads out of bounds (SIGSEGV) on images whose decimated height
  // is under 3 px (1 x 2 at decimate 1, 100 x 4 at decimate 2: measured for decimate 1-4 on
  // 1-24 px); no tag fits in fewer than 8 px anyway (tag16h5 is 8 modules wide).
  const int minimum = std::max(8, static_cast<int>(std::ceil(2.0 * params_.decimate)) + 1);
  if (w < minimum || h < minimum) return {};
  d.grey.resize(std::size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = image.pixel(r.x0, r.y0 + y);
    std::uint8_t* out = &d.grey[std::size_t(y) * w];
    if (image.channels == 1) {
      std::copy_n(row, w, out);
    } else {
      for (int x = 0; x < w; ++x, row += 3)
        out[x] =
            static_cast<std::uint8_t>((299 * row[0] + 587 * row[1] + 114 * row[2] + 500) / 1000);
    }
  }
  image_u8_t im{w, h, w, d.grey.data()};
  zarray_t* found = apriltag_detector_detect(d.detector, &im);
  std::vector<TagDetection> out;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(found, i, &det);
    if (det->decision_margin < params_.min_decision_margin) continue;
    TagDetection t;
    t.family = params_.family;
    t.id = det->id;
    t.hamming = det->hamming;
    t.decision_margin = det->decision_margin;
    // libapriltag's coordinates put pixel centres at +0.5; the estimator's at integers.
    const Vec2 offset(r.x0 - 0.5, r.y0 - 0.5);
    for (int k = 0; k < 4; ++k)
      t.corners[static_cast<std::size_t>(k)] = Vec2(det->p[k][0], det->p[k][1]) + offset;
    t.center = Vec2(det->c[0], det->c[1]) + offset;
    out.push_back(t);
  }
  apriltag_detections_destroy(found);
  std::sort(out.begin(), out.end(), [](const TagDetection& a, const TagDetection& b) {
    return a.id != b.id ? a.id < b.id
                        : (a.center.x() != b.center.x() ? a.center.x() < b.center.x()
                                                        : a.center.y() < b.center.y());
  });
  return out;
}

}  // namespace inhand
