#include "test_support.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace inhand::test {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "tmp";
  for (char& c : name)
    if (c == '/') c = '_';
  path_ = (std::filesystem::temp_directory_path() / ("inhand-test-" + std::to_string(::getpid()) +
                                                     "-" + std::to_string(counter++) + "-" + name))
              .string();
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

void TempDir::Write(const std::string& rel, const std::string& contents) const {
  const std::filesystem::path p = std::filesystem::path(path_) / rel;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << contents;
}

namespace {

// A configuration folder of this test process's own, empty: the GUI's saved layout of whoever runs
// the tests never changes what they see. Removed when the process ends.
struct ConfigHome {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("inhand-test-config-" + std::to_string(::getpid()));
  ~ConfigHome() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace

CommandResult RunInhand(const std::string& args, const std::string& prefix) {
  static const ConfigHome config;
  // The sanitizer pass makes the tests' sessions with the Release simulator (scripts/
  // sanitize.sh sets INHAND_TEST_SIMULATOR): the simulator is tested in Release, and under ASan
  // one scenario took 19 s instead of 6 for every test that needs a session.
  std::string binary = INHAND_BINARY;
  if (const char* simulator = std::getenv("INHAND_TEST_SIMULATOR");
      simulator && *simulator && args.rfind("simulate ", 0) == 0)
    binary = simulator;
  const std::string cmd = "XDG_CONFIG_HOME='" + config.path.string() + "' " +
                          (prefix.empty() ? "" : prefix + " ") + binary + " " + args + " 2>&1";
  CommandResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace inhand::test
