#include "inhand/ros/mcap_writer.hpp"

#include <libdeflate.h>
#include <zstd.h>

#include <algorithm>

#include "inhand/core/error.hpp"
#include "mcap_format.hpp"

namespace inhand::ros {

namespace {

using namespace mcap;  // NOLINT: the format's opcodes

template <class T>
void Int(std::string* s, T v) {
  char b[sizeof(T)];
  for (std::size_t i = 0; i < sizeof(T); ++i)
    b[i] = static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xff);
  s->append(b, sizeof(T));
}
void Str(std::string* s, const std::string& v) {
  Int<std::uint32_t>(s, static_cast<std::uint32_t>(v.size()));
  s->append(v);
}
std::string Record(std::uint8_t op, const std::string& body) {
  std::string r(1, static_cast<char>(op));
  Int<std::uint64_t>(&r, body.size());
  r += body;
  return r;
}
std::uint32_t Crc(std::uint32_t crc, const std::string& bytes) {
  return libdeflate_crc32(crc, bytes.data(), bytes.size());
}

}  // namespace

McapWriter::McapWriter(const std::string& path, const std::string& library,
                       McapWriterOptions options)
    : path_(path), options_(std::move(options)), out_(path, std::ios::binary) {
  if (!out_) throw InputError(path + ": cannot write");
  INHAND_CHECK(options_.compression.empty() || options_.compression == "zstd",
               "MCAP chunks are zstd-compressed or stored");
  out_.write(kMagic, 8);
  crc_ = Crc(0, std::string(kMagic, 8));
  offset_ = 8;
  std::string header;
  Str(&header, options_.profile);
  Str(&header, library);
  Put(kHeader, header);
}

McapWriter::~McapWriter() {
  if (!closed_) {
    try {
      Close();
    } catch (...) {
    }
  }
}

void McapWriter::Put(std::uint8_t op, const std::string& body) {
  const std::string r = Record(op, body);
  out_.write(r.data(), static_cast<std::streamsize>(r.size()));
  offset_ += r.size();
  crc_ = Crc(crc_, r);
  if (!out_) throw InputError(path_ + ": write failed");
}

std::uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                                    const std::string& data) {
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);  // 0 means "no schema"
  std::string body;
  Int<std::uint16_t>(&body, id);
  Str(&body, name);
  Str(&body, encoding);
  Str(&body, data);
  Put(kSchema, body);
  schemas_.push_back(body);
  return id;
}

std::uint16_t McapWriter::AddChannel(const std::string& topic, std::uint16_t schema,
                                     const std::string& message_encoding) {
  const auto id = static_cast<std::uint16_t>(channels_.size());
  std::string body;
  Int<std::uint16_t>(&body, id);
  Int<std::uint16_t>(&body, schema);
  Str(&body, topic);
  Str(&body, message_encoding);
  Int<std::uint32_t>(&body, 0);  // metadata: empty map
  Put(kChannel, body);
  channels_.push_back(body);
  sequence_.push_back(0);
  counts_[id] = 0;
  return id;
}

void McapWriter::Write(std::uint16_t channel, std::uint64_t log_time_ns, const std::string& data) {
  INHAND_CHECK(channel < channels_.size(), "MCAP message on an unknown channel");
  std::string body;
  Int<std::uint16_t>(&body, channel);
  Int<std::uint32_t>(&body, sequence_[channel]++);
  Int<std::uint64_t>(&body, log_time_ns);
  Int<std::uint64_t>(&body, log_time_ns);  // publish time
  body.append(data);
  // The message index: its log time and its offset among the chunk's uncompressed records.
  std::string& entries = chunk_entries_[channel];
  Int<std::uint64_t>(&entries, log_time_ns);
  Int<std::uint64_t>(&entries, chunk_.size());
  chunk_start_ = chunk_.empty() ? log_time_ns : std::min(chunk_start_, log_time_ns);
  chunk_end_ = chunk_.empty() ? log_time_ns : std::max(chunk_end_, log_time_ns);
  chunk_ += Record(kMessage, body);
  ++counts_[channel];
  start_ = messages_ == 0 ? log_time_ns : std::min(start_, log_time_ns);
  end_ = messages_ == 0 ? log_time_ns : std::max(end_, log_time_ns);
  ++messages_;
  if (chunk_.size() >= options_.chunk_size) FlushChunk();
}

void McapWriter::FlushChunk() {
  if (chunk_.empty()) return;
  std::string records = chunk_;
  if (options_.compression == "zstd") {
    records.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress(records.data(), records.size(), chunk_.data(),
                                        chunk_.size(), options_.zstd_level);
    if (ZSTD_isError(n)) throw InputError(path_ + ": zstd: " + ZSTD_getErrorName(n));
    records.resize(n);
  }
  std::string body;
  Int<std::uint64_t>(&body, chunk_start_);
  Int<std::uint64_t>(&body, chunk_end_);
  Int<std::uint64_t>(&body, chunk_.size());
  Int<std::uint32_t>(&body, Crc(0, chunk_));
  Str(&body, options_.compression);
  Int<std::uint64_t>(&body, records.size());
  body += records;
  const std::uint64_t chunk_offset = offset_;
  Put(kChunk, body);
  const std::uint64_t chunk_length = offset_ - chunk_offset;
  // Its message indexes, one per channel, right after it.
  std::string offsets;
  const std::uint64_t indexes_start = offset_;
  for (const auto& [channel, entries] : chunk_entries_) {
    Int<std::uint16_t>(&offsets, channel);
    Int<std::uint64_t>(&offsets, offset_);
    std::string index;
    Int<std::uint16_t>(&index, channel);
    Str(&index, entries);  // a u32 byte length, then the (time, offset) pairs
    Put(kMessageIndex, index);
  }
  std::string chunk_index;
  Int<std::uint64_t>(&chunk_index, chunk_start_);
  Int<std::uint64_t>(&chunk_index, chunk_end_);
  Int<std::uint64_t>(&chunk_index, chunk_offset);
  Int<std::uint64_t>(&chunk_index, chunk_length);
  Str(&chunk_index, offsets);
  Int<std::uint64_t>(&chunk_index, offset_ - indexes_start);
  Str(&chunk_index, options_.compression);
  Int<std::uint64_t>(&chunk_index, records.size());
  Int<std::uint64_t>(&chunk_index, chunk_.size());
  chunk_indexes_.push_back(chunk_index);
  ++chunks_;
  chunk_.clear();
  chunk_entries_.clear();
}

void McapWriter::Close() {
  if (closed_) return;
  closed_ = true;
  FlushChunk();
  std::string data_end;
  Int<std::uint32_t>(&data_end, crc_);  // magic, header and every record before this one
  Put(kDataEnd, data_end);
  // The summary, in groups that the summary offsets point to; its CRC runs from here through
  // the footer's summary_offset_start.
  crc_ = 0;
  const std::uint64_t summary_start = offset_;
  std::vector<std::pair<std::uint8_t, std::pair<std::uint64_t, std::uint64_t>>> groups;
  const auto group = [&](std::uint8_t op, const std::vector<std::string>& bodies) {
    const std::uint64_t start = offset_;
    for (const std::string& b : bodies) Put(op, b);
    if (offset_ > start) groups.push_back({op, {start, offset_ - start}});
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  std::string stats;
  Int<std::uint64_t>(&stats, messages_);
  Int<std::uint16_t>(&stats, static_cast<std::uint16_t>(schemas_.size()));
  Int<std::uint32_t>(&stats, static_cast<std::uint32_t>(channels_.size()));
  Int<std::uint32_t>(&stats, 0);  // attachments
  Int<std::uint32_t>(&stats, 0);  // metadata
  Int<std::uint32_t>(&stats, static_cast<std::uint32_t>(chunks_));
  Int<std::uint64_t>(&stats, start_);
  Int<std::uint64_t>(&stats, end_);
  Int<std::uint32_t>(&stats, static_cast<std::uint32_t>(counts_.size() * 10));
  for (const auto& [id, n] : counts_) Int<std::uint16_t>(&stats, id), Int<std::uint64_t>(&stats, n);
  group(kStatistics, {stats});
  group(kChunkIndex, chunk_indexes_);
  const std::uint64_t summary_offset_start = offset_;
  for (const auto& [op, span] : groups) {
    std::string body(1, static_cast<char>(op));
    Int<std::uint64_t>(&body, span.first);
    Int<std::uint64_t>(&body, span.second);
    Put(kSummaryOffset, body);
  }
  std::string footer;
  Int<std::uint64_t>(&footer, summary_start);
  Int<std::uint64_t>(&footer, summary_offset_start);
  const std::uint32_t summary_crc =
      Crc(crc_, Record(kFooter, footer + std::string(4, '\0')).substr(0, 1 + 8 + 16));
  Int<std::uint32_t>(&footer, summary_crc);
  Put(kFooter, footer);
  out_.write(kMagic, 8);
  out_.close();
  if (!out_) throw InputError(path_ + ": write failed");
}

}  // namespace inhand::ros
