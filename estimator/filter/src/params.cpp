#include "inhand/filter/params.hpp"

#include <cmath>
#include <functional>
#include <sstream>

#include "inhand/core/error.hpp"
#include "inhand/filter/detail/param_table.hpp"

namespace inhand {

namespace {

using Json = param_table::Json;

using param_table::Flag;
using param_table::Integer;
using param_table::Number;
using Field = param_table::Field<FilterParams>;

// One table drives JSON reading, writing and validation (param_table.hpp).
const std::vector<Field>& Fields() {
  using P = FilterParams;
  static const std::vector<Field> fields = {
      Number("contact_sigma", &P::contact_sigma, 1e-5, 1.0, "in [1e-5, 1] m"),
      Flag("contact_normal_only", &P::contact_normal_only),
      Integer("contact_iterations", &P::contact_iterations, 1, 20, "an integer in [1, 20]"),
      Number("contact_model_sigma", &P::contact_model_sigma, 0.0, 1.0, "in [0, 1] m (0 disables)"),
      Number("contact_gate_chi2", &P::contact_gate_chi2, 0.0, 1e9, ">= 0 (0 disables)"),
      Number("prediction_contact_distance", &P::prediction_contact_distance, 0.0, 0.1,
             "in [0, 0.1] m"),
      Number("torque_candidate_distance", &P::torque_candidate_distance, 0.0, 0.2, "in [0, 0.2] m"),
      Number("friction_cone_deg", &P::friction_cone_deg, 0.0, 90.0, "in (0, 90] degrees", true),
      Number("force_min", &P::force_min, 0.0, 1e4, "in [0, 1e4] N"),
      Number("torque_damping", &P::torque_damping, 1e-12, 1.0, "in [1e-12, 1]"),
      Number("torque_distance_scale", &P::torque_distance_scale, 0.0, 1.0,
             "in [0, 1] m (0: the paper's pseudo-inverse)"),
      Number("twist_damping", &P::twist_damping, 1e-12, 1.0, "in [1e-12, 1]"),
      Number("process_position", &P::process_position, 0.0, 10.0, "in [0, 10] m/sqrt(s)"),
      Number("process_orientation", &P::process_orientation, 0.0, 10.0, "in [0, 10] rad/sqrt(s)"),
      Number("process_bias", &P::process_bias, 0.0, 10.0, "in [0, 10] rad/sqrt(s)"),
      Number("motion_position", &P::motion_position, 0.0, 10.0, "in [0, 10]"),
      Number("motion_orientation", &P::motion_orientation, 0.0, 10.0, "in [0, 10]"),
      Number("travel_orientation", &P::travel_orientation, 0.0, 1.0, "in [0, 1] m (0 disables)"),
      Number("slip_torque", &P::slip_torque, 0.0, 1e4, "in [0, 1e4] N m (0 disables)"),
      Number("slip_scale", &P::slip_scale, 1.0, 1e4, "in [1, 1e4]"),
      Number("pixel_sigma", &P::pixel_sigma, 0.01, 1000.0, "in [0.01, 1000] px"),
      Number("visual_gate_chi2", &P::visual_gate_chi2, 0.0, 1e9, ">= 0 (0 disables)"),
      Number("visual_model_sigma", &P::visual_model_sigma, 0.0, 1000.0,
             "in [0, 1000] px (0 disables)"),
      Number("camera_position_sigma", &P::camera_position_sigma, 0.0, 1.0, "in [0, 1] m"),
      Number("camera_orientation_sigma", &P::camera_orientation_sigma, 0.0, 1.0, "in [0, 1] rad"),
  };
  return fields;
}

}  // namespace

void FilterParams::Validate(const std::string& source) const {
  param_table::Validate(*this, Fields(), source);
}

std::string FilterParamsToJson(const FilterParams& params) {
  return param_table::Write(params, Fields()).dump(2);
}

FilterParams FilterParamsFromJson(const std::string& json_text, const std::string& source) {
  Json j;
  try {
    j = Json::parse(json_text, [&](int depth, Json::parse_event_t, Json&) {
      if (depth > 64) throw InputError(source + ": JSON nested deeper than 64 levels");
      return true;
    });
  } catch (const Json::parse_error& e) {
    throw InputError(source + ": malformed JSON (" + e.what() + ")");
  }
  FilterParams p;
  param_table::Read(j, Fields(), source, p);
  p.Validate(source);
  return p;
}

}  // namespace inhand
