#pragma once
// Everything a Tracker is configured with, in one struct and one JSON file (`--params`): the
// filter's parameters at the top level (as the files written before the tracker existed), the
// tag detector's under "tags", the extracted features' under "features", the health monitor's
// under "health". Unknown fields are
// errors that name the file and the field; every value is validated.
#include <string>

#include "inhand/core/hand_model.hpp"
#include "inhand/features/extracted.hpp"
#include "inhand/features/tags.hpp"
#include "inhand/filter/health.hpp"
#include "inhand/filter/joint_samples.hpp"  // ScreenJointSample, ClampToLimits (joints.*)
#include "inhand/filter/params.hpp"

namespace inhand {

struct TrackerParams {
  FilterParams filter;
  TagDetectorParams tags;              // `family` is replaced by the object's tags' family unless
  bool tag_family_from_object = true;  // the file names one (tag_family_from_object false)
  bool tag_fine_search = true;         // search tags the decimated detection missed at full
                                       // resolution where the estimate expects them
  // Tags whose own fit of the object's pose (every corner of the image, Gauss-Newton from each
  // tag's homography) the estimate cannot explain (χ²₆ > 99.9 % under both covariances) in this
  // many images in a row put the object where the fit says, instead of being gated corner by
  // corner while the estimate stays where the object is not (a bottle fallen out of a loosened
  // grip; a start far off). 0: never. JSON: "tags": {"relocate_images"}.
  int tag_relocate_images = 2;
  FeatureParams features;
  // Joint samples that no hand can produce are dropped (counted), never fused: a value that is
  // not a number, or beyond its URDF limits by more than this (rad or m; joints without limits:
  // beyond ±1000). A real hand's encoders overshoot their URDF limits a little (the Allegro's
  // thumb by ~0.1 rad); a corrupt sample is off by far more. JSON: "joints": {"limit_margin"}.
  double joint_limit_margin = 0.5;
  // Samples within the margin but beyond the limits: kept as measured (false), or clamped to the
  // limits before they are fused (true: when the URDF's limits are right and the encoders
  // overshoot). JSON: "joints": {"clamp_to_limits"}. The player reports them either way, once per
  // joint (SessionPlayer::InputReport).
  bool joint_clamp_to_limits = false;
  // When the estimate calls itself uncertain, inconsistent or lost (filter/health.hpp). JSON:
  // "health": {...}, the fields' names.
  HealthParams health;

  // Throws InputError("SOURCE: parameter '...' is ..., expected ...").
  void Validate(const std::string& source = "tracker parameters") const;
};

std::string TrackerParamsToJson(const TrackerParams& params);
TrackerParams TrackerParamsFromJson(const std::string& json_text, const std::string& source);
// Reads a parameter file; InputError naming the file when it cannot be read or a field is wrong.
TrackerParams ReadTrackerParams(const std::string& path);

}  // namespace inhand
