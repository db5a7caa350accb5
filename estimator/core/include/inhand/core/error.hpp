#pragma once
// Error tiers:
//  - InputError: bad user input or files. The message names the file, line or field and what
//    was expected. Callers (the CLI) print it and exit non-zero.
//  - INHAND_CHECK: broken invariants. Always on; aborts with file:line and the condition.
//  - Hot loops use Eigen's/assert's debug checks only.
#include <stdexcept>
#include <string>

namespace inhand {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

[[noreturn]] void CheckFailed(const char* condition, const char* file, int line,
                              const std::string& message);

}  // namespace inhand

#define INHAND_CHECK(cond, msg)                                           \
  do {                                                                    \
    if (!(cond)) ::inhand::CheckFailed(#cond, __FILE__, __LINE__, (msg)); \
  } while (false)
