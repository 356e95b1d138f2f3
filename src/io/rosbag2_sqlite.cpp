// rosbag2's SQLite3 storage: a `topics` table (id, name, type, serialization_format) and a `messages`
// table (topic_id, timestamp, data) read in recording order, one row at a time.
#include <sqlite3.h>

#include <memory>

#include "io/ros_bag_formats.hpp"

namespace eds {

namespace {

class SqliteBag : public RosBagReader {
 public:
  explicit SqliteBag(const std::filesystem::path& file) : path_(file.string()) {
    if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
      fail("cannot open as an SQLite database");
    readTopics();
    rewind();
  }

  const std::string& path() const override { return path_; }
  const char* format() const override { return "rosbag2-sqlite3"; }
  const std::vector<RosTopic>& topics() const override { return topics_; }

  bool next(RosMessage& msg) override {
    if (done_) return false;  // stepping a finished statement would start it again
    const int rc = sqlite3_step(messages_);
    if (rc == SQLITE_DONE) {
      done_ = true;
      return false;
    }
    if (rc != SQLITE_ROW) fail("reading message " + std::to_string(index_));
    const auto topic_id = sqlite3_column_int64(messages_, 0);
    const auto it = topic_index_.find(topic_id);
    if (it == topic_index_.end())
      throw InputError(path_, "message " + std::to_string(index_) + " is on topic id " +
                                  std::to_string(topic_id) + ", which the topics table does not hold");
    msg.topic = it->second;
    msg.t_record = sqlite3_column_int64(messages_, 1);
    msg.index = index_++;
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(messages_, 2));
    const auto size = static_cast<std::size_t>(sqlite3_column_bytes(messages_, 2));
    msg.data = messageView(blob, size, where_, path_, msg.index);
    return true;
  }

  void rewind() override {
    sqlite3_finalize(messages_);
    messages_ = nullptr;
    if (sqlite3_prepare_v2(db_, "SELECT topic_id, timestamp, data FROM messages ORDER BY id", -1, &messages_,
                           nullptr) != SQLITE_OK)
      fail("not a rosbag2 database (no messages table)");
    index_ = 0;
    done_ = false;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_, what + (db_ ? std::string(": ") + sqlite3_errmsg(db_) : std::string()));
  }

  void readTopics() {
    sqlite3_stmt* raw = nullptr;
    const int prepared = sqlite3_prepare_v2(
        db_,
        "SELECT t.id, t.name, t.type, t.serialization_format, "
        "(SELECT COUNT(*) FROM messages m WHERE m.topic_id = t.id) FROM topics t ORDER BY t.id",
        -1, &raw, nullptr);
    const std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> statement(raw, sqlite3_finalize);
    sqlite3_stmt* st = statement.get();
    if (prepared != SQLITE_OK) fail("not a rosbag2 database (no topics/messages tables)");
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
      RosTopic t;
      const auto text = [&](int col) {
        const auto* s = sqlite3_column_text(st, col);
        return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
      };
      t.name = text(1);
      t.type = normalizeRosType(text(2));
      const std::string serialization = text(3);
      if (serialization != "cdr")
        throw InputError(
            path_, "topic " + t.name + " uses serialization '" + serialization + "' (only cdr is read)");
      t.serialization = RosSerialization::kCdr;
      t.messages = static_cast<std::uint64_t>(sqlite3_column_int64(st, 4));
      topic_index_[sqlite3_column_int64(st, 0)] = topics_.size();
      topics_.push_back(std::move(t));
    }
    if (rc != SQLITE_DONE) fail("reading the topics table");
  }

  std::string path_, where_;
  // Closed by this member's destructor, which also runs when the constructor throws.
  struct Handles {
    sqlite3* db = nullptr;
    sqlite3_stmt* messages = nullptr;
    ~Handles() {
      sqlite3_finalize(messages);
      sqlite3_close(db);
    }
  } handles_;
  sqlite3*& db_ = handles_.db;
  sqlite3_stmt*& messages_ = handles_.messages;
  std::vector<RosTopic> topics_;
  std::unordered_map<std::int64_t, std::size_t> topic_index_;
  std::uint64_t index_ = 0;
  bool done_ = false;
};

}  // namespace

std::unique_ptr<RosBagReader> openSqliteBag(const std::filesystem::path& file) {
  return std::make_unique<SqliteBag>(file);
}

}  // namespace eds
