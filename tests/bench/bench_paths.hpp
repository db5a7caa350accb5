// Where the benchmarks find the project's assets and the shared ones beside the repository.
#pragma once

#include <string>

namespace inhand {

inline const std::string kRoot = INHAND_SOURCE_DIR;

}  // namespace inhand
