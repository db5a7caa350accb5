#pragma once
// AprilTag detection (libapriltag behind the .cpp). Corners are in the estimator's pixel
// convention (core/intrinsics.hpp: pixel centres at integer coordinates) and in the library's
// order: bottom-left, bottom-right, top-right, top-left of the tag as printed (TagPlacement's
// CornersO order).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "inhand/core/image.hpp"
#include "inhand/core/object_model.hpp"
#include "inhand/core/so3.hpp"

namespace inhand {

struct TagDetection {
  std::string family;
  int id = -1;
  std::array<Vec2, 4> corners;
  Vec2 center = Vec2::Zero();
  double decision_margin = 0.0;
  int hamming = 0;
};

struct TagDetectorParams {
  std::string family = "tag36h11";  // tag36h11, tag25h9, tag16h5, tagStandard41h12, tagCircle21h7
  double decimate = 2.0;            // quad_decimate: > 1 is faster, less precise
  bool refine_edges = true;
  double sigma = 0.0;  // [px] Gaussian blur before quad detection
  int threads = 1;
  int max_hamming = 2;               // bit errors corrected (libapriltag's default)
  double min_decision_margin = 0.0;  // detections with a smaller margin are dropped
  // Throws InputError naming the field.
  void Validate() const;
};

class TagDetector {
 public:
  explicit TagDetector(const TagDetectorParams& params = {});
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;
  // RGB or grey image; detections sorted by id, then by centre.
  std::vector<TagDetection> Detect(const Image8& image);
  // Only within `region` (clipped to the image; corners in the whole image's coordinates): a
  // search around where a tag is expected, affordable at full resolution.
  std::vector<TagDetection> Detect(const Image8& image, const PixelRect& region);
  const TagDetectorParams& params() const { return params_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  TagDetectorParams params_;
};

// Reads an image for tag detection as grey levels: JPEG files through libapriltag's own
// decoder (as its tools and regression test do), anything else through OpenCV. Throws
// InputError naming the file.
Image8 ReadGreyImage(const std::string& path);

}  // namespace inhand
