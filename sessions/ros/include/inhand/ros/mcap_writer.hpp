#pragma once
// An MCAP writer (mcap.dev/spec) for exports that Foxglove and Lichtblick open and seek in
// without reading the whole file: schemas and channels in the data section as they are added;
// messages in zstd-compressed chunks (about `chunk_size` bytes of records each), every chunk
// followed by its message indexes; then a summary (schemas, channels, statistics, one chunk index
// per chunk), the summary offsets and the footer, with the data section's, each chunk's and the
// summary's CRC-32. Messages are written as they come; Close() finishes the file.
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace inhand::ros {

struct McapWriterOptions {
  std::string profile;               // "" (JSON messages), "ros2" (CDR messages), ...
  std::string compression = "zstd";  // "zstd" or "" (chunks stored as they are)
  std::size_t chunk_size = 1 << 20;  // [bytes] of records before a chunk is closed
  int zstd_level = 3;
};

class McapWriter {
 public:
  // Throws InputError when `path` cannot be written.
  explicit McapWriter(const std::string& path, const std::string& library = "inhand",
                      McapWriterOptions options = {});
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // encoding: "jsonschema" (with message encoding "json"), "ros2msg" (with "cdr"), ...
  std::uint16_t AddSchema(const std::string& name, const std::string& encoding,
                          const std::string& data);
  std::uint16_t AddChannel(const std::string& topic, std::uint16_t schema,
                           const std::string& message_encoding);
  void Write(std::uint16_t channel, std::uint64_t log_time_ns, const std::string& data);
  void Close();

  std::uint64_t chunks() const { return chunks_; }

 private:
  void Put(std::uint8_t op, const std::string& body);  // a record into the file
  void FlushChunk();
  std::string path_;
  McapWriterOptions options_;
  std::ofstream out_;
  std::uint64_t offset_ = 0;
  std::uint32_t crc_ = 0;  // of everything written so far (the data section's, then summary's)
  std::vector<std::string> schemas_, channels_;  // their records' bodies, for the summary
  std::map<std::uint16_t, std::uint64_t> counts_;
  std::vector<std::uint32_t> sequence_;
  std::uint64_t messages_ = 0, start_ = 0, end_ = 0;
  // The open chunk: its records, message time span, and per channel (log time, offset) pairs.
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0, chunks_ = 0;
  std::map<std::uint16_t, std::string> chunk_entries_;
  std::vector<std::string> chunk_indexes_;  // Chunk Index records' bodies, for the summary
  bool closed_ = false;
};

}  // namespace inhand::ros
