#pragma once
// Image files <-> Image8 (OpenCV imgcodecs behind the .cpp). RGB in memory.
#include <string>

#include "inhand/core/image.hpp"

namespace inhand {

// Throws InputError naming the file when it is missing or not a readable image.
Image8 ReadImage(const std::string& path);
// Writes PNG/JPEG by extension; throws InputError when the file cannot be written.
void WriteImage(const std::string& path, const Image8& image);

}  // namespace inhand
