#pragma once
// Internal to app: an output folder written under a hidden staging name beside the target and
// renamed into place by Commit(); destroyed uncommitted, it leaves nothing behind. Only what
// inhand may replace is replaced (sessions/output_folder.hpp).
#include <filesystem>
#include <string>
#include <vector>

#include "inhand/sessions/output_folder.hpp"

namespace inhand::app {

class StagedOutput {
 public:
  // `inputs`: what the command reads (never replaced, nor their ancestors).
  StagedOutput(const std::string& out, const std::vector<std::string>& inputs, std::string command)
      : final_(CheckOutputFolder(out, inputs)),
        tmp_(PrepareStaging(final_)),
        command_(std::move(command)) {}
  ~StagedOutput() {
    std::error_code ec;
    if (!committed_) std::filesystem::remove_all(tmp_, ec);
  }
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;
  std::filesystem::path operator/(const std::string& rel) const { return tmp_ / rel; }
  void Commit() {
    CommitStaging(tmp_, final_, command_);
    committed_ = true;
  }

 private:
  std::filesystem::path final_, tmp_;
  std::string command_;
  bool committed_ = false;
};

}  // namespace inhand::app
