#include "inhand/sessions/install_dirs.hpp"

#include <dlfcn.h>

#include <string>

namespace inhand {

std::filesystem::path RunningCodeDir() {
  // dladdr names a shared object by its path, but the main program only as it was invoked
  // (argv[0], a bare name when found on PATH): the program's path comes from /proc/self/exe.
  std::string self = "/proc/self/exe";
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&RunningCodeDir), &info) != 0 && info.dli_fname &&
      std::string(info.dli_fname).find('/') != std::string::npos)
    self = info.dli_fname;
  std::error_code ec;
  const std::filesystem::path file = std::filesystem::canonical(self, ec);
  return ec ? std::filesystem::path() : file.parent_path();
}

std::vector<std::filesystem::path> BesideRunningCode(const std::filesystem::path& relative) {
  const std::filesystem::path here = RunningCodeDir();
  if (here.empty()) return {};
  return {(here / ".." / relative).lexically_normal(),
          (here / "../../.." / relative).lexically_normal()};
}

}  // namespace inhand
