// A fast lossless PNG encoder for camera frames: one filter for every row (Sub: the left
// neighbour, which is what makes photographs compressible) and a single deflate block coded
// with a Huffman code of the filtered bytes alone. LZ77 matching, which libpng's deflate spends
// most of its time on, finds next to nothing in a camera image (sensor noise); Huffman coding of
// the residuals gets within a few per cent of zlib level 1 at a fifth of its time. Any PNG
// decoder reads the result (tested against libpng through OpenCV). Checksums: libdeflate's.
#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <functional>
#include <queue>

#include "inhand/core/error.hpp"
#include "inhand/sessions/image_io.hpp"

namespace inhand {

namespace {

// Code lengths of a Huffman code for `freq`, none longer than `max_bits`. Symbols with zero
// frequency get length 0; at least two symbols always get a code (a complete code for zlib).
std::vector<int> HuffmanLengths(std::vector<std::uint64_t> freq, int max_bits) {
  const int n = static_cast<int>(freq.size());
  int used = 0;
  for (auto f : freq) used += f > 0;
  for (int s = 0; used < 2 && s < n; ++s)
    if (freq[static_cast<std::size_t>(s)] == 0) freq[static_cast<std::size_t>(s)] = 1, ++used;
  while (true) {
    // Plain Huffman over the used symbols.
    struct Node {
      std::uint64_t f;
      int left, right;
    };
    std::vector<Node> nodes;
    using Item = std::pair<std::uint64_t, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (int s = 0; s < n; ++s)
      if (freq[static_cast<std::size_t>(s)] > 0)
        nodes.push_back({freq[static_cast<std::size_t>(s)], -1, s}),
            q.push({nodes.back().f, static_cast<int>(nodes.size()) - 1});
    while (q.size() > 1) {
      const Item a = q.top();
      q.pop();
      const Item b = q.top();
      q.pop();
      nodes.push_back({a.first + b.first, a.second, b.second});
      q.push({nodes.back().f, static_cast<int>(nodes.size()) - 1});
    }
    std::vector<int> lengths(static_cast<std::size_t>(n), 0);
    int deepest = 0;
    // Depth-first over the tree: leaves have left == -1 and their symbol in right.
    std::vector<std::pair<int, int>> stack{{q.top().second, 0}};
    while (!stack.empty()) {
      const auto [i, depth] = stack.back();
      stack.pop_back();
      const Node& node = nodes[static_cast<std::size_t>(i)];
      if (node.left < 0) {
        lengths[static_cast<std::size_t>(node.right)] = std::max(depth, 1);
        deepest = std::max(deepest, depth);
      } else {
        stack.push_back({node.left, depth + 1});
        stack.push_back({node.right, depth + 1});
      }
    }
    if (deepest <= max_bits) return lengths;
    for (auto& f : freq)
      if (f > 0)
        f = (f + 1) / 2;  // flatten and try again (converges: equal counts give a balanced tree)
  }
}

// Canonical codes (RFC 1951 3.2.2), bit-reversed for deflate's least-significant-bit-first order.
std::vector<std::uint32_t> CanonicalCodes(const std::vector<int>& lengths) {
  std::array<int, 16> count{};
  for (int l : lengths) count[static_cast<std::size_t>(l)] += l > 0;
  std::array<std::uint32_t, 16> next{};
  std::uint32_t code = 0;
  for (int bits = 1; bits < 16; ++bits) {
    code = (code + static_cast<std::uint32_t>(count[static_cast<std::size_t>(bits - 1)])) << 1;
    next[static_cast<std::size_t>(bits)] = code;
  }
  std::vector<std::uint32_t> codes(lengths.size(), 0);
  for (std::size_t s = 0; s < lengths.size(); ++s) {
    const int l = lengths[s];
    if (l == 0) continue;
    const std::uint32_t c = next[static_cast<std::size_t>(l)]++;
    std::uint32_t r = 0;
    for (int b = 0; b < l; ++b) r |= ((c >> b) & 1u) << (l - 1 - b);
    codes[s] = r;
  }
  return codes;
}

// Least-significant-bit-first bits into a buffer the caller sized for the worst case.
class BitWriter {
 public:
  explicit BitWriter(std::uint8_t* out) : out_(out) {}
  // n <= 32; the buffer has 4 bytes to spare. Branch-free: the low word is always stored, the
  // pointer advances only when 32 bits are complete.
  void Put(std::uint32_t bits, int n) {
    acc_ |= static_cast<std::uint64_t>(bits) << fill_;
    fill_ += n;
    const auto word = static_cast<std::uint32_t>(acc_);
    const std::uint8_t b[4] = {
        static_cast<std::uint8_t>(word), static_cast<std::uint8_t>(word >> 8),
        static_cast<std::uint8_t>(word >> 16), static_cast<std::uint8_t>(word >> 24)};
    std::memcpy(out_, b, 4);
    const int full = fill_ >> 5;  // 0 or 1
    out_ += 4 * full;
    acc_ >>= 32 * full;
    fill_ -= 32 * full;
  }
  std::uint8_t* Flush() {
    while (fill_ > 0) {
      *out_++ = static_cast<std::uint8_t>(acc_);
      acc_ >>= 8;
      fill_ -= 8;
    }
    acc_ = 0, fill_ = 0;
    return out_;
  }

 private:
  std::uint8_t* out_;
  std::uint64_t acc_ = 0;
  int fill_ = 0;
};

void PutBe32(std::vector<std::uint8_t>* out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out->push_back(static_cast<std::uint8_t>(v >> s));
}

void Chunk(std::vector<std::uint8_t>* png, const char type[4], const std::uint8_t* data,
           std::size_t size) {
  PutBe32(png, static_cast<std::uint32_t>(size));
  const std::size_t at = png->size();
  png->insert(png->end(), type, type + 4);
  png->insert(png->end(), data, data + size);
  PutBe32(png, libdeflate_crc32(0, png->data() + at, size + 4));
}

}  // namespace

std::vector<std::uint8_t> EncodePng(const Image8& image) {
  INHAND_CHECK(image.channels == 1 || image.channels == 3, "EncodePng takes RGB or grey images");
  return EncodePng(
      image.data.data(), image.width, image.height, image.channels,
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.channels));
}

std::vector<std::uint8_t> EncodePng(const std::uint8_t* pixels, int width, int height, int channels,
                                    std::size_t stride) {
  INHAND_CHECK(channels == 1 || channels == 3, "EncodePng takes RGB or grey images");
  INHAND_CHECK(width > 0 && height > 0, "EncodePng of an empty image");
  const std::size_t c = static_cast<std::size_t>(channels);
  const std::size_t row = static_cast<std::size_t>(width) * c;
  INHAND_CHECK(stride >= row, "EncodePng: row stride shorter than a row");
  // Filtered scanlines: filter type 1 (Sub) then each byte minus the byte one pixel to its left.
  // Scratch buffers are kept per thread: fresh 1 MB allocations cost more in page faults than
  // the encoding itself.
  thread_local std::vector<std::uint8_t> raw, z;
  raw.resize((row + 1) * static_cast<std::size_t>(height));
  // Four histograms, merged after: consecutive bytes rarely wait on the same counter.
  std::array<std::array<std::uint32_t, 256>, 4> hist{};
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* p = pixels + static_cast<std::size_t>(y) * stride;
    std::uint8_t* o = raw.data() + static_cast<std::size_t>(y) * (row + 1);
    o[0] = 1;
    ++hist[0][1];
    for (std::size_t i = 0; i < c; ++i) o[1 + i] = p[i], ++hist[1][p[i]];
    std::size_t i = c;
    for (; i + 4 <= row; i += 4)
      for (std::size_t k = 0; k < 4; ++k) {
        const auto v = static_cast<std::uint8_t>(p[i + k] - p[i + k - c]);
        o[1 + i + k] = v;
        ++hist[k][v];
      }
    for (; i < row; ++i) {
      const auto v = static_cast<std::uint8_t>(p[i] - p[i - c]);
      o[1 + i] = v;
      ++hist[0][v];
    }
  }
  std::array<std::uint64_t, 286> counts{};
  for (std::size_t b = 0; b < 256; ++b)
    counts[b] = std::uint64_t{hist[0][b]} + hist[1][b] + hist[2][b] + hist[3][b];
  counts[256] = 1;  // end of block
  const std::vector<int> lit_len =
      HuffmanLengths(std::vector<std::uint64_t>(counts.begin(), counts.end()), 15);
  const std::vector<std::uint32_t> lit_code = CanonicalCodes(lit_len);

  // The code lengths of the 257 literal/length codes and one (unused, zero-length) distance
  // code, themselves Huffman-coded with the code-length alphabet (no run-length symbols).
  std::vector<int> all(lit_len.begin(), lit_len.begin() + 257);
  all.push_back(0);
  std::vector<std::uint64_t> cl_freq(19, 0);
  for (int l : all) ++cl_freq[static_cast<std::size_t>(l)];
  const std::vector<int> cl_len = HuffmanLengths(cl_freq, 7);
  const std::vector<std::uint32_t> cl_code = CanonicalCodes(cl_len);
  static constexpr int kOrder[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                     11, 4,  12, 3, 13, 2, 14, 1, 15};
  int hclen = 19;
  while (hclen > 4 && cl_len[static_cast<std::size_t>(kOrder[hclen - 1])] == 0) --hclen;

  // At most 15 bits a byte, plus the headers.
  z.resize(2 + raw.size() * 15 / 8 + 1024);
  z[0] = 0x78, z[1] = 0x01;  // zlib header: deflate, 32 K window, no dictionary
  BitWriter bits(z.data() + 2);
  bits.Put(1, 1);          // BFINAL
  bits.Put(2, 2);          // BTYPE = dynamic Huffman
  bits.Put(257 - 257, 5);  // HLIT
  bits.Put(1 - 1, 5);      // HDIST
  bits.Put(static_cast<std::uint32_t>(hclen - 4), 4);
  for (int i = 0; i < hclen; ++i)
    bits.Put(static_cast<std::uint32_t>(cl_len[static_cast<std::size_t>(kOrder[i])]), 3);
  for (int l : all)
    bits.Put(cl_code[static_cast<std::size_t>(l)], cl_len[static_cast<std::size_t>(l)]);
  // Two bytes per step: the pair's codes joined (at most 30 bits).
  thread_local std::vector<std::uint32_t> pair_code(65536);
  thread_local std::vector<std::uint8_t> pair_len(65536);
  for (std::uint32_t a = 0; a < 256; ++a)
    for (std::uint32_t b = 0; b < 256; ++b) {
      pair_code[a | b << 8] = lit_code[a] | lit_code[b] << lit_len[a];
      pair_len[a | b << 8] = static_cast<std::uint8_t>(lit_len[a] + lit_len[b]);
    }
  std::size_t i = 0;
  for (; i + 1 < raw.size(); i += 2) {
    const std::uint32_t pair = raw[i] | static_cast<std::uint32_t>(raw[i + 1]) << 8;
    bits.Put(pair_code[pair], pair_len[pair]);
  }
  if (i < raw.size()) bits.Put(lit_code[raw[i]], lit_len[raw[i]]);
  bits.Put(lit_code[256], lit_len[256]);
  std::uint8_t* end = bits.Flush();
  std::size_t zsize = static_cast<std::size_t>(end - z.data());
  const std::uint32_t adler = libdeflate_adler32(1, raw.data(), raw.size());
  for (int sh = 24; sh >= 0; sh -= 8) z[zsize++] = static_cast<std::uint8_t>(adler >> sh);

  std::vector<std::uint8_t> png;
  png.reserve(zsize + 64);
  png.insert(png.end(), {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'});
  std::vector<std::uint8_t> ihdr;
  PutBe32(&ihdr, static_cast<std::uint32_t>(width));
  PutBe32(&ihdr, static_cast<std::uint32_t>(height));
  ihdr.insert(ihdr.end(),
              {8, static_cast<std::uint8_t>(c == 3 ? 2 : 0), 0, 0, 0});  // 8 bit, RGB or grey
  Chunk(&png, "IHDR", ihdr.data(), ihdr.size());
  Chunk(&png, "IDAT", z.data(), zsize);
  Chunk(&png, "IEND", nullptr, 0);
  return png;
}

}  // namespace inhand
