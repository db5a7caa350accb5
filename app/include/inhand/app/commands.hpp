#pragma once
// The CLI's commands as plain functions (main.cpp only parses arguments with CLI11).
// Each returns the process exit code; bad input surfaces as InputError, which main turns into
// one line on stderr and exit code 2.
#include <string>
#include <vector>

namespace inhand::app {

struct ModelCommand {
  std::string file;                   // a hand URDF, or an object description (.json)
  std::vector<std::string> packages;  // NAME=DIR
  bool json = false;
};
int RunModel(const ModelCommand& cmd);

}  // namespace inhand::app
