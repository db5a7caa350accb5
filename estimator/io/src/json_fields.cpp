#include "inhand/io/detail/json_fields.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand::jsonf {

std::string Field::Where() const {
  if (path.empty()) return file + ": document";
  return file + ": field '" + path + "'";
}

void Field::Fail(const std::string& expected) const {
  // Never dump a whole array or object: it can be arbitrarily large or deep.
  std::string got = value.is_null()    ? "null"
                    : value.is_array() ? "an array of " + std::to_string(value.size()) + " elements"
                    : value.is_object() ? "an object of " + std::to_string(value.size()) + " fields"
                                        : value.dump();
  if (got.size() > 60) got = got.substr(0, 57) + "...";
  throw InputError(Where() + " is " + got + ", expected " + expected);
}

void Field::ExpectKeys(std::initializer_list<const char*> keys) const {
  std::string list;
  for (auto k = keys.begin(); k != keys.end(); ++k) {
    if (k != keys.begin()) list += k + 1 == keys.end() ? " or " : ", ";
    list += "\"" + std::string(*k) + "\"";
  }
  if (!value.is_object()) Fail("an object with " + list);
  for (auto it = value.begin(); it != value.end(); ++it)
    if (std::find(keys.begin(), keys.end(), it.key()) == keys.end())
      throw InputError(Where() + ": unknown key '" + it.key() + "', expected " + list);
}

bool Field::Has(const std::string& key) const { return value.is_object() && value.contains(key); }

Field Field::operator[](const std::string& key) const {
  if (!value.is_object()) Fail("an object with field '" + key + "'");
  const std::string sub = path.empty() ? key : path + "." + key;
  auto it = value.find(key);
  if (it == value.end()) throw InputError(file + ": missing field '" + sub + "'");
  return Field{*it, file, sub};
}

Field Field::At(std::size_t index) const {
  if (!value.is_array() || index >= value.size())
    Fail("an array with an element " + std::to_string(index));
  return Field{value[index], file, path + "[" + std::to_string(index) + "]"};
}

std::size_t Field::Size() const {
  if (!value.is_array()) Fail("an array");
  return value.size();
}

double Field::Number() const {
  if (!value.is_number()) Fail("a number");
  const double v = value.get<double>();
  if (!std::isfinite(v)) Fail("a finite number");
  return v;
}

double Field::PositiveNumber(const std::string& unit) const {
  const double v = value.is_number() ? value.get<double>() : 0.0;
  if (!value.is_number() || !(v > 0.0) || !std::isfinite(v))
    Fail(unit.empty() ? "a finite number > 0" : "a finite number > 0 in " + unit);
  return v;
}

double Field::NonNegativeNumber() const {
  const double v = value.is_number() ? value.get<double>() : -1.0;
  if (!value.is_number() || !(v >= 0.0) || !std::isfinite(v)) Fail("a finite number >= 0");
  return v;
}

int Field::Integer() const {
  if (!value.is_number_integer()) Fail("an integer");
  // Read wide: get<int>() wraps 4294967297 to 1.
  if (value.is_number_unsigned()
          ? value.get<unsigned long long>() > 2147483647ULL
          : (value.get<long long>() > 2147483647LL || value.get<long long>() < -2147483647LL))
    Fail("an integer in [-2147483647, 2147483647]");
  return static_cast<int>(value.get<long long>());
}

std::string Field::String() const {
  if (!value.is_string()) Fail("a string");
  return value.get<std::string>();
}

bool Field::Bool() const {
  if (!value.is_boolean()) Fail("true or false");
  return value.get<bool>();
}

Vec3 Field::Vector3() const {
  if (!value.is_array() || value.size() != 3) Fail("an array of 3 numbers");
  return Vec3(At(0).Number(), At(1).Number(), At(2).Number());
}

Transform Field::Pose() const {
  if (!value.is_object()) Fail("a pose {\"xyz\": [x, y, z], \"rpy\" or \"quat_wxyz\": [...]}");
  Vec3 xyz = Vec3::Zero();
  Mat3 R = Mat3::Identity();
  if (Has("xyz")) xyz = (*this)["xyz"].Vector3();
  if (Has("rpy") && Has("quat_wxyz")) Fail("either \"rpy\" or \"quat_wxyz\", not both");
  if (Has("rpy")) R = RotationFromRpy((*this)["rpy"].Vector3());
  if (Has("quat_wxyz")) {
    const Field q = (*this)["quat_wxyz"];
    if (!q.value.is_array() || q.value.size() != 4) q.Fail("an array of 4 numbers (w, x, y, z)");
    const Quat quat(q.At(0).Number(), q.At(1).Number(), q.At(2).Number(), q.At(3).Number());
    if (std::abs(quat.norm() - 1.0) > 1e-3) q.Fail("a unit quaternion (norm 1 ± 1e-3)");
    R = quat.normalized().toRotationMatrix();
  }
  return MakeTransform(xyz, R);
}

Json ParseText(const std::string& text, const std::string& file) {
  try {
    // Nesting is bounded: 100,000 nested arrays overflowed the stack when the value was used.
    return Json::parse(text, [&](int depth, Json::parse_event_t, Json&) {
      if (depth > kMaxJsonDepth)
        throw InputError(file + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                         " levels");
      return true;
    });
  } catch (const Json::parse_error& e) {
    // Turn the byte offset into a line number.
    const std::size_t upto = std::min<std::size_t>(e.byte, text.size());
    const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(upto), '\n');
    throw InputError(file + ":" + std::to_string(line) + ": malformed JSON (" + e.what() + ")");
  }
}

Json ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open JSON file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ParseText(ss.str(), path);
}

Json PoseToJson(const Transform& T) {
  const Quat q(T.linear());
  return Json{{"xyz", {T.translation().x(), T.translation().y(), T.translation().z()}},
              {"quat_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

}  // namespace inhand::jsonf
