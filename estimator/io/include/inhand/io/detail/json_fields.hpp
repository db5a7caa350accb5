#pragma once
// Internal (io, sessions, app): typed access to JSON fields with messages that name the file
// and the field path, e.g. "object.json: field 'tags[0].size': expected a number > 0".
// Not part of the estimator's public API: it exposes nlohmann::json.
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "inhand/core/so3.hpp"

namespace inhand::jsonf {

using Json = nlohmann::json;

// A cursor: a JSON value together with where it came from.
struct Field {
  const Json& value;
  std::string file;
  std::string path;  // "" for the document root, else "a.b[2].c"

  std::string Where() const;  // "FILE: field 'PATH'"
  [[noreturn]] void Fail(const std::string& expected) const;

  // An object whose keys are all among `keys`; else fails naming them ("an object with "a", "b"
  // or "c"", "unknown key 'k', expected "a", "b" or "c"").
  void ExpectKeys(std::initializer_list<const char*> keys) const;
  bool Has(const std::string& key) const;
  Field operator[](const std::string& key) const;  // throws when missing
  Field At(std::size_t index) const;
  std::size_t Size() const;  // arrays; throws otherwise

  double Number() const;
  double PositiveNumber(const std::string& unit = "") const;  // a unit, if given, is in the message
  double NonNegativeNumber() const;
  int Integer() const;
  std::string String() const;
  bool Bool() const;
  Vec3 Vector3() const;
  // {"xyz": [...], "rpy": [...]} or {"xyz": [...], "quat_wxyz": [...]}, both parts optional.
  Transform Pose() const;
};

// Deeper nesting is an error (no inhand file needs more than a few levels).
constexpr int kMaxJsonDepth = 64;

// Reads and parses a JSON file; errors name the file and the line.
Json ReadFile(const std::string& path);
Json ParseText(const std::string& text, const std::string& file);

Json PoseToJson(const Transform& T);  // {"xyz": [...], "quat_wxyz": [...]}

}  // namespace inhand::jsonf
