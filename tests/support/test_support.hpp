#pragma once
// Shared test helpers: where the repository and ../shared/assets are, temp directories, and
// running the inhand binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace inhand::test {

inline std::string SourceDir() { return INHAND_SOURCE_DIR; }

// Built with AddressSanitizer and UBSan (scripts/sanitize.sh): the heaviest loops draw fewer
// samples there, with the same assertions (the Release build runs them whole).
#ifdef INHAND_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
inline std::string ProjectAsset(const std::string& rel) { return SourceDir() + "/assets/" + rel; }

// ../shared/assets beside the repository, or "" when absent (tests then skip).
inline std::string SharedAssets() {
  const std::filesystem::path p =
      std::filesystem::path(SourceDir()).parent_path() / "shared" / "assets";
  return std::filesystem::is_directory(p) ? p.string() : std::string();
}

#define INHAND_REQUIRE_SHARED_ASSETS()                                             \
  do {                                                                             \
    if (::inhand::test::SharedAssets().empty())                                    \
      GTEST_SKIP() << "../shared/assets is absent: third-party assets not tested"; \
  } while (false)

// A whole file's bytes ("" when it cannot be read).
inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A fresh directory under the build's temp area, removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& rel) const { return path_ + "/" + rel; }
  void Write(const std::string& rel, const std::string& contents) const;

 private:
  std::string path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};
// Runs the inhand binary with `args` (a shell-quoted string); `prefix` goes before the binary
// (e.g. "env -u DISPLAY" or "xvfb-run -a"). XDG_CONFIG_HOME is an empty folder of the test
// process (a prefix "env XDG_CONFIG_HOME=DIR" gives another).
CommandResult RunInhand(const std::string& args, const std::string& prefix = "");
inline std::string InhandBinary() { return INHAND_BINARY; }

// The same seeded generator everywhere: failures reproduce.
inline std::mt19937& Rng() {
  static std::mt19937 rng(20180412u);
  return rng;
}

}  // namespace inhand::test
