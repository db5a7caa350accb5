#pragma once
// A read-only memory map of a whole file (recordings are read once, front to back). Internal.
#include <cstddef>
#include <cstdint>
#include <string>

namespace inhand::ros {

class MappedFile {
 public:
  // Throws InputError naming the file when it cannot be opened.
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace inhand::ros
