#pragma once
// Image files <-> Image8 (OpenCV imgcodecs behind the .cpp). RGB in memory.
#include <cstdint>
#include <string>
#include <vector>

#include "inhand/core/image.hpp"

namespace inhand {

// Throws InputError naming the file when it is missing or not a readable image.
Image8 ReadImage(const std::string& path);
// Writes PNG/JPEG by extension; throws InputError when the file cannot be written.
void WriteImage(const std::string& path, const Image8& image);
// Decodes PNG or JPEG bytes into RGB; throws InputError naming `context` when they are not an
// image. Thread-safe (no stderr redirection: decoders may print their own warnings).
Image8 DecodeImage(const std::uint8_t* data, std::size_t size, const std::string& context);
// PNG bytes of an RGB or grey image, at the fastest compression (lossless either way).
std::vector<std::uint8_t> EncodePng(const Image8& image);

}  // namespace inhand
