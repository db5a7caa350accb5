#pragma once
// Internal to app: an output folder written under a hidden temporary name beside the target
// and renamed into place by Commit(); destroyed uncommitted, it leaves nothing behind.
#include <unistd.h>

#include <filesystem>
#include <string>

#include "inhand/core/error.hpp"

namespace inhand::app {

class StagedOutput {
 public:
  explicit StagedOutput(const std::string& out) : final_(std::filesystem::absolute(out).lexically_normal()) {
    if (final_.filename().empty()) final_ = final_.parent_path();
    tmp_ = final_.parent_path() / ("." + final_.filename().string() + ".tmp-" + std::to_string(::getpid()));
    std::filesystem::remove_all(tmp_);
    std::error_code ec;
    std::filesystem::create_directories(tmp_, ec);
    if (ec) throw InputError(out + ": cannot create the output folder (" + ec.message() + ")");
  }
  ~StagedOutput() {
    std::error_code ec;
    if (!committed_) std::filesystem::remove_all(tmp_, ec);
  }
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;
  std::filesystem::path operator/(const std::string& rel) const { return tmp_ / rel; }
  void Commit() {
    std::filesystem::remove_all(final_);
    std::filesystem::rename(tmp_, final_);
    committed_ = true;
  }

 private:
  std::filesystem::path final_, tmp_;
  bool committed_ = false;
};

}  // namespace inhand::app
