#pragma once
// Internal (filter, tracker): one table per parameter struct drives its JSON writing, its JSON
// reading and, for the fields that state a range, its validation. Messages name the source and
// the parameter: "p.json (tags): parameter 'decimate' must be a number". Exposes nlohmann::json,
// so it is not installed.
#include <climits>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "inhand/core/error.hpp"

namespace inhand::param_table {

using Json = nlohmann::json;

// One parameter: exactly one member pointer is set. `expected` (when set) says the allowed range
// [lo, hi] (lo excluded when lo_open) in the words of the message that refuses a value outside.
template <typename P>
struct Field {
  const char* name = "";
  double P::*number = nullptr;
  int P::*integer = nullptr;
  unsigned P::*unsigned_integer = nullptr;
  bool P::*flag = nullptr;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  const char* expected = nullptr;
};

template <typename P>
Field<P> Number(const char* name, double P::*member, double lo, double hi, const char* expected,
                bool lo_open = false) {
  Field<P> f;
  f.name = name;
  f.number = member;
  f.lo = lo;
  f.hi = hi;
  f.lo_open = lo_open;
  f.expected = expected;
  return f;
}
template <typename P>
Field<P> Number(const char* name, double P::*member) {  // any number; the struct validates it
  Field<P> f;
  f.name = name;
  f.number = member;
  return f;
}
template <typename P>
Field<P> Integer(const char* name, int P::*member, int lo = -INT_MAX, int hi = INT_MAX,
                 const char* expected = nullptr) {
  Field<P> f;
  f.name = name;
  f.integer = member;
  f.lo = lo;
  f.hi = hi;
  f.expected = expected;
  return f;
}
template <typename P>
Field<P> Unsigned(const char* name, unsigned P::*member) {
  Field<P> f;
  f.name = name;
  f.unsigned_integer = member;
  f.lo = 0;
  f.hi = INT_MAX;
  return f;
}
template <typename P>
Field<P> Flag(const char* name, bool P::*member) {
  Field<P> f;
  f.name = name;
  f.flag = member;
  return f;
}

template <typename P>
Json Write(const P& p, const std::vector<Field<P>>& fields) {
  Json j = Json::object();
  for (const Field<P>& f : fields) {
    if (f.number) j[f.name] = p.*f.number;
    if (f.integer) j[f.name] = p.*f.integer;
    if (f.unsigned_integer) j[f.name] = p.*f.unsigned_integer;
    if (f.flag) j[f.name] = p.*f.flag;
  }
  return j;
}

// The members `j` names, into `p`; an unknown name, a value of the wrong type or an integer
// outside its range is an InputError naming `where` and the parameter.
template <typename P>
void Read(const Json& j, const std::vector<Field<P>>& fields, const std::string& where, P& p) {
  if (!j.is_object()) throw InputError(where + ": expected a JSON object of parameters");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const Field<P>* field = nullptr;
    for (const Field<P>& f : fields)
      if (it.key() == f.name) field = &f;
    if (field == nullptr) throw InputError(where + ": unknown parameter '" + it.key() + "'");
    const std::string name = where + ": parameter '" + it.key() + "'";
    const Json& v = it.value();
    if (field->flag) {
      if (!v.is_boolean()) throw InputError(name + " must be true or false");
      p.*field->flag = v.get<bool>();
    } else if (field->integer || field->unsigned_integer) {
      if (!v.is_number_integer()) throw InputError(name + " must be an integer");
      // Read wide and range-checked: get<int>() wraps 4294967297 to 1.
      const double wide = v.is_number_unsigned() ? static_cast<double>(v.get<unsigned long long>())
                                                 : static_cast<double>(v.get<long long>());
      if (!(wide >= field->lo && wide <= field->hi))
        throw InputError(name + " is " + v.dump() + ", " +
                         (field->expected ? std::string("expected ") + field->expected
                                          : std::string("out of range")));
      if (field->integer)
        p.*field->integer = static_cast<int>(wide);
      else
        p.*field->unsigned_integer = static_cast<unsigned>(wide);
    } else {
      if (!v.is_number()) throw InputError(name + " must be a number");
      p.*field->number = v.get<double>();
    }
  }
}

// The fields that state a range, checked: "SOURCE: parameter 'NAME' is V, expected E".
template <typename P>
void Validate(const P& p, const std::vector<Field<P>>& fields, const std::string& source) {
  for (const Field<P>& f : fields) {
    if (f.expected == nullptr) continue;
    double v;
    if (f.number)
      v = p.*f.number;
    else if (f.integer)
      v = p.*f.integer;
    else if (f.unsigned_integer)
      v = p.*f.unsigned_integer;
    else
      continue;
    const bool ok = std::isfinite(v) && (f.lo_open ? v > f.lo : v >= f.lo) && v <= f.hi;
    if (!ok) {
      std::ostringstream os;
      os << v;
      throw InputError(source + ": parameter '" + f.name + "' is " + os.str() + ", expected " +
                       f.expected);
    }
  }
}

}  // namespace inhand::param_table
