#include "inhand/app/modalities.hpp"

#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand::app {

Rgb ModalityColour(const std::string& name) {
  if (name == "j") return kColourJoints;
  if (name == "jt") return kColourTorques;
  if (name == "jta") return kColourTags;
  if (name == "jtf") return kColourFeatures;
  if (name == "ja") return kColourJointsTags;
  if (name == "jf") return kColourJointsFeatures;
  if (name == "jaf") return kColourJointsTagsFeatures;
  if (name == "jtaf") return kColourAll;
  return kColourTruth;
}

ModalitySet ParseModalitySet(const std::string& text) {
  const Modalities m = Modalities::Parse(text, "--modalities");
  ModalitySet s;
  s.torque = m.torque;
  s.tags = m.tags;
  s.features = m.features;
  // One name per combination, in the paper's letter order (jat is jta).
  s.name = m.Name();
  s.colour = ModalityColour(s.name);
  return s;
}

std::vector<ModalitySet> ParseModalities(const std::string& list) {
  std::vector<ModalitySet> out;
  std::stringstream ss(list);
  std::string text;
  while (std::getline(ss, text, ',')) {
    out.push_back(ParseModalitySet(text));
    for (std::size_t i = 0; i + 1 < out.size(); ++i)
      if (out[i].name == out.back().name)
        throw InputError("--modalities: set '" + out.back().name + "' is listed twice");
  }
  if (out.empty()) throw InputError("--modalities: empty list");
  return out;
}

std::string DefaultModalities(bool torques, bool camera, bool tags) {
  std::string list = torques ? "j,jt" : "j";
  if (camera && tags) list += torques ? ",jta" : ",ja";
  if (camera) list += torques ? ",jtf" : ",jf";
  return list;
}

}  // namespace inhand::app
