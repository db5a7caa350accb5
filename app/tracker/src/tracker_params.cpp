#include "inhand/tracker/tracker_params.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "inhand/core/error.hpp"
#include "inhand/io/detail/json_fields.hpp"

namespace inhand {

namespace {

using Json = nlohmann::json;

// One table per section drives reading and writing; validation is the structs' own.
template <typename P>
struct Field {
  const char* name;
  double P::*number = nullptr;
  int P::*integer = nullptr;
  bool P::*flag = nullptr;
  unsigned P::*unsigned_integer = nullptr;
};

const std::vector<Field<TagDetectorParams>>& TagFields() {
  using T = TagDetectorParams;
  static const std::vector<Field<T>> fields = {{"decimate", &T::decimate},
                                               {"refine_edges", nullptr, nullptr, &T::refine_edges},
                                               {"sigma", &T::sigma},
                                               {"threads", nullptr, &T::threads},
                                               {"max_hamming", nullptr, &T::max_hamming},
                                               {"min_decision_margin", &T::min_decision_margin}};
  return fields;
}

const std::vector<Field<FeatureParams>>& FeatureFields() {
  using F = FeatureParams;
  static const std::vector<Field<F>> fields = {
      {"canny_low", &F::canny_low},
      {"canny_high", &F::canny_high},
      {"blur_sigma", &F::blur_sigma},
      {"harris_block", nullptr, &F::harris_block},
      {"harris_k", &F::harris_k},
      {"harris_relative", &F::harris_relative},
      {"max_corners", nullptr, &F::max_corners},
      {"min_corner_distance", &F::min_corner_distance},
      {"occluder_clearance", nullptr, &F::occluder_clearance},
      {"piece_radius", nullptr, &F::piece_radius},
      {"min_piece_pixels", nullptr, &F::min_piece_pixels},
      {"search_radius", nullptr, &F::search_radius},
      {"max_search_radius", nullptr, &F::max_search_radius},
      {"global_truncation", &F::global_truncation},
      {"orientation_bins", nullptr, &F::orientation_bins},
      {"min_vote_fraction", &F::min_vote_fraction},
      {"ransac_threshold", &F::ransac_threshold},
      {"ransac_iterations", nullptr, &F::ransac_iterations},
      {"seed", nullptr, nullptr, nullptr, &F::seed}};
  return fields;
}

template <typename P>
Json Write(const P& p, const std::vector<Field<P>>& fields) {
  Json j = Json::object();
  for (const Field<P>& f : fields) {
    if (f.number) j[f.name] = p.*f.number;
    if (f.integer) j[f.name] = p.*f.integer;
    if (f.flag) j[f.name] = p.*f.flag;
    if (f.unsigned_integer) j[f.name] = p.*f.unsigned_integer;
  }
  return j;
}

template <typename P>
void Read(const Json& j, const std::vector<Field<P>>& fields, const std::string& where, P& p) {
  if (!j.is_object()) throw InputError(where + ": expected a JSON object of parameters");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const Field<P>* field = nullptr;
    for (const Field<P>& f : fields)
      if (it.key() == f.name) field = &f;
    const std::string name = where + ": parameter '" + it.key() + "'";
    if (field == nullptr) throw InputError(where + ": unknown parameter '" + it.key() + "'");
    const Json& v = it.value();
    if (field->flag) {
      if (!v.is_boolean()) throw InputError(name + " must be true or false");
      p.*field->flag = v.get<bool>();
    } else if (field->integer || field->unsigned_integer) {
      if (!v.is_number_integer()) throw InputError(name + " must be an integer");
      const long long value = v.get<long long>();
      if (value < (field->integer ? -2147483647LL : 0LL) || value > 2147483647LL)
        throw InputError(name + " is " + std::to_string(value) + ", out of range");
      if (field->integer)
        p.*field->integer = static_cast<int>(value);
      else
        p.*field->unsigned_integer = static_cast<unsigned>(value);
    } else {
      if (!v.is_number()) throw InputError(name + " must be a number");
      p.*field->number = v.get<double>();
    }
  }
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
}

std::string TrackerParamsToJson(const TrackerParams& params) {
  Json j = Json::parse(FilterParamsToJson(params.filter));
  Json tags = Write(params.tags, TagFields());
  if (!params.tag_family_from_object) tags["family"] = params.tags.family;
  tags["fine_search"] = params.tag_fine_search;
  tags["relocate_images"] = params.tag_relocate_images;
  j["tags"] = tags;
  j["features"] = Write(params.features, FeatureFields());
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
