// rosbag2 writer: sqlite3 storage (schema version 4) + metadata.yaml.
//
// Durability: the database runs in WAL mode (synchronous=NORMAL, what rosbag2's
// "resilient" preset uses). Messages are inserted inside a transaction that is
// committed by write() once flush_interval of wall time has passed since the last
// commit, and by a background thread while the caller is idle. A committed
// transaction survives a SIGKILL of the process (it is in the -wal file, which the
// next reader recovers), so a killed recording loses at most the last interval.
// metadata.yaml is written at open, rewritten with the topics created since at the next
// commit (so it is as durable as the messages on those topics) and at close.
#include <sqlite3.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "internal.hpp"
#include "mcap.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/distro.hpp"

namespace fs = std::filesystem;

namespace tactile_bag {
namespace {

std::string emit_yaml(const YAML::Node& node) {
  YAML::Emitter e;
  e << node;
  return e.c_str();
}

/// Appends `block` (block-style YAML, no final newline) with every non-empty line indented
/// by `indent` spaces, and a final newline. Block-style YAML nests by indentation alone, so
/// a block emitted on its own and indented equals the emitter's output for it nested there.
void append_indented(std::string& out, std::string_view block, size_t indent) {
  size_t pos = 0;
  while (pos <= block.size()) {
    const size_t eol = block.find('\n', pos);
    const size_t end = eol == std::string_view::npos ? block.size() : eol;
    if (end > pos) out.append(indent, ' ');
    out.append(block.substr(pos, end - pos));
    out.push_back('\n');
    if (eol == std::string_view::npos) break;
    pos = eol + 1;
  }
}


const char* kSchemaSql =
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
    " metadata TEXT NOT NULL);"
    "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
    " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,"
    " type_description_hash TEXT NOT NULL);"
    "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL,"
    " encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL,"
    " type_description_hash TEXT NOT NULL);"
    "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
    " timestamp INTEGER NOT NULL, data BLOB NOT NULL);";
// rosbag2's index on the message timestamps, built by close() in one sorted
// pass instead of updated on every insert: a recording spent about a third of
// its sqlite time keeping it (issue 18). A killed recording has no index; its
// messages are read in timestamp order all the same (ORDER BY), only slower.
const char* kIndexSql = "CREATE INDEX IF NOT EXISTS timestamp_idx ON messages (timestamp ASC);";

constexpr int kSchemaVersion = 4;

std::string distro_for(int version) {
  if (version >= 9) return "jazzy";
  if (version == 8) return "iron";
  return "humble";
}

struct Stmt {
  sqlite3_stmt* s = nullptr;
  ~Stmt() { sqlite3_finalize(s); }
};

}  // namespace

Writer::Writer() : Writer(WriterOptions{}) {}

Writer::Writer(WriterOptions options) : opt_(std::move(options)) {
  if (!opt_.ros_distro.empty()) {
    check_distro(opt_.ros_distro, "WriterOptions.ros_distro");
    if (opt_.metadata_version == 0) opt_.metadata_version = metadata_version_for_distro(opt_.ros_distro);
  }
  if (opt_.metadata_version == 0) opt_.metadata_version = 9;
  if (opt_.storage != "sqlite3" && opt_.storage != "mcap") {
    throw BagError("WriterOptions.storage: must be sqlite3 or mcap, got '" + opt_.storage + "'");
  }
  if (!opt_.compression.empty() && (opt_.storage != "mcap" || (opt_.compression != "zstd" && opt_.compression != "lz4"))) {
    throw BagError("WriterOptions.compression: '" + opt_.compression +
                   "' is not supported (mcap chunk compression: zstd or lz4; sqlite3 bags are written uncompressed)");
  }
  if (opt_.metadata_version != 5 && opt_.metadata_version != 8 && opt_.metadata_version != 9) {
    throw BagError("WriterOptions.metadata_version: must be 5, 8 or 9, got " +
                   std::to_string(opt_.metadata_version));
  }
  if (opt_.flush_interval.count() < 0 || opt_.flush_interval > std::chrono::seconds(1)) {
    throw BagError("WriterOptions.flush_interval: must be in [0, 1000] ms (0: by size only), got " +
                   std::to_string(opt_.flush_interval.count()) + " ms");
  }
  if (opt_.ros_distro.empty()) opt_.ros_distro = distro_for(opt_.metadata_version);
  hash_types_ = distro_has_type_hashes(opt_.ros_distro) && opt_.metadata_version >= 7;
}

Writer::~Writer() {
  try {
    close();
  } catch (const std::exception& e) {
    std::cerr << "tactile_bag::Writer: close failed in destructor: " << e.what() << "\n";
  }
}

void Writer::fail(const std::string& what) const {
  std::string msg = db_path_ + ": " + what;
  if (db_ != nullptr) msg += ": " + std::string(sqlite3_errmsg(db_));
  throw BagError(msg);
}

void Writer::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    std::string e = err != nullptr ? err : "unknown error";
    sqlite3_free(err);
    throw BagError(db_path_ + ": " + std::string(sql).substr(0, 40) + "...: " + e);
  }
}

void Writer::open(const std::string& dir) {
  if (is_open()) throw BagError(dir + ": writer is already open on " + dir_);
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  std::error_code ec;
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) throw BagError(p.string() + ": exists and is not a directory");
    if (!fs::is_empty(p, ec)) {
      throw BagError(p.string() + ": bag directory exists and is not empty (not overwriting)");
    }
  } else if (!fs::create_directories(p, ec) || ec) {
    throw BagError(p.string() + ": cannot create bag directory: " + ec.message());
  }
  dir_ = p.string();
  db_name_ = p.filename().string() + (opt_.storage == "mcap" ? "_0.mcap" : "_0.db3");
  db_path_ = (p / db_name_).string();
  if (opt_.storage == "mcap") {
    auto w = std::make_unique<mcap::FileWriter>();
    mcap::WriterConfig cfg;
    cfg.compression = opt_.compression;
    cfg.chunk_size = opt_.chunk_size;
    w->open(db_path_, cfg, "tactile_bag");
    std::lock_guard<std::mutex> lk(mu_);
    mcap_ = std::move(w);
    topics_.clear();
    topic_order_.clear();
    by_id_.clear();
    count_ = 0;
    min_ts_ = max_ts_ = 0;
    last_commit_ = std::chrono::steady_clock::now();
    bytes_since_commit_ = 0;
    write_metadata_locked();
    stop_ = false;
    if (opt_.flush_interval.count() > 0) flusher_ = std::thread([this] { flusher_main(); });
    return;
  }

  // Every call into the connection holds mu_, so sqlite's own per-call mutex is
  // redundant (NOMUTEX: sqlite's multi-thread mode).
  if (sqlite3_open_v2(db_path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                      nullptr) != SQLITE_OK) {
    std::string e = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw BagError(db_path_ + ": cannot create database: " + e);
  }
  try {
    exec("PRAGMA journal_mode=WAL;");
    exec("PRAGMA synchronous=NORMAL;");
    exec(kSchemaSql);
    {
      Stmt st;
      if (sqlite3_prepare_v2(db_, "INSERT INTO schema(schema_version, ros_distro) VALUES(?, ?)",
                             -1, &st.s, nullptr) != SQLITE_OK) {
        fail("prepare schema insert");
      }
      sqlite3_bind_int(st.s, 1, kSchemaVersion);
      sqlite3_bind_text(st.s, 2, opt_.ros_distro.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(st.s) != SQLITE_DONE) fail("insert schema version");
    }
    if (sqlite3_prepare_v2(db_, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)",
                           -1, &insert_, nullptr) != SQLITE_OK) {
      fail("prepare message insert");
    }
  } catch (...) {
    sqlite3_finalize(insert_);
    insert_ = nullptr;
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
  std::lock_guard<std::mutex> lk(mu_);
  topics_.clear();
  topic_order_.clear();
  by_id_.clear();
  defined_types_.clear();
  count_ = 0;
  min_ts_ = max_ts_ = 0;
  in_txn_ = false;
  last_commit_ = std::chrono::steady_clock::now();
  bytes_since_commit_ = 0;
  write_metadata_locked();
  stop_ = false;
  if (opt_.flush_interval.count() > 0) flusher_ = std::thread([this] { flusher_main(); });
}

bool Writer::has_topic(const std::string& name) const {
  std::lock_guard<std::mutex> lk(mu_);
  return topics_.count(name) != 0;
}

std::string Writer::topic_type(const std::string& name) const {
  std::lock_guard<std::mutex> lk(mu_);
  auto it = topics_.find(name);
  return it == topics_.end() ? std::string() : it->second.info.type;
}

uint64_t Writer::message_count() const {
  std::lock_guard<std::mutex> lk(mu_);
  return count_;
}

// Everything a topic's entry derives from its TopicInfo and this writer's options: the QoS
// text normalised to the metadata version, the Range layout of the distro, the RIHS01 hash,
// the metadata.yaml block. A process that records many bags of one graph (`tactile sim
// --trials`, the sweeps) used to derive it per topic per bag with yaml-cpp's parser and
// emitter and a SHA-256 (3.3 % of a recorded whisker flight's CPU, issue 18): it is now
// derived once per distinct input and kept in a process-wide table (bounded; a fault is
// never kept, so a bad topic fails every time with its own message).
Writer::TopicState Writer::derived_topic_state(const TopicInfo& topic) const {
  std::string key;
  key.reserve(topic.name.size() + topic.type.size() + topic.offered_qos_profiles.size() +
              topic.type_definition.size() + topic.type_description_hash.size() + 64);
  for (const std::string* f : {&opt_.ros_distro, &topic.name, &topic.type, &topic.serialization_format,
                               &topic.offered_qos_profiles, &topic.type_definition,
                               &topic.definition_encoding, &topic.type_description_hash}) {
    key += std::to_string(f->size());
    key += ':';
    key += *f;
  }
  key += std::to_string(opt_.metadata_version);
  key += hash_types_ ? 'h' : '-';
  static std::mutex cache_mu;
  static std::unordered_map<std::string, TopicState> cache;
  {
    std::lock_guard<std::mutex> lk(cache_mu);
    const auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  TopicState st;
  st.info = topic;
  // Normalise the QoS text to the encoding of the metadata version we write.
  std::vector<QosProfile> profiles(1);
  if (!topic.offered_qos_profiles.empty()) {
    const std::string ctx = "topic '" + topic.name + "' offered_qos_profiles";
    profiles = parse_qos_profiles(topic.offered_qos_profiles, ctx);
  }
  st.info.offered_qos_profiles = dump_qos_profiles(profiles, opt_.metadata_version);
  st.qos = profiles;
  prepare_topic_locked(st);
  {
    // The topic's entry of metadata.yaml, emitted once here rather than at every metadata
    // write (the emitter was 3.8 % of a recorded whisker flight's CPU, issue 18).
    const int v = opt_.metadata_version;
    YAML::Node tm;
    tm["name"] = st.info.name;
    tm["type"] = st.info.type;
    tm["serialization_format"] = st.info.serialization_format;
    if (v >= 9) {
      tm["offered_qos_profiles"] = qos_node(st.qos, v);
    } else {
      tm["offered_qos_profiles"] = st.info.offered_qos_profiles;
    }
    if (v >= 7) tm["type_description_hash"] = st.info.type_description_hash;
    st.metadata_yaml = emit_yaml(tm);
  }
  std::lock_guard<std::mutex> lk(cache_mu);
  if (cache.size() >= 4096) cache.clear();  // a long-lived process recording ever new topics
  cache.emplace(std::move(key), st);
  return st;
}

Writer::TopicId Writer::create_topic(const TopicInfo& topic) {
  std::lock_guard<std::mutex> lk(mu_);
  if (!is_open()) throw BagError(topic.name + ": create_topic on a writer that is not open");
  if (topic.name.empty() || topic.type.empty()) {
    throw BagError(db_path_ + ": create_topic: topic name and type must not be empty");
  }
  auto it = topics_.find(topic.name);
  if (it != topics_.end()) {
    if (it->second.info.type != topic.type) {
      throw BagError(db_path_ + ": topic '" + topic.name + "' already exists with type '" +
                     it->second.info.type + "', not '" + topic.type + "'");
    }
    for (TopicId i = 0; i < by_id_.size(); ++i) {
      if (by_id_[i] == &it->second) return i;
    }
    throw BagError(db_path_ + ": topic '" + topic.name + "' has no number (internal error)");
  }
  TopicState st = derived_topic_state(topic);
  if (mcap_ != nullptr) {
    const uint16_t schema = st.info.type_definition.empty()
                                ? 0
                                : mcap_->add_schema(st.info.type, st.info.definition_encoding,
                                                    st.info.type_definition);
    mcap::StringMap meta;
    meta["offered_qos_profiles"] = st.info.offered_qos_profiles;
    if (opt_.metadata_version >= 7) meta["topic_type_hash"] = st.info.type_description_hash;
    st.id = mcap_->add_channel(schema, st.info.name, st.info.serialization_format, meta);
    by_id_.push_back(&topics_.emplace(topic.name, st).first->second);
    topic_order_.push_back(topic.name);
    metadata_dirty_ = true;  // written by the next commit
    chunks_at_dirty_ = mcap_->chunk_count();
    return by_id_.size() - 1;
  }
  const TopicInfo& topic_in = topic;
  (void)topic_in;

  begin_locked();
  {
    Stmt s;
    if (sqlite3_prepare_v2(db_,
                           "INSERT INTO topics(name, type, serialization_format,"
                           " offered_qos_profiles, type_description_hash) VALUES(?, ?, ?, ?, ?)",
                           -1, &s.s, nullptr) != SQLITE_OK) {
      fail("prepare topic insert");
    }
    sqlite3_bind_text(s.s, 1, st.info.name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 2, st.info.type.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 3, st.info.serialization_format.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 4, st.info.offered_qos_profiles.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 5, st.info.type_description_hash.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(s.s) != SQLITE_DONE) fail("insert topic '" + topic.name + "'");
    st.id = sqlite3_last_insert_rowid(db_);
  }
  if (!st.info.type_definition.empty() && defined_types_.count(topic.type) == 0) {
    Stmt s;
    if (sqlite3_prepare_v2(db_,
                           "INSERT INTO message_definitions(topic_type, encoding,"
                           " encoded_message_definition, type_description_hash)"
                           " VALUES(?, ?, ?, ?)",
                           -1, &s.s, nullptr) != SQLITE_OK) {
      fail("prepare message definition insert");
    }
    sqlite3_bind_text(s.s, 1, topic.type.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 2, st.info.definition_encoding.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 3, st.info.type_definition.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.s, 4, st.info.type_description_hash.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(s.s) != SQLITE_DONE) fail("insert definition of '" + topic.type + "'");
    defined_types_[topic.type] = true;
  }
  by_id_.push_back(&topics_.emplace(topic.name, st).first->second);
  topic_order_.push_back(topic.name);
  metadata_dirty_ = true;
  commit_locked();
  return by_id_.size() - 1;
}

void Writer::begin_locked() {
  if (in_txn_) return;
  exec("BEGIN;");
  in_txn_ = true;
}

void Writer::commit_locked() {
  if (mcap_ != nullptr) mcap_->flush();
  bytes_since_commit_ = 0;
  if (in_txn_) {
    exec("COMMIT;");
    in_txn_ = false;
  }
  if (metadata_dirty_) write_metadata_locked();
  last_commit_ = std::chrono::steady_clock::now();
}

void Writer::write(const std::string& topic, int64_t timestamp_ns, const uint8_t* data,
                   size_t size) {
  std::lock_guard<std::mutex> lk(mu_);
  if (!is_open()) throw BagError(topic + ": write on a writer that is not open");
  auto it = topics_.find(topic);
  if (it == topics_.end()) {
    throw BagError(db_path_ + ": write: topic '" + topic + "' has not been created");
  }
  write_locked(it->second, timestamp_ns, data, size);
}

Writer::TopicId Writer::topic_id(const std::string& name) const {
  std::lock_guard<std::mutex> lk(mu_);
  for (TopicId i = 0; i < by_id_.size(); ++i) {
    if (by_id_[i]->info.name == name) return i;
  }
  throw BagError(db_path_ + ": topic '" + name + "' has not been created");
}

void Writer::write(TopicId topic, int64_t timestamp_ns, const uint8_t* data, size_t size) {
  std::lock_guard<std::mutex> lk(mu_);
  if (!is_open()) throw BagError(db_path_ + ": write on a writer that is not open");
  if (topic >= by_id_.size()) {
    throw BagError(db_path_ + ": write: topic number " + std::to_string(topic) + " has not been created (" +
                   std::to_string(by_id_.size()) + " topics)");
  }
  write_locked(*by_id_[topic], timestamp_ns, data, size);
}

bool Writer::flush_due_locked() {
  if (opt_.flush_interval.count() == 0) {
    // By size only (a reproducible file). mcap: the FileWriter writes chunks by chunk_size;
    // a topic created since metadata.yaml was written is added to it once a chunk has
    // gone to the file after its creation.
    if (mcap_ != nullptr) {
      if (metadata_dirty_ && mcap_->chunk_count() > chunks_at_dirty_) write_metadata_locked();
      return false;
    }
    return bytes_since_commit_ >= opt_.chunk_size;
  }
  // The clock is read every 16th write (a vdso call per message was ~1 % of a recorded
  // run); the background flusher commits an idle writer on time regardless.
  if ((++writes_since_clock_ & 15U) != 0) return false;
  return std::chrono::steady_clock::now() - last_commit_ >= opt_.flush_interval;
}

void Writer::write_locked(TopicState& st, int64_t timestamp_ns, const uint8_t* data, size_t size) {
  const std::string& topic = st.info.name;
  if (size > 0 && data == nullptr) throw BagError(db_path_ + ": write: null data");
  if (st.drop_range_variance) {
    // Humble/Iron layout: the payload ends after `range` (tactile_bag/distro.hpp).
    const size_t cut = range_payload_size_without_variance(data, size);
    if (cut == 0 || cut + 4 != size) {
      throw BagError(db_path_ + ": write: message on '" + topic + "' (" + std::to_string(size) +
                     " bytes) is not a sensor_msgs/msg/Range in the Jazzy/Kilted layout, cannot "
                     "convert it to " + opt_.ros_distro + "'s layout");
    }
    size = cut;
  }
  if (mcap_ != nullptr) {
    write_mcap_locked(st, timestamp_ns, data, size);
    return;
  }
  if (size > static_cast<size_t>(sqlite3_limit(db_, SQLITE_LIMIT_LENGTH, -1))) {
    throw BagError(db_path_ + ": write: message of " + std::to_string(size) +
                   " bytes on '" + topic + "' exceeds the sqlite blob limit");
  }
  begin_locked();
  sqlite3_bind_int64(insert_, 1, st.id);
  sqlite3_bind_int64(insert_, 2, timestamp_ns);
  static const uint8_t kEmpty = 0;
  sqlite3_bind_blob64(insert_, 3, size > 0 ? data : &kEmpty, size, SQLITE_STATIC);
  const int rc = sqlite3_step(insert_);
  sqlite3_reset(insert_);  // every parameter is bound again by the next write
  if (rc != SQLITE_DONE) fail("insert message on '" + topic + "'");
  if (count_ == 0 || timestamp_ns < min_ts_) min_ts_ = timestamp_ns;
  if (count_ == 0 || timestamp_ns > max_ts_) max_ts_ = timestamp_ns;
  ++count_;
  ++st.count;
  bytes_since_commit_ += size;
  if (flush_due_locked()) commit_locked();
}

void Writer::write_mcap_locked(TopicState& st, int64_t timestamp_ns, const uint8_t* data, size_t size) {
  if (timestamp_ns < 0) {
    throw BagError(db_path_ + ": write: negative timestamp " + std::to_string(timestamp_ns) +
                   " ns on '" + st.info.name + "' (mcap log times are unsigned)");
  }
  mcap_->write(static_cast<uint16_t>(st.id), static_cast<uint64_t>(timestamp_ns), data, size);
  if (count_ == 0 || timestamp_ns < min_ts_) min_ts_ = timestamp_ns;
  if (count_ == 0 || timestamp_ns > max_ts_) max_ts_ = timestamp_ns;
  ++count_;
  ++st.count;
  bytes_since_commit_ += size;
  if (flush_due_locked()) commit_locked();
}

void Writer::prepare_topic_locked(TopicState& st) const {
  TopicInfo& t = st.info;
  if (t.type == "sensor_msgs/msg/Range" && distro_range_without_variance(opt_.ros_distro)) {
    bool has_section = false;
    const bool has_variance = t.type_definition.empty() ||
                              definition_has_field(t.type_definition, t.type, t.type, "variance", &has_section);
    if (has_variance) {
      st.drop_range_variance = true;
      if (!t.type_definition.empty()) {
        t.type_definition = remove_field_from_definition(t.type_definition, t.type, t.type, "variance");
      }
    }
  } else if (distro_range_without_variance(opt_.ros_distro) && !t.type_definition.empty()) {
    bool nests = false;
    definition_has_field(t.type_definition, t.type, "sensor_msgs/msg/Range", "variance", &nests);
    if (nests) {
      throw BagError(db_path_ + ": topic '" + t.name + "' (" + t.type + ") nests sensor_msgs/msg/Range, "
                     "which cannot be converted to " + opt_.ros_distro + "'s Range layout");
    }
  }
  if (hash_types_ && t.type_description_hash.empty() && !t.type_definition.empty() &&
      t.definition_encoding == "ros2msg") {
    t.type_description_hash = rihs01_hash(t.type, t.type_definition);
  }
}

void Writer::flush() {
  std::lock_guard<std::mutex> lk(mu_);
  if (is_open()) commit_locked();
}

void Writer::flusher_main() {
  std::unique_lock<std::mutex> lk(mu_);
  const auto period = opt_.flush_interval / 4 > std::chrono::milliseconds(1)
                          ? opt_.flush_interval / 4
                          : std::chrono::milliseconds(1);
  while (!stop_) {
    cv_.wait_for(lk, period);
    if (stop_ || !is_open()) break;
    if ((in_txn_ || mcap_ != nullptr) && std::chrono::steady_clock::now() - last_commit_ >= opt_.flush_interval) {
      try {
        commit_locked();
      } catch (const std::exception& e) {
        std::cerr << "tactile_bag::Writer: background commit failed: " << e.what() << "\n";
      }
    }
  }
}

std::string Writer::metadata_yaml_locked(bool with_root) const {
  // rosbag2's metadata.yaml, as yaml-cpp emits the whole node tree (block style), composed
  // from three parts: the head and the tail emitted here and each topic's block emitted when
  // the topic was created (TopicState::metadata_yaml), nested by indentation.
  const int v = opt_.metadata_version;
  const int64_t start = count_ > 0 ? min_ts_ : 0;
  const int64_t duration = count_ > 0 ? max_ts_ - min_ts_ : 0;
  YAML::Node head;
  head["version"] = v;
  head["storage_identifier"] = opt_.storage;
  head["duration"]["nanoseconds"] = duration;
  head["starting_time"]["nanoseconds_since_epoch"] = start;
  head["message_count"] = count_;
  std::string text = emit_yaml(head);
  text += "\ntopics_with_message_count:\n";
  if (topic_order_.empty()) text += "  []\n";
  for (const auto& name : topic_order_) {
    const TopicState& st = topics_.at(name);
    text += "  - topic_metadata:\n";
    append_indented(text, st.metadata_yaml, 6);
    text += "    message_count: ";
    text += std::to_string(st.count);
    text += '\n';
  }
  YAML::Node tail;
  tail["compression_format"] = "";
  tail["compression_mode"] = "";
  YAML::Node paths(YAML::NodeType::Sequence);
  paths.push_back(db_name_);
  tail["relative_file_paths"] = paths;
  if (v >= 5) {
    YAML::Node f;
    f["path"] = db_name_;
    f["starting_time"]["nanoseconds_since_epoch"] = start;
    f["duration"]["nanoseconds"] = duration;
    f["message_count"] = count_;
    YAML::Node files(YAML::NodeType::Sequence);
    files.push_back(f);
    tail["files"] = files;
  }
  if (v >= 6) tail["custom_data"] = YAML::Node(YAML::NodeType::Map);
  if (v >= 8) tail["ros_distro"] = opt_.ros_distro;
  text += emit_yaml(tail);
  text += '\n';
  if (!with_root) return text;
  std::string rooted = "rosbag2_bagfile_information:\n";
  rooted.reserve(text.size() + text.size() / 8 + 40);
  append_indented(rooted, std::string_view(text).substr(0, text.size() - 1), 2);
  return rooted;
}

void Writer::write_metadata_locked(const std::string* inner) {
  metadata_dirty_ = false;
  // With the storage's copy (`inner`, emitted without the root key) at hand, the file's
  // text is that block under the root key: block-style YAML nests by indentation alone,
  // so the bytes equal an emit with the root (the emitter is the slowest step of close()).
  std::string text;
  if (inner != nullptr && !inner->empty() && inner->back() == '\n') {
    text = "rosbag2_bagfile_information:\n";
    text.reserve(inner->size() + inner->size() / 8 + 40);
    append_indented(text, std::string_view(*inner).substr(0, inner->size() - 1), 2);
  } else {
    text = metadata_yaml_locked(true);
  }
  const fs::path final_path = fs::path(dir_) / "metadata.yaml";
  const fs::path tmp = fs::path(dir_) / ".metadata.yaml.tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw BagError(tmp.string() + ": cannot write metadata");
  }
  std::error_code ec;
  fs::rename(tmp, final_path, ec);
  if (ec) throw BagError(final_path.string() + ": cannot write metadata: " + ec.message());
}

void Writer::close() {
  if (flusher_.joinable()) {
    {
      std::lock_guard<std::mutex> lk(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    flusher_.join();
  }
  std::lock_guard<std::mutex> lk(mu_);
  if (mcap_ != nullptr) {
    std::string error, inner;
    try {
      mcap_->flush();
      // What rosbag2's mcap plugin stores: the final metadata and the distro.
      inner = metadata_yaml_locked(false);
      mcap_->set_metadata("rosbag2", {{"serialized_metadata", inner}, {"ros_distro", opt_.ros_distro}});
      mcap_->close();
    } catch (const std::exception& e) {
      error = e.what();
    }
    mcap_.reset();
    write_metadata_locked(inner.empty() ? nullptr : &inner);
    if (!error.empty()) throw BagError(error);
    return;
  }
  if (db_ == nullptr) return;
  std::string error, meta;
  try {
    exec(kIndexSql);
    commit_locked();
    // The final metadata is also stored in the database, as rosbag2 does; its
    // version tells ROS 2 how to parse the QoS strings of the topics table.
    Stmt s;
    if (sqlite3_prepare_v2(db_, "INSERT INTO metadata(metadata_version, metadata) VALUES(?, ?)",
                           -1, &s.s, nullptr) != SQLITE_OK) {
      fail("prepare metadata insert");
    }
    meta = metadata_yaml_locked(false);
    sqlite3_bind_int(s.s, 1, opt_.metadata_version);
    sqlite3_bind_text(s.s, 2, meta.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(s.s) != SQLITE_DONE) fail("insert metadata");
    // Checkpoint the WAL into the main file and leave a plain rollback-journal
    // database, so read-only and immutable openers (rosbags) see every message.
    exec("PRAGMA journal_mode=DELETE;");
  } catch (const std::exception& e) {
    error = e.what();
  }
  sqlite3_finalize(insert_);
  insert_ = nullptr;
  if (sqlite3_close(db_) != SQLITE_OK && error.empty()) {
    error = db_path_ + ": close: " + sqlite3_errmsg(db_);
  }
  db_ = nullptr;
  in_txn_ = false;
  write_metadata_locked(meta.empty() ? nullptr : &meta);
  if (!error.empty()) throw BagError(error);
}

}  // namespace tactile_bag
