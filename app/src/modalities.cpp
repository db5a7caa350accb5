#include "inhand/app/modalities.hpp"

#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand::app {

std::vector<ModalitySet> ParseModalities(const std::string& list) {
  std::vector<ModalitySet> out;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name == "j") out.push_back({"j", false, false, false, kColourJoints});
    else if (name == "jt") out.push_back({"jt", true, false, false, kColourTorques});
    else if (name == "jta") out.push_back({"jta", true, true, false, kColourTags});
    else if (name == "jtf") out.push_back({"jtf", true, false, true, kColourFeatures});
    else throw InputError("--modalities: unknown set '" + name + "', expected j, jt, jta or jtf");
    for (std::size_t i = 0; i + 1 < out.size(); ++i)
      if (out[i].name == name) throw InputError("--modalities: set '" + name + "' is listed twice");
  }
  if (out.empty()) throw InputError("--modalities: empty list");
  return out;
}

}  // namespace inhand::app
