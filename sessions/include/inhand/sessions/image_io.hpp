#pragma once
// Image files <-> Image8: PNG (libpng) and JPEG (libjpeg-turbo). RGB in memory.
#include <cstdint>
#include <string>
#include <vector>

#include "inhand/core/image.hpp"

namespace inhand {

// Throws InputError naming the file when it is missing or not a readable image.
Image8 ReadImage(const std::string& path);
// Writes PNG (grey, RGB or RGBA) or JPEG (quality 95) by extension (.png, .jpg, .jpeg); throws
// InputError when the name has another extension or the file cannot be written.
void WriteImage(const std::string& path, const Image8& image);
// Decodes PNG or JPEG bytes into 8-bit RGB (grey and palettes expanded, 16 bits cut to their high
// byte, alpha dropped); throws InputError naming `context` when they are not such an image or
// its header claims more than 268 million pixels. Thread-safe; the decoders print nothing.
Image8 DecodeImage(const std::uint8_t* data, std::size_t size, const std::string& context);
// JPEG bytes of an RGB or grey image (libjpeg's defaults: 4:2:0, baseline, quality 1-100).
std::vector<std::uint8_t> EncodeJpeg(const Image8& image, int quality);
// PNG bytes of an RGB or grey image, lossless, fast (Sub filter + Huffman-only deflate,
// png_writer.cpp): about 2 ms for a 640x480 camera frame, within a few per cent of libpng's size.
std::vector<std::uint8_t> EncodePng(const Image8& image);
// The same from rows of `stride` bytes (a recorded message's buffer, without a copy).
std::vector<std::uint8_t> EncodePng(const std::uint8_t* pixels, int width, int height, int channels,
                                    std::size_t stride);

}  // namespace inhand
