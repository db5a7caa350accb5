#pragma once
// The modality sets a command runs, with the colours every overlay and plot gives them.
#include <string>
#include <vector>

#include "inhand/renderer/overlay.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::app {

struct ModalitySet {
  std::string name;  // j, then t, a, f in this order: j, jt, ja, jf, jta, jtf, jaf, jtaf
  bool torque = false;
  bool tags = false;
  bool features = false;
  Rgb colour;
  Modalities modalities() const { return {torque, tags, features}; }
};
// Parses one set: j followed by any of t (torques), a (AprilTags), f (extracted features), in
// any order ("jat" is "jta"). Throws InputError naming the set and what was expected.
ModalitySet ParseModalitySet(const std::string& text);
// Parses "j,jt,..."; throws InputError for unknown or repeated sets.
std::vector<ModalitySet> ParseModalities(const std::string& list);
// The paper's colours for its four sets, distinct ones for the others.
Rgb ModalityColour(const std::string& name);
// The sets a session supports by default: the paper's four where it has torques (jta only with
// tags on the object, jta and jtf only with images); without torques j, ja, jf.
std::string DefaultModalities(bool torques, bool camera, bool tags);

}  // namespace inhand::app
