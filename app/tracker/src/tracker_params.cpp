#include "inhand/tracker/tracker_params.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "inhand/core/error.hpp"
#include "inhand/filter/detail/param_table.hpp"
#include "inhand/io/detail/json_fields.hpp"

namespace inhand {

namespace {

using Json = nlohmann::json;

// One table per section drives reading and writing; validation is the structs' own.
using param_table::Flag;
using param_table::Integer;
using param_table::Number;
using param_table::Read;
using param_table::Unsigned;
using param_table::Write;

const std::vector<param_table::Field<TagDetectorParams>>& TagFields() {
  using T = TagDetectorParams;
  static const std::vector<param_table::Field<T>> fields = {
      Number("decimate", &T::decimate),
      Flag("refine_edges", &T::refine_edges),
      Number("sigma", &T::sigma),
      Integer("threads", &T::threads),
      Integer("max_hamming", &T::max_hamming),
      Number("min_decision_margin", &T::min_decision_margin)};
  return fields;
}

const std::vector<param_table::Field<FeatureParams>>& FeatureFields() {
  using F = FeatureParams;
  static const std::vector<param_table::Field<F>> fields = {
      Number("canny_low", &F::canny_low),
      Number("canny_high", &F::canny_high),
      Number("blur_sigma", &F::blur_sigma),
      Integer("harris_block", &F::harris_block),
      Number("harris_k", &F::harris_k),
      Number("harris_relative", &F::harris_relative),
      Integer("max_corners", &F::max_corners),
      Number("min_corner_distance", &F::min_corner_distance),
      Integer("occluder_clearance", &F::occluder_clearance),
      Integer("piece_radius", &F::piece_radius),
      Integer("min_piece_pixels", &F::min_piece_pixels),
      Integer("search_radius", &F::search_radius),
      Integer("max_search_radius", &F::max_search_radius),
      Number("global_truncation", &F::global_truncation),
      Integer("orientation_bins", &F::orientation_bins),
      Number("min_vote_fraction", &F::min_vote_fraction),
      Number("ransac_threshold", &F::ransac_threshold),
      Integer("ransac_iterations", &F::ransac_iterations),
      Unsigned("seed", &F::seed)};
  return fields;
}

const std::vector<param_table::Field<HealthParams>>& HealthFields() {
  using H = HealthParams;
  static const std::vector<param_table::Field<H>> fields = {
      Number("uncertain_position", &H::uncertain_position),
      Number("uncertain_orientation", &H::uncertain_orientation),
      Number("penetration", &H::penetration),
      Number("press_torque", &H::press_torque),
      Number("press_gap", &H::press_gap),
      Number("press_reach", &H::press_reach),
      Number("press_period", &H::press_period),
      Number("sustain", &H::sustain),
      Integer("vision_window", &H::vision_window),
      Integer("vision_min_offered", &H::vision_min_offered),
      Number("vision_gated_share", &H::vision_gated_share),
      Integer("vision_min_used", &H::vision_min_used),
      Number("images_stale", &H::images_stale),
      Integer("images_frozen", &H::images_frozen),
      Number("relocalized_hold", &H::relocalized_hold),
      Number("slip_hold", &H::slip_hold),
      Number("lost_after", &H::lost_after),
      Integer("recover_images", &H::recover_images),
      Number("recover_gap", &H::recover_gap),
      Number("recover_reach", &H::recover_reach)};
  return fields;
}

// The structs' own Validate() messages, prefixed with the file.
template <typename F>
void Prefixed(const std::string& source, F&& validate) {
  try {
    validate();
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
}

}  // namespace

void TrackerParams::Validate(const std::string& source) const {
  filter.Validate(source);
  if (!(joint_limit_margin >= 0.0 && joint_limit_margin <= 100.0))
    throw InputError(source + ": parameter 'joints.limit_margin' is " +
                     std::to_string(joint_limit_margin) + ", expected in [0, 100]");
  if (!(tag_relocate_images >= 0 && tag_relocate_images <= 1000))
    throw InputError(source + ": parameter 'tags.relocate_images' is " +
                     std::to_string(tag_relocate_images) + ", expected in [0, 1000] (0: never)");
  Prefixed(source, [&] { tags.Validate(); });
  Prefixed(source, [&] { features.Validate(); });
  health.Validate(source);
}

std::string TrackerParamsToJson(const TrackerParams& params) {
  Json j = Json::parse(FilterParamsToJson(params.filter));
  Json tags = Write(params.tags, TagFields());
  if (!params.tag_family_from_object) tags["family"] = params.tags.family;
  tags["fine_search"] = params.tag_fine_search;
  tags["relocate_images"] = params.tag_relocate_images;
  j["tags"] = tags;
  j["features"] = Write(params.features, FeatureFields());
  j["health"] = Write(params.health, HealthFields());
  j["joints"] = {{"limit_margin", params.joint_limit_margin},
                 {"clamp_to_limits", params.joint_clamp_to_limits}};
  return j.dump(2);
}

TrackerParams TrackerParamsFromJson(const std::string& json_text, const std::string& source) {
  Json j = jsonf::ParseText(json_text, source);  // bounded depth, errors with the line
  if (!j.is_object()) throw InputError(source + ": expected a JSON object of parameters");
  TrackerParams p;
  if (j.contains("tags")) {
    Json tags = j["tags"];
    if (tags.is_object() && tags.contains("family")) {
      if (!tags["family"].is_string())
        throw InputError(source + ": parameter 'tags.family' must be a string");
      p.tags.family = tags["family"].get<std::string>();
      p.tag_family_from_object = false;
      tags.erase("family");
    }
    if (tags.is_object() && tags.contains("fine_search")) {
      if (!tags["fine_search"].is_boolean())
        throw InputError(source + ": parameter 'tags.fine_search' must be true or false");
      p.tag_fine_search = tags["fine_search"].get<bool>();
      tags.erase("fine_search");
    }
    if (tags.is_object() && tags.contains("relocate_images")) {
      const Json& v = tags["relocate_images"];
      if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 1000)
        throw InputError(source + ": parameter 'tags.relocate_images' is " + v.dump() +
                         ", expected an integer in [0, 1000] (0: never)");
      p.tag_relocate_images = v.get<int>();
      tags.erase("relocate_images");
    }
    Read(tags, TagFields(), source + " (tags)", p.tags);
    j.erase("tags");
  }
  if (j.contains("features")) {
    Read(j["features"], FeatureFields(), source + " (features)", p.features);
    j.erase("features");
  }
  if (j.contains("health")) {
    Read(j["health"], HealthFields(), source + " (health)", p.health);
    j.erase("health");
  }
  if (j.contains("joints")) {
    const Json& joints = j["joints"];
    if (!joints.is_object()) throw InputError(source + ": 'joints' must be an object");
    for (auto it = joints.begin(); it != joints.end(); ++it) {
      if (it.key() == "clamp_to_limits") {
        if (!it.value().is_boolean())
          throw InputError(source + ": parameter 'joints.clamp_to_limits' must be true or false");
        p.joint_clamp_to_limits = it.value().get<bool>();
        continue;
      }
      if (it.key() != "limit_margin")
        throw InputError(source + " (joints): unknown parameter '" + it.key() + "'");
      if (!it.value().is_number())
        throw InputError(source + ": parameter 'joints.limit_margin' must be a number");
      p.joint_limit_margin = it.value().get<double>();
    }
    j.erase("joints");
  }
  p.filter = FilterParamsFromJson(j.dump(), source);
  p.Validate(source);
  return p;
}

TrackerParams ReadTrackerParams(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the parameter file");
  std::stringstream ss;
  ss << in.rdbuf();
  return TrackerParamsFromJson(ss.str(), path);
}

}  // namespace inhand
