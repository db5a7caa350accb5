#pragma once
// FNV-1a, 64 bit: the key of inhand's on-disk caches (HACD pieces, distance fields). Internal to
// io/.
#include <cstddef>
#include <cstdint>

#include "inhand/core/so3.hpp"

namespace inhand::detail {

class Fnv1a {
 public:
  void Mix(const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ b[i]) * 1099511628211ULL;
  }
  void Mix(const Vec3& v) { Mix(v.data(), 3 * sizeof(double)); }
  void Mix(double x) { Mix(&x, sizeof x); }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ULL;
};

}  // namespace inhand::detail
