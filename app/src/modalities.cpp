#include "inhand/app/modalities.hpp"

#include <sstream>

#include "inhand/core/error.hpp"

namespace inhand::app {

namespace {

constexpr const char* kExpected =
    "expected j followed by any of t (torques), a (AprilTags), f (extracted features): j, jt, ja, "
    "jf, jta, jtf, jaf, jtaf";

}  // namespace

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
  if (text.empty() || text[0] != 'j')
    throw InputError("--modalities: '" + text + "': " + kExpected);
  ModalitySet s;
  for (std::size_t i = 1; i < text.size(); ++i) {
    bool* flag = text[i] == 't'   ? &s.torque
                 : text[i] == 'a' ? &s.tags
                 : text[i] == 'f' ? &s.features
                                  : nullptr;
    if (flag == nullptr)
      throw InputError("--modalities: '" + text + "': unknown letter '" + text[i] + "'; " +
                       kExpected);
    if (*flag)
      throw InputError("--modalities: '" + text + "': letter '" + text[i] + "' given twice");
    *flag = true;
  }
  // One name per combination, in the paper's letter order (jat is jta).
  s.name = std::string("j") + (s.torque ? "t" : "") + (s.tags ? "a" : "") + (s.features ? "f" : "");
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
