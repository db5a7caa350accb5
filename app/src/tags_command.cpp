#include <iomanip>
#include <iostream>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/io/detail/json_fields.hpp"

namespace inhand::app {

int RunTags(const TagsCommand& cmd) {
  if (cmd.refine_edges != 0 && cmd.refine_edges != 1)
    throw InputError("--refine-edges is " + std::to_string(cmd.refine_edges) + ", expected 0 or 1");
  TagDetectorParams params;
  params.family = cmd.family;
  params.decimate = cmd.decimate;
  params.refine_edges = cmd.refine_edges == 1;
  TagDetector detector(params);
  const std::vector<TagDetection> found = detector.Detect(ReadGreyImage(cmd.image));
  // Output in libapriltag's coordinates (pixel centres at +0.5), comparable with its tools;
  // the estimator uses the same corners shifted by -0.5 (pixel centres at integers).
  if (cmd.json) {
    jsonf::Json detections = jsonf::Json::array();
    for (const TagDetection& d : found) {
      jsonf::Json corners = jsonf::Json::array();
      for (const Vec2& c : d.corners) corners.push_back({c.x() + 0.5, c.y() + 0.5});
      detections.push_back({{"id", d.id},
                            {"family", d.family},
                            {"corners", corners},
                            {"center", {d.center.x() + 0.5, d.center.y() + 0.5}},
                            {"decision_margin", d.decision_margin},
                            {"hamming", d.hamming}});
    }
    std::cout << jsonf::Json{{"image", cmd.image}, {"detections", detections}}.dump(2) << "\n";
    return 0;
  }
  std::cout << found.size() << " " << cmd.family << " tags in " << cmd.image
            << " (corners: bottom-left, bottom-right, top-right, top-left)\n";
  for (const TagDetection& d : found) {
    std::cout << std::fixed << std::setprecision(4) << d.id;
    for (const Vec2& c : d.corners) std::cout << ", (" << c.x() + 0.5 << " " << c.y() + 0.5 << ")";
    std::cout << std::setprecision(1) << "   margin " << d.decision_margin << ", hamming "
              << d.hamming << "\n";
  }
  return 0;
}

}  // namespace inhand::app
