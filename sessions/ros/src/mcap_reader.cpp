// ROS 2 recordings in MCAP (mcap.dev/spec): records scanned front to back, chunks decompressed
// (none, zstd, lz4 frames), messages of the chosen channels decoded from CDR.
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <map>

#include "cdr.hpp"
#include "inhand/core/error.hpp"
#include "mapped_file.hpp"
#include "mcap_format.hpp"
#include "recordings.hpp"

namespace inhand::ros {

namespace {

using namespace mcap;  // NOLINT: the format's opcodes

// Bounds-checked little-endian reads inside one record.
class Cursor {
 public:
  Cursor(const std::uint8_t* p, std::size_t n, const std::string& context)
      : p_(p), n_(n), context_(context) {}
  template <class T>
  T Int() {
    Need(sizeof(T));
    T v;
    std::memcpy(&v, p_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string String() {
    const std::uint32_t len = Int<std::uint32_t>();
    Need(len);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), len);
    pos_ += len;
    return s;
  }
  const std::uint8_t* Bytes(std::size_t len) {
    Need(len);
    const std::uint8_t* b = p_ + pos_;
    pos_ += len;
    return b;
  }
  std::size_t remaining() const { return n_ - pos_; }

 private:
  void Need(std::size_t k) const {
    if (k > n_ - pos_)
      throw InputError(context_ + ": record ends before its fields (corrupt MCAP)");
  }
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
  const std::string& context_;
};

struct Channel {
  std::string topic, type, encoding;
  MsgType msg_type = MsgType::kOther;
  std::uint64_t count = 0;
  std::int64_t first = 0, last = 0;
  bool wanted = false;
};

class McapRecording final : public Recording {
 public:
  explicit McapRecording(const std::string& path) : file_(path) {
    path_ = path;
    const std::uint8_t* d = file_.data();
    if (file_.size() < 8 || std::memcmp(d, kMagic, 8) != 0)
      throw InputError(path + ": not an MCAP file (no leading magic bytes)");
  }
  std::string format() const override { return "MCAP"; }

  std::vector<TopicInfo> Topics() override {
    Scan({}, false, nullptr, {});
    std::map<std::string, TopicInfo> by_topic;
    for (const auto& [id, c] : channels_) {
      TopicInfo& t = by_topic[c.topic];
      if (t.count == 0) t.first_ns = c.first, t.last_ns = c.last;
      t.name = c.topic;
      t.type = c.type;
      if (c.count > 0) {
        t.first_ns = t.count == 0 ? c.first : std::min(t.first_ns, c.first);
        t.last_ns = t.count == 0 ? c.last : std::max(t.last_ns, c.last);
      }
      t.count += c.count;
    }
    std::vector<TopicInfo> out;
    for (auto& [name, t] : by_topic) out.push_back(t);
    return out;
  }

  void Read(const std::vector<std::string>& topics, bool decode_images,
            const std::function<void(Message&)>& on_message,
            const std::function<void(double)>& progress) override {
    Scan(topics, decode_images, &on_message, progress);
  }

 private:
  [[noreturn]] void Truncated(std::size_t at, const std::string& what) const {
    throw InputError(path_ + ": truncated or corrupt MCAP at byte " + std::to_string(at) + " of " +
                     std::to_string(file_.size()) + " (" + what + ")");
  }

  // One pass over the data section. `on_message` null: only counts messages per channel.
  void Scan(const std::vector<std::string>& topics, bool decode_images,
            const std::function<void(Message&)>* on_message,
            const std::function<void(double)>& progress) {
    channels_.clear();
    schemas_.clear();
    wanted_ = topics;
    const std::uint8_t* d = file_.data();
    const std::size_t n = file_.size();
    std::size_t pos = 8;
    bool ended = false;
    std::size_t last_progress = 0;
    while (!ended) {
      if (pos == n) Truncated(pos, "the file ends before its data-end record and footer");
      if (n - pos < 9) Truncated(pos, "a record header is cut off");
      const std::uint8_t op = d[pos];
      std::uint64_t len;
      std::memcpy(&len, d + pos + 1, 8);
      if (len > n - pos - 9)
        Truncated(pos, "record 0x" + Hex(op) + " claims " + std::to_string(len) + " bytes, " +
                           std::to_string(n - pos - 9) + " remain");
      const std::uint8_t* body = d + pos + 9;
      if (op == kDataEnd || op == kFooter)
        ended = true;
      else if (op == kChunk)
        Chunk(body, len, pos, decode_images, on_message);
      else
        Record(op, body, len, pos, decode_images, on_message);
      pos += 9 + len;
      if (progress && pos - last_progress > (1u << 22))
        progress(static_cast<double>(pos) / static_cast<double>(n)), last_progress = pos;
    }
    if (progress) progress(1.0);
  }

  static std::string Hex(std::uint8_t v) {
    const char* digits = "0123456789abcdef";
    return std::string{digits[v >> 4], digits[v & 15]};
  }

  void Chunk(const std::uint8_t* body, std::uint64_t len, std::size_t at, bool decode_images,
             const std::function<void(Message&)>* on_message) {
    const std::string context = path_ + ": chunk at byte " + std::to_string(at);
    Cursor c(body, len, context);
    c.Int<std::uint64_t>();  // message start time
    c.Int<std::uint64_t>();  // message end time
    const std::uint64_t uncompressed = c.Int<std::uint64_t>();
    c.Int<std::uint32_t>();  // uncompressed CRC (0: not computed)
    const std::string compression = c.String();
    const std::uint64_t size = c.Int<std::uint64_t>();
    if (size > c.remaining())
      throw InputError(context + ": records run past the chunk (corrupt MCAP)");
    const std::uint8_t* records = c.Bytes(size);
    const std::uint8_t* plain = records;
    if (compression.empty()) {
      if (uncompressed != size)
        throw InputError(context + ": uncompressed size " + std::to_string(uncompressed) +
                         " differs from the records' " + std::to_string(size));
    } else {
      // Recorders write chunks of a few megabytes; a gigabyte is a corrupt size field.
      if (uncompressed > (std::uint64_t{1} << 30))
        throw InputError(context + ": implausible uncompressed size " +
                         std::to_string(uncompressed) + " (corrupt MCAP?)");
      buffer_.resize(uncompressed);
      if (compression == "zstd") {
        const std::size_t got = ZSTD_decompress(buffer_.data(), uncompressed, records, size);
        if (ZSTD_isError(got) || got != uncompressed)
          throw InputError(
              context + ": zstd data does not decompress to its " + std::to_string(uncompressed) +
              " bytes" +
              (ZSTD_isError(got) ? std::string(" (") + ZSTD_getErrorName(got) + ")" : ""));
      } else if (compression == "lz4") {
        Lz4(records, size, uncompressed, context);
      } else {
        throw InputError(context + ": unsupported chunk compression '" + compression +
                         "' (expected none, zstd or lz4)");
      }
      plain = buffer_.data();
    }
    // The records inside; the buffer is not touched again until they are done.
    std::size_t pos = 0;
    while (pos < uncompressed) {
      if (uncompressed - pos < 9)
        throw InputError(context + ": a record header inside the chunk is cut off");
      const std::uint8_t op = plain[pos];
      std::uint64_t rlen;
      std::memcpy(&rlen, plain + pos + 1, 8);
      if (rlen > uncompressed - pos - 9)
        throw InputError(context + ": a record inside the chunk runs past its end");
      Record(op, plain + pos + 9, rlen, at, decode_images, on_message);
      pos += 9 + rlen;
    }
  }

  void Lz4(const std::uint8_t* src, std::size_t size, std::size_t uncompressed,
           const std::string& context) {
    LZ4F_dctx* dctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&dctx, LZ4F_VERSION)))
      throw InputError(context + ": cannot create an lz4 context");
    std::size_t in_done = 0, out_done = 0;
    std::size_t hint = 1;
    while (hint != 0 && in_done < size) {
      std::size_t in = size - in_done, out = uncompressed - out_done;
      hint = LZ4F_decompress(dctx, buffer_.data() + out_done, &out, src + in_done, &in, nullptr);
      if (LZ4F_isError(hint)) {
        const std::string e = LZ4F_getErrorName(hint);
        LZ4F_freeDecompressionContext(dctx);
        throw InputError(context + ": lz4 data does not decompress (" + e + ")");
      }
      in_done += in;
      out_done += out;
      if (in == 0 && out == 0) break;
    }
    LZ4F_freeDecompressionContext(dctx);
    if (out_done != uncompressed || hint != 0)
      throw InputError(context + ": lz4 data decompresses to " + std::to_string(out_done) +
                       " bytes, the chunk says " + std::to_string(uncompressed));
  }

  void Record(std::uint8_t op, const std::uint8_t* body, std::uint64_t len, std::size_t at,
              bool decode_images, const std::function<void(Message&)>* on_message) {
    if (op == kSchema) {
      const std::string context = path_ + ": schema record at byte " + std::to_string(at);
      Cursor c(body, len, context);
      const auto id = c.Int<std::uint16_t>();
      schemas_[id] = c.String();
    } else if (op == kChannel) {
      const std::string context = path_ + ": channel record at byte " + std::to_string(at);
      Cursor c(body, len, context);
      const auto id = c.Int<std::uint16_t>();
      const auto schema = c.Int<std::uint16_t>();
      if (channels_.count(id)) return;  // repeated in the summary
      Channel ch;
      ch.topic = c.String();
      ch.encoding = c.String();
      auto s = schemas_.find(schema);
      ch.type = NormaliseTypeName(s == schemas_.end() ? std::string("(no schema)") : s->second);
      ch.msg_type = MsgTypeOf(ch.type);
      ch.wanted = wanted_.empty()
                      ? false
                      : std::find(wanted_.begin(), wanted_.end(), ch.topic) != wanted_.end();
      channels_[id] = ch;
    } else if (op == kMessage) {
      if (len < 22)
        throw InputError(path_ + ": message record at byte " + std::to_string(at) +
                         " is shorter than its fields (corrupt MCAP)");
      std::uint16_t id;
      std::uint64_t log;
      std::memcpy(&id, body, 2);
      std::memcpy(&log, body + 6, 8);
      auto it = channels_.find(id);
      if (it == channels_.end())
        throw InputError(path_ + ": message at byte " + std::to_string(at) + " on channel " +
                         std::to_string(id) + ", which no channel record declares");
      Channel& ch = it->second;
      const auto log_ns = static_cast<std::int64_t>(log);
      ch.first = ch.count == 0 ? log_ns : std::min(ch.first, log_ns);
      ch.last = ch.count == 0 ? log_ns : std::max(ch.last, log_ns);
      const std::uint64_t index = ch.count++;
      if (on_message == nullptr || !ch.wanted) return;
      if (ch.msg_type != MsgType::kOther && ch.encoding != "cdr")
        throw InputError(path_ + ": topic " + ch.topic + " is encoded as '" + ch.encoding +
                         "', expected cdr (ROS 2)");
      Message m;
      m.topic = &ch.topic;
      m.type = &ch.type;
      m.log_ns = log_ns;
      m.payload = DecodeCdr(ch.msg_type, body + 22, len - 22, decode_images,
                            path_ + ": topic " + ch.topic + ", message " + std::to_string(index));
      (*on_message)(m);
    }
    // Everything else (indexes, attachments, metadata, statistics) is not needed.
  }

  MappedFile file_;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, Channel> channels_;
  std::vector<std::string> wanted_;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace

std::unique_ptr<Recording> OpenMcap(const std::string& path) {
  return std::make_unique<McapRecording>(path);
}

}  // namespace inhand::ros
