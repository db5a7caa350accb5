// ROS 2 recordings in rosbag2's sqlite3 storage (.db3): tables `topics` (id, name, type,
// serialization_format, ...) and `messages` (id, topic_id, timestamp, data), CDR messages.
#include <sqlite3.h>

#include <cstring>
#include <map>
#include <memory>

#include "cdr.hpp"
#include "inhand/core/error.hpp"
#include "recordings.hpp"

namespace inhand::ros {

namespace {

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql, const std::string& path) : path_(path) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK)
      throw InputError(path + ": not a rosbag2 sqlite3 database (" + sqlite3_errmsg(db) + ")");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  bool Step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw InputError(path_ + ": cannot read (" + sqlite3_errstr(rc) +
                     "; truncated or corrupt database?)");
  }
  sqlite3_stmt* get() const { return stmt_; }
  std::string Text(int col) const {
    const unsigned char* t = sqlite3_column_text(stmt_, col);
    return t == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(t));
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
  const std::string& path_;
};

class Db3Recording final : public Recording {
 public:
  explicit Db3Recording(const std::string& path) {
    path_ = path;
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
    db_.reset(db);  // closed also when this constructor throws below (the fuzzer found the leak)
    if (rc != SQLITE_OK)
      throw InputError(path + ": cannot open as sqlite3 (" +
                       (db != nullptr ? sqlite3_errmsg(db) : "out of memory") + ")");
    Statement s(db_.get(), "SELECT id, name, type, serialization_format FROM topics", path_);
    while (s.Step()) {
      Topic t;
      t.name = s.Text(1);
      t.type = NormaliseTypeName(s.Text(2));
      t.format = s.Text(3);
      t.msg_type = MsgTypeOf(t.type);
      topics_[sqlite3_column_int64(s.get(), 0)] = t;
    }
  }
  ~Db3Recording() override = default;
  std::string format() const override { return "sqlite3 .db3"; }

  std::vector<TopicInfo> Topics() override {
    std::map<std::string, TopicInfo> by_name;
    for (const auto& [id, t] : topics_) by_name[t.name] = TopicInfo{t.name, t.type, 0, 0, 0};
    Statement s(
        db_.get(),
        "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id",
        path_);
    while (s.Step()) {
      auto it = topics_.find(sqlite3_column_int64(s.get(), 0));
      if (it == topics_.end()) continue;
      TopicInfo& info = by_name[it->second.name];
      info.count += static_cast<std::uint64_t>(sqlite3_column_int64(s.get(), 1));
      info.first_ns = sqlite3_column_int64(s.get(), 2);
      info.last_ns = sqlite3_column_int64(s.get(), 3);
    }
    std::vector<TopicInfo> out;
    for (auto& [name, t] : by_name) out.push_back(t);
    return out;
  }

  void Read(const std::vector<std::string>& topics, bool decode_images,
            const std::function<void(Message&)>& on_message,
            const std::function<void(double)>& progress) override {
    std::string ids;
    for (const auto& [id, t] : topics_)
      for (const std::string& want : topics)
        if (t.name == want) {
          if (t.msg_type != MsgType::kOther && t.format != "cdr")
            throw InputError(path_ + ": topic " + t.name + " is serialised as '" + t.format +
                             "', expected cdr");
          ids += (ids.empty() ? "" : ",") + std::to_string(id);
        }
    if (ids.empty()) return;
    std::int64_t total = 0;
    {
      Statement c(db_.get(), "SELECT COUNT(*) FROM messages WHERE topic_id IN (" + ids + ")",
                  path_);
      if (c.Step()) total = sqlite3_column_int64(c.get(), 0);
    }
    Statement s(db_.get(),
                "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" + ids +
                    ") ORDER BY timestamp, id",
                path_);
    std::map<std::int64_t, std::uint64_t> index;
    std::int64_t done = 0;
    while (s.Step()) {
      const Topic& t = topics_.at(sqlite3_column_int64(s.get(), 0));
      Message m;
      m.topic = &t.name;
      m.type = &t.type;
      m.log_ns = sqlite3_column_int64(s.get(), 1);
      const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(s.get(), 2));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(s.get(), 2));
      m.payload = DecodeCdr(t.msg_type, blob, size, decode_images,
                            path_ + ": topic " + t.name + ", message " +
                                std::to_string(index[sqlite3_column_int64(s.get(), 0)]++));
      on_message(m);
      if (progress && (++done & 1023) == 0)
        progress(static_cast<double>(done) / static_cast<double>(total));
    }
    if (progress) progress(1.0);
  }

 private:
  struct Topic {
    std::string name, type, format;
    MsgType msg_type = MsgType::kOther;
  };
  struct Close {
    void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
  };
  std::unique_ptr<sqlite3, Close> db_;
  std::map<std::int64_t, Topic> topics_;
};

}  // namespace

std::unique_ptr<Recording> OpenDb3(const std::string& path) {
  return std::make_unique<Db3Recording>(path);
}

}  // namespace inhand::ros
