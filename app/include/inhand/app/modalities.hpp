#pragma once
// The modality sets a command runs, with the colours every overlay and plot gives them.
#include <string>
#include <vector>

#include "inhand/renderer/overlay.hpp"
#include "inhand/tracker/tracker.hpp"

namespace inhand::app {

struct ModalitySet {
  std::string name;  // j, jt, jta, jtf
  bool torque = false;
  bool tags = false;
  bool features = false;
  Rgb colour;
  Modalities modalities() const { return {torque, tags, features}; }
};
// Parses "j,jt,..."; throws InputError for unknown or not yet supported sets.
std::vector<ModalitySet> ParseModalities(const std::string& list);

}  // namespace inhand::app
