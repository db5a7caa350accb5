#pragma once
// A minimal MCAP writer (mcap.dev/spec) for exports that Foxglove and Lichtblick open: schemas,
// channels and messages in an unchunked data section, then a summary (schemas, channels,
// statistics) and the footer. Messages are written as they come; Close() finishes the file.
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace inhand::ros {

class McapWriter {
 public:
  // Throws InputError when `path` cannot be written.
  explicit McapWriter(const std::string& path, const std::string& library = "inhand");
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // encoding: "jsonschema" (with message encoding "json"), ...
  std::uint16_t AddSchema(const std::string& name, const std::string& encoding,
                          const std::string& data);
  std::uint16_t AddChannel(const std::string& topic, std::uint16_t schema,
                           const std::string& message_encoding);
  void Write(std::uint16_t channel, std::uint64_t log_time_ns, const std::string& data);
  void Close();

 private:
  struct Record;
  void Put(std::uint8_t op, const std::string& body);
  std::string path_;
  std::ofstream out_;
  std::uint64_t offset_ = 0;
  std::vector<std::string> schemas_, channels_;  // their records' bodies, for the summary
  std::map<std::uint16_t, std::uint64_t> counts_;
  std::vector<std::uint32_t> sequence_;
  std::uint64_t messages_ = 0, start_ = 0, end_ = 0;
  bool closed_ = false;
};

}  // namespace inhand::ros
