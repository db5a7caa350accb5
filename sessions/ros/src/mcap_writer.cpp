#include "inhand/ros/mcap_writer.hpp"

#include <algorithm>

#include "inhand/core/error.hpp"

namespace inhand::ros {

namespace {

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

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

}  // namespace

McapWriter::McapWriter(const std::string& path, const std::string& library)
    : path_(path), out_(path, std::ios::binary) {
  if (!out_) throw InputError(path + ": cannot write");
  out_.write(kMagic, 8);
  offset_ = 8;
  std::string header;
  Str(&header, "");  // profile: none (JSON messages with JSON schemas)
  Str(&header, library);
  Put(0x01, header);
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
  std::string head(1, static_cast<char>(op));
  Int<std::uint64_t>(&head, body.size());
  out_.write(head.data(), static_cast<std::streamsize>(head.size()));
  out_.write(body.data(), static_cast<std::streamsize>(body.size()));
  offset_ += head.size() + body.size();
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
  Put(0x03, body);
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
  Put(0x04, body);
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
  Put(0x05, body);
  ++counts_[channel];
  start_ = messages_ == 0 ? log_time_ns : std::min(start_, log_time_ns);
  end_ = messages_ == 0 ? log_time_ns : std::max(end_, log_time_ns);
  ++messages_;
}

void McapWriter::Close() {
  if (closed_) return;
  closed_ = true;
  std::string data_end;
  Int<std::uint32_t>(&data_end, 0);  // data section CRC: not computed
  Put(0x0F, data_end);
  const std::uint64_t summary_start = offset_;
  for (const std::string& s : schemas_) Put(0x03, s);
  for (const std::string& c : channels_) Put(0x04, c);
  std::string stats;
  Int<std::uint64_t>(&stats, messages_);
  Int<std::uint16_t>(&stats, static_cast<std::uint16_t>(schemas_.size()));
  Int<std::uint32_t>(&stats, static_cast<std::uint32_t>(channels_.size()));
  Int<std::uint32_t>(&stats, 0);  // attachments
  Int<std::uint32_t>(&stats, 0);  // metadata
  Int<std::uint32_t>(&stats, 0);  // chunks
  Int<std::uint64_t>(&stats, start_);
  Int<std::uint64_t>(&stats, end_);
  Int<std::uint32_t>(&stats, static_cast<std::uint32_t>(counts_.size() * 10));
  for (const auto& [id, n] : counts_) Int<std::uint16_t>(&stats, id), Int<std::uint64_t>(&stats, n);
  Put(0x0B, stats);
  std::string footer;
  Int<std::uint64_t>(&footer, summary_start);
  Int<std::uint64_t>(&footer, 0);  // no summary offset section
  Int<std::uint32_t>(&footer, 0);  // summary CRC: not computed
  Put(0x02, footer);
  out_.write(kMagic, 8);
  out_.close();
  if (!out_) throw InputError(path_ + ": write failed");
}

}  // namespace inhand::ros
