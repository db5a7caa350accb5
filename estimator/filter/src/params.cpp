#include "inhand/filter/params.hpp"

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

using Json = nlohmann::json;

// One table drives JSON reading, writing and validation.
struct Field {
  const char* name;
  double FilterParams::*number = nullptr;
  int FilterParams::*integer = nullptr;
  bool FilterParams::*flag = nullptr;
  double lo = 0.0, hi = 0.0;  // allowed range (numbers and integers)
  bool lo_open = false;       // lo excluded
  const char* expected = "";
};

const std::vector<Field>& Fields() {
  static const std::vector<Field> fields = {
      {"contact_sigma", &FilterParams::contact_sigma, nullptr, nullptr, 1e-5, 1.0, false,
       "in [1e-5, 1] m"},
      {"contact_normal_only", nullptr, nullptr, &FilterParams::contact_normal_only, 0, 0, false,
       "true or false"},
      {"contact_iterations", nullptr, &FilterParams::contact_iterations, nullptr, 1, 20, false,
       "an integer in [1, 20]"},
      {"contact_model_sigma", &FilterParams::contact_model_sigma, nullptr, nullptr, 0.0, 1.0, false,
       "in [0, 1] m (0 disables)"},
      {"contact_gate_chi2", &FilterParams::contact_gate_chi2, nullptr, nullptr, 0.0, 1e9, false,
       ">= 0 (0 disables)"},
      {"prediction_contact_distance", &FilterParams::prediction_contact_distance, nullptr, nullptr,
       0.0, 0.1, false, "in [0, 0.1] m"},
      {"torque_candidate_distance", &FilterParams::torque_candidate_distance, nullptr, nullptr, 0.0,
       0.2, false, "in [0, 0.2] m"},
      {"friction_cone_deg", &FilterParams::friction_cone_deg, nullptr, nullptr, 0.0, 90.0, true,
       "in (0, 90] degrees"},
      {"force_min", &FilterParams::force_min, nullptr, nullptr, 0.0, 1e4, false, "in [0, 1e4] N"},
      {"torque_damping", &FilterParams::torque_damping, nullptr, nullptr, 1e-12, 1.0, false,
       "in [1e-12, 1]"},
      {"torque_distance_scale", &FilterParams::torque_distance_scale, nullptr, nullptr, 0.0, 1.0,
       false, "in [0, 1] m (0: the paper's pseudo-inverse)"},
      {"twist_damping", &FilterParams::twist_damping, nullptr, nullptr, 1e-12, 1.0, false,
       "in [1e-12, 1]"},
      {"process_position", &FilterParams::process_position, nullptr, nullptr, 0.0, 10.0, false,
       "in [0, 10] m/sqrt(s)"},
      {"process_orientation", &FilterParams::process_orientation, nullptr, nullptr, 0.0, 10.0,
       false, "in [0, 10] rad/sqrt(s)"},
      {"process_bias", &FilterParams::process_bias, nullptr, nullptr, 0.0, 10.0, false,
       "in [0, 10] rad/sqrt(s)"},
      {"motion_position", &FilterParams::motion_position, nullptr, nullptr, 0.0, 10.0, false,
       "in [0, 10]"},
      {"motion_orientation", &FilterParams::motion_orientation, nullptr, nullptr, 0.0, 10.0, false,
       "in [0, 10]"},
      {"travel_orientation", &FilterParams::travel_orientation, nullptr, nullptr, 0.0, 1.0, false,
       "in [0, 1] m (0 disables)"},
      {"slip_torque", &FilterParams::slip_torque, nullptr, nullptr, 0.0, 1e4, false,
       "in [0, 1e4] N m (0 disables)"},
      {"slip_scale", &FilterParams::slip_scale, nullptr, nullptr, 1.0, 1e4, false, "in [1, 1e4]"},
      {"pixel_sigma", &FilterParams::pixel_sigma, nullptr, nullptr, 0.01, 1000.0, false,
       "in [0.01, 1000] px"},
      {"visual_gate_chi2", &FilterParams::visual_gate_chi2, nullptr, nullptr, 0.0, 1e9, false,
       ">= 0 (0 disables)"},
      {"visual_model_sigma", &FilterParams::visual_model_sigma, nullptr, nullptr, 0.0, 1000.0,
       false, "in [0, 1000] px (0 disables)"},
      {"camera_position_sigma", &FilterParams::camera_position_sigma, nullptr, nullptr, 0.0, 1.0,
       false, "in [0, 1] m"},
      {"camera_orientation_sigma", &FilterParams::camera_orientation_sigma, nullptr, nullptr, 0.0,
       1.0, false, "in [0, 1] rad"},
  };
  return fields;
}

std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

void FilterParams::Validate(const std::string& source) const {
  for (const Field& f : Fields()) {
    double v;
    if (f.number)
      v = this->*f.number;
    else if (f.integer)
      v = this->*f.integer;
    else
      continue;
    const bool ok = std::isfinite(v) && (f.lo_open ? v > f.lo : v >= f.lo) && v <= f.hi;
    if (!ok)
      throw InputError(source + ": parameter '" + f.name + "' is " + Num(v) + ", expected " +
                       f.expected);
  }
}

std::string FilterParamsToJson(const FilterParams& params) {
  Json j = Json::object();
  for (const Field& f : Fields()) {
    if (f.number) j[f.name] = params.*f.number;
    if (f.integer) j[f.name] = params.*f.integer;
    if (f.flag) j[f.name] = params.*f.flag;
  }
  return j.dump(2);
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
  if (!j.is_object()) throw InputError(source + ": expected a JSON object of parameters");
  FilterParams p;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const Field* field = nullptr;
    for (const Field& f : Fields())
      if (it.key() == f.name) field = &f;
    if (field == nullptr) throw InputError(source + ": unknown parameter '" + it.key() + "'");
    const Json& v = it.value();
    if (field->flag) {
      if (!v.is_boolean())
        throw InputError(source + ": parameter '" + it.key() + "' must be true or false");
      p.*field->flag = v.get<bool>();
    } else if (field->integer) {
      if (!v.is_number_integer())
        throw InputError(source + ": parameter '" + it.key() + "' must be an integer");
      // Read wide and range-checked: get<int>() wraps 4294967297 to 1.
      const double wide = v.is_number_unsigned() ? static_cast<double>(v.get<unsigned long long>())
                                                 : static_cast<double>(v.get<long long>());
      if (!(wide >= field->lo && wide <= field->hi))
        throw InputError(source + ": parameter '" + it.key() + "' is " + v.dump() + ", expected " +
                         field->expected);
      p.*field->integer = static_cast<int>(wide);
    } else {
      if (!v.is_number())
        throw InputError(source + ": parameter '" + it.key() + "' must be a number");
      p.*field->number = v.get<double>();
    }
  }
  p.Validate(source);
  return p;
}

}  // namespace inhand
