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
// PNG bytes of an RGB or grey image, lossless, fast (Sub filter + Huffman-only deflate,
// png_writer.cpp): about 2 ms for a 640x480 camera frame, within a few per cent of libpng's size.
std::vector<std::uint8_t> EncodePng(const Image8& image);
// The same from rows of `stride` bytes (a recorded message's buffer, without a copy).
std::vector<std::uint8_t> EncodePng(const std::uint8_t* pixels, int width, int height, int channels,
                                    std::size_t stride);

}  // namespace inhand
