#include "inhand/sessions/image_io.hpp"

// PNG through libpng and JPEG through libjpeg(-turbo), called directly: OpenCV's imgcodecs would
// do the same, but linking it maps GDAL, poppler, HDF5 and some seventy other libraries into
// every process (0.17 s of start-up). Errors come back through setjmp/longjmp, C-style, inside
// functions whose locals are plain data; the callers turn them into InputError naming the file.
#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

constexpr double kMaxPixels = 1 << 28;  // 268 megapixels

bool SizeInRange(double w, double h) { return w >= 1 && h >= 1 && w * h <= kMaxPixels; }

// Any image header's size: refuse an absurd one before allocating (a 60000 x 60000 PNG header).
void CheckSize(double w, double h, const char* format, const std::string& what) {
  if (!SizeInRange(w, h))
    throw InputError(
        what + ": the " + format + " header says " + std::to_string(static_cast<long long>(w)) +
        "x" + std::to_string(static_cast<long long>(h)) + " px; expected 1 to 268 million pixels");
}

// ---- PNG ------------------------------------------------------------------------------------

// libpng's error text, kept for the InputError (libpng's error pointer, reading and writing).
struct PngMessage {
  char text[256];
};

void PngError(png_structp png, png_const_charp msg) {
  auto* message = static_cast<PngMessage*>(png_get_error_ptr(png));
  std::snprintf(message->text, sizeof(message->text), "%s", msg);
  png_longjmp(png, 1);
}
void PngWarning(png_structp, png_const_charp) {}

struct PngSource {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t pos;
};

void PngRead(png_structp png, png_bytep out, png_size_t n) {
  auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
  if (n > src->size - src->pos) png_error(png, "truncated");
  std::memcpy(out, src->data + src->pos, n);
  src->pos += n;
}

// 8-bit RGB whatever the file holds, as OpenCV's IMREAD_COLOR gives it: palettes and grey
// expanded, 16 bits cut to their high byte, alpha dropped (not composited). The header's size
// has been checked by the caller.
bool DecodePng(PngSource* src, Image8* out, PngMessage* message) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows;
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, src, PngRead);
  png_read_info(png, info);
  const auto w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  const int colour = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((colour & PNG_COLOR_MASK_COLOR) == 0 && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (depth == 16) png_set_strip_16(png);
  if ((colour & PNG_COLOR_MASK_ALPHA) != 0) png_set_strip_alpha(png);
  if ((colour & PNG_COLOR_MASK_COLOR) == 0) png_set_gray_to_rgb(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_channels(png, info) != 3 || png_get_rowbytes(png, info) != 3 * std::size_t{w})
    png_error(png, "unsupported pixel layout");
  *out = Image8(static_cast<int>(w), static_cast<int>(h), 3);
  rows.resize(static_cast<std::size_t>(h));
  for (int y = 0; y < out->height; ++y) rows[static_cast<std::size_t>(y)] = out->pixel(0, y);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

void PngWrite(png_structp png, png_bytep data, png_size_t n) {
  auto* bytes = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  bytes->insert(bytes->end(), data, data + n);
}
void PngFlush(png_structp) {}

// Grey, RGB or RGBA as PNG, with the settings OpenCV's writer uses by default (zlib level 1,
// run-length strategy): saved pictures stay as small as before.
bool EncodePngLibpng(const Image8& image, std::vector<std::uint8_t>* bytes, PngMessage* message) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.height));
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, bytes, PngWrite, PngFlush);
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, 3);  // Z_RLE
  const int type = image.channels == 1   ? PNG_COLOR_TYPE_GRAY
                   : image.channels == 3 ? PNG_COLOR_TYPE_RGB
                                         : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  for (int y = 0; y < image.height; ++y)
    rows[static_cast<std::size_t>(y)] = const_cast<std::uint8_t*>(image.pixel(0, y));
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// ---- JPEG -----------------------------------------------------------------------------------

struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegExit(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  std::longjmp(err->jump, 1);
}
void JpegMessage(j_common_ptr) {}

// False with err->message on a libjpeg error; throws InputError naming `context` when the
// header's size is out of range.
bool DecodeJpeg(const std::uint8_t* data, std::size_t size, Image8* out, JpegError* err,
                const std::string& context) {
  jpeg_decompress_struct cinfo{};
  cinfo.err = jpeg_std_error(&err->mgr);
  err->mgr.error_exit = JpegExit;
  err->mgr.output_message = JpegMessage;
  if (setjmp(err->jump)) {
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  const double w = cinfo.image_width, h = cinfo.image_height;
  if (!SizeInRange(w, h)) {
    jpeg_destroy_decompress(&cinfo);
    CheckSize(w, h, "JPEG", context);
  }
  cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&cinfo);
  *out = Image8(static_cast<int>(cinfo.output_width), static_cast<int>(cinfo.output_height), 3);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out->pixel(0, static_cast<int>(cinfo.output_scanline));
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return true;
}

bool EncodeJpegInto(const Image8& image, int quality, std::vector<std::uint8_t>* bytes,
                    JpegError* err) {
  jpeg_compress_struct cinfo{};
  cinfo.err = jpeg_std_error(&err->mgr);
  err->mgr.error_exit = JpegExit;
  err->mgr.output_message = JpegMessage;
  unsigned char* buffer = nullptr;
  unsigned long length = 0;
  if (setjmp(err->jump)) {
    jpeg_destroy_compress(&cinfo);
    std::free(buffer);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, &buffer, &length);
  cinfo.image_width = static_cast<JDIMENSION>(image.width);
  cinfo.image_height = static_cast<JDIMENSION>(image.height);
  cinfo.input_components = image.channels;
  cinfo.in_color_space = image.channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<std::uint8_t*>(image.pixel(0, static_cast<int>(cinfo.next_scanline)));
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  bytes->assign(buffer, buffer + length);
  jpeg_destroy_compress(&cinfo);
  std::free(buffer);
  return true;
}

bool IsPng(const std::uint8_t* data, std::size_t size) {
  static const std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::equal(kPng, kPng + 8, data);
}
bool IsJpeg(const std::uint8_t* data, std::size_t size) {
  return size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
}

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

Image8 ReadImage(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": image file not found");
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw InputError(path + ": cannot read the image file");
  return DecodeImage(bytes.data(), bytes.size(), path);
}

Image8 DecodeImage(const std::uint8_t* data, std::size_t size, const std::string& context) {
  Image8 out;
  if (IsPng(data, size)) {
    // The header's size is checked before libpng sees it (and its CRC): the message names it.
    const auto be32 = [&](std::size_t at) {
      return (double(data[at]) * 256 + data[at + 1]) * 65536 + double(data[at + 2]) * 256 +
             data[at + 3];
    };
    if (size >= 24) CheckSize(be32(16), be32(20), "PNG", context);
    PngSource src{data, size, 0};
    PngMessage message{};
    if (!DecodePng(&src, &out, &message))
      throw InputError(context + ": not a readable image (PNG: " + message.text + ")");
    return out;
  }
  if (IsJpeg(data, size)) {
    JpegError err{};
    if (!DecodeJpeg(data, size, &out, &err, context))
      throw InputError(context + ": not a readable image (JPEG: " + err.message + ")");
    return out;
  }
  throw InputError(context + ": not a readable image (expected PNG or JPEG data)");
}

std::vector<std::uint8_t> EncodeJpeg(const Image8& image, int quality) {
  INHAND_CHECK(image.channels == 1 || image.channels == 3, "EncodeJpeg takes RGB or grey images");
  INHAND_CHECK(image.width > 0 && image.height > 0, "EncodeJpeg of an empty image");
  std::vector<std::uint8_t> bytes;
  JpegError err{};
  if (!EncodeJpegInto(image, std::clamp(quality, 1, 100), &bytes, &err))
    throw std::runtime_error(std::string("JPEG encoding failed: ") + err.message);
  return bytes;
}

void WriteImage(const std::string& path, const Image8& image) {
  INHAND_CHECK(image.channels == 1 || image.channels == 3 || image.channels == 4,
               "WriteImage takes grey, RGB or RGBA images");
  const std::string ext = LowerExtension(path);
  std::vector<std::uint8_t> bytes;
  if (ext == ".png") {
    PngMessage message{};
    if (!EncodePngLibpng(image, &bytes, &message))
      throw InputError(path + ": cannot encode the PNG (" + message.text + ")");
  } else if (ext == ".jpg" || ext == ".jpeg") {
    if (image.channels == 4) throw InputError(path + ": JPEG has no alpha; write a .png");
    bytes = EncodeJpeg(image, 95);
  } else {
    throw InputError(path + ": cannot write image (expected a .png, .jpg or .jpeg name)");
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out.good()) throw InputError(path + ": cannot write image");
}

}  // namespace inhand
