// rosbag2 reader: metadata.yaml (versions 1..9) + sqlite3 storage (schema 1..4).
#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include "codec.hpp"
#include "internal.hpp"
#include "mcap.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/distro.hpp"

namespace fs = std::filesystem;

namespace tactile_bag {
namespace {

// metadata.yaml that is rosbag2 metadata but declares what this reader cannot honour (a newer
// version, another storage, another compression): an error, never a fallback. Any other
// fault of the file (not YAML, keys missing or mistyped) makes it unreadable, and the bag is
// read from its data files as if it had none (README "Corrupt bags").
struct UnsupportedMetadata : BagError {
  using BagError::BagError;
};

/// metadata.yaml larger than this is not read (a recording of 1000 topics writes ~1 MB).
constexpr uint64_t kMaxMetadataBytes = uint64_t{16} << 20;

struct MetaTopic {
  TopicInfo info;
  uint64_t count = 0;
};

struct Metadata {
  int version = 0;
  std::string storage = "sqlite3", compression_format, compression_mode, ros_distro;
  std::vector<std::string> files;
  std::vector<MetaTopic> topics;
  uint64_t message_count = 0;
};

// Read a required key; errors name the file, the key path and the reason.
YAML::Node need(const YAML::Node& node, const char* key, const std::string& file,
                const std::string& path) {
  if (!node.IsMap()) throw BagError(file + ": key '" + path + "': expected a map");
  YAML::Node v = node[key];
  if (!v) throw BagError(file + ": key '" + path + "." + key + "': missing");
  return v;
}

template <class T>
T need_as(const YAML::Node& node, const char* key, const std::string& file,
          const std::string& path, const char* what) {
  YAML::Node v = need(node, key, file, path);
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw BagError(file + ": key '" + path + "." + key + "': expected " + what);
  }
}

Metadata parse_metadata(const std::string& file, const std::string& dir) {
  std::error_code size_ec;
  const auto file_size = fs::file_size(file, size_ec);
  if (size_ec) throw BagError(file + ": cannot read: " + size_ec.message());
  if (file_size > kMaxMetadataBytes) {
    throw BagError(file + ": " + std::to_string(file_size) + " bytes, more than the " +
                   std::to_string(kMaxMetadataBytes) + " a metadata.yaml may have (not read)");
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::ParserException& e) {
    throw BagError(file + ": not valid YAML: " + e.what());
  } catch (const YAML::Exception& e) {
    throw BagError(file + ": cannot read: " + e.what());
  }
  if (!root || !root.IsMap()) throw BagError(file + ": expected a YAML map at the top level");
  const std::string top = "rosbag2_bagfile_information";
  YAML::Node info = root[top];
  if (!info) throw BagError(file + ": key '" + top + "': missing");
  if (!info.IsMap()) throw BagError(file + ": key '" + top + "': expected a map");
  Metadata m;
  m.version = need_as<int>(info, "version", file, top, "an integer");
  if (m.version < 1 || m.version > 9) {
    throw UnsupportedMetadata(file + ": key '" + top + ".version': unsupported version " +
                   std::to_string(m.version) + " (this reader supports 1..9)");
  }
  const auto storage = need_as<std::string>(info, "storage_identifier", file, top, "a string");
  if (storage != "sqlite3" && storage != "mcap") {
    throw UnsupportedMetadata(file + ": key '" + top + ".storage_identifier': storage '" + storage +
                   "' is not supported (sqlite3 and mcap are)");
  }
  m.storage = storage;
  if (m.version >= 3 && info["compression_mode"]) {
    std::string mode = need_as<std::string>(info, "compression_mode", file, top, "a string");
    std::transform(mode.begin(), mode.end(), mode.begin(), ::toupper);
    std::string format;
    if (info["compression_format"]) {
      format = need_as<std::string>(info, "compression_format", file, top, "a string");
    }
    if (!mode.empty() && mode != "NONE") {
      if (mode != "FILE" && mode != "MESSAGE") {
        throw UnsupportedMetadata(file + ": key '" + top + ".compression_mode': unknown mode '" + mode +
                       "' (FILE, MESSAGE or NONE)");
      }
      if (format != "zstd") {
        throw UnsupportedMetadata(file + ": key '" + top + ".compression_format': '" + format +
                       "' is not supported (rosbag2 compresses with zstd)");
      }
      m.compression_mode = mode;
      m.compression_format = format;
    }
  }
  if (info["ros_distro"] && info["ros_distro"].IsScalar()) m.ros_distro = info["ros_distro"].Scalar();
  YAML::Node paths = need(info, "relative_file_paths", file, top);
  if (!paths.IsSequence()) {
    throw BagError(file + ": key '" + top + ".relative_file_paths': expected a sequence");
  }
  for (size_t i = 0; i < paths.size(); ++i) {
    std::string rel;
    try {
      rel = paths[i].as<std::string>();
    } catch (const YAML::Exception&) {
      throw BagError(file + ": key '" + top + ".relative_file_paths[" + std::to_string(i) +
                     "]': expected a string");
    }
    // Versions < 4 stored "<bagname>/<file>"; the file always lives in the bag dir.
    m.files.push_back((fs::path(dir) / fs::path(rel).filename()).string());
  }
  m.message_count = need_as<uint64_t>(info, "message_count", file, top, "an unsigned integer");
  YAML::Node topics = need(info, "topics_with_message_count", file, top);
  if (!topics.IsSequence() && !topics.IsNull()) {
    throw BagError(file + ": key '" + top + ".topics_with_message_count': expected a sequence");
  }
  for (size_t i = 0; topics.IsSequence() && i < topics.size(); ++i) {
    const std::string p = top + ".topics_with_message_count[" + std::to_string(i) + "]";
    MetaTopic mt;
    YAML::Node tm = need(topics[i], "topic_metadata", file, p);
    const std::string pt = p + ".topic_metadata";
    mt.info.name = need_as<std::string>(tm, "name", file, pt, "a string");
    mt.info.type = need_as<std::string>(tm, "type", file, pt, "a string");
    mt.info.serialization_format =
        need_as<std::string>(tm, "serialization_format", file, pt, "a string");
    if (m.version >= 4 && tm["offered_qos_profiles"]) {
      YAML::Node q = tm["offered_qos_profiles"];
      std::string text;
      if (q.IsScalar()) {
        text = q.Scalar();
      } else {
        YAML::Emitter e;
        e << q;
        text = e.c_str();
      }
      // Normalise to the Jazzy spelling; errors name the key.
      mt.info.offered_qos_profiles = dump_qos_profiles(
          parse_qos_profiles(text, file + ": key '" + pt + ".offered_qos_profiles'"), 9);
    }
    if (tm["type_description_hash"]) {
      mt.info.type_description_hash =
          need_as<std::string>(tm, "type_description_hash", file, pt, "a string");
    }
    mt.count = need_as<uint64_t>(topics[i], "message_count", file, p, "an unsigned integer");
    m.topics.push_back(mt);
  }
  return m;
}

uint32_t be32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// A database file shorter than its header declares (a cut copy, a disk that filled up).
struct Truncation {
  uint64_t size = 0, pages = 0, page_size = 0;
  bool truncated() const { return size < pages * page_size; }
  std::string what(const std::string& path) const {
    return path + ": database is truncated: " + std::to_string(size) + " bytes, but its header declares " +
           std::to_string(pages) + " pages of " + std::to_string(page_size) + " bytes";
  }
};

// Checks sqlite would only report late (or as a generic error) on first access.
Truncation check_file_header(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) throw BagError(path + ": cannot read database file: " + ec.message());
  if (size == 0) throw BagError(path + ": file is empty (0 bytes): not a database");
  std::array<unsigned char, 100> h{};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(h.data()), static_cast<std::streamsize>(h.size()));
  if (size < 100 || std::memcmp(h.data(), "SQLite format 3", 16) != 0) {
    throw BagError(path + ": file is not a database (no sqlite3 header)");
  }
  uint64_t page_size = (uint64_t{h[16]} << 8) | h[17];
  if (page_size == 1) page_size = 65536;
  const uint32_t pages = be32(&h[28]);
  const bool pages_valid = pages != 0 && be32(&h[24]) == be32(&h[92]);
  Truncation t;
  if (pages_valid) t = Truncation{static_cast<uint64_t>(size), pages, page_size};
  return t;
}

// The b-tree (table or index name) that owns page `pageno`, through sqlite's dbstat virtual
// table; empty if sqlite cannot say (dbstat missing, or the walk meets a damaged page).
std::string page_owner(sqlite3* db, uint64_t pageno) {
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(db, "SELECT name FROM dbstat WHERE pageno = ?", -1, &s, nullptr) != SQLITE_OK) return "";
  sqlite3_bind_int64(s, 1, static_cast<sqlite3_int64>(pageno));
  std::string name;
  int rc;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    if (p != nullptr) name = p;
  }
  sqlite3_finalize(s);
  return rc == SQLITE_DONE ? name : "";
}

[[noreturn]] void sql_fail(sqlite3* db, const std::string& path, const std::string& what) {
  const int code = sqlite3_errcode(db);
  std::string reason = sqlite3_errmsg(db);
  if (code == SQLITE_CORRUPT) reason += " (the file is corrupt or truncated)";
  throw BagError(path + ": " + what + ": " + reason);
}

bool has_column(sqlite3* db, const std::string& path, const char* table, const char* column) {
  sqlite3_stmt* s = nullptr;
  const std::string sql = std::string("PRAGMA table_info(") + table + ")";
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
    sql_fail(db, path, "read columns of " + std::string(table));
  }
  bool found = false;
  int rc;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(s, 1));
    if (name != nullptr && std::strcmp(name, column) == 0) found = true;
  }
  sqlite3_finalize(s);
  if (rc != SQLITE_DONE) sql_fail(db, path, "read columns of " + std::string(table));
  return found;
}

std::string col_text(sqlite3_stmt* s, int i) {
  const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s, i));
  return p != nullptr ? std::string(p, static_cast<size_t>(sqlite3_column_bytes(s, i)))
                      : std::string();
}

}  // namespace

Reader::Reader() = default;
Reader::Reader(const std::string& dir) { open(dir); }
Reader::~Reader() { close(); }

void Reader::close() {
  for (auto& f : files_) {
    sqlite3_finalize(f.stmt);
    sqlite3_close(f.db);
  }
  files_.clear();
  mcap_files_.clear();
  for (const auto& t : temp_files_) {
    std::error_code ec;
    fs::remove(t, ec);
  }
  temp_files_.clear();
  upgraded_.clear();
  upgraded_fsm_state_.clear();
  storage_ = "sqlite3";
  compression_format_.clear();
  compression_mode_.clear();
  ros_distro_.clear();
  db_paths_.clear();
  topics_.clear();
  counts_.clear();
  filter_.clear();
  total_count_ = 0;
  start_ns_ = end_ns_ = 0;
  metadata_version_ = 0;
  metadata_complete_ = false;
  recovery_note_.clear();
  damaged_ = false;
  chunks_skipped_ = 0;
  iter_ready_ = false;
}

const TopicInfo* Reader::find_topic(const std::string& name) const {
  for (const auto& t : topics_) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

uint64_t Reader::message_count(const std::string& topic) const {
  auto it = counts_.find(topic);
  return it == counts_.end() ? 0 : it->second;
}

void Reader::open(const std::string& dir) {
  close();
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw BagError(dir + ": bag directory does not exist");
  if (!fs::is_directory(dir, ec)) throw BagError(dir + ": not a directory (a bag is a directory)");
  dir_ = dir;
  const std::string meta_path = (fs::path(dir) / "metadata.yaml").string();
  Metadata meta;
  bool have_meta = false;
  std::string meta_unreadable;  // why metadata.yaml was not used (the bag is read without it)
  if (fs::exists(meta_path, ec)) {
    try {
      meta = parse_metadata(meta_path, dir);
      have_meta = true;
    } catch (const UnsupportedMetadata&) {
      throw;
    } catch (const BagError& e) {
      meta_unreadable = e.what();
      meta = Metadata{};
    } catch (const YAML::Exception& e) {
      meta_unreadable = meta_path + ": " + e.what();
      meta = Metadata{};
    }
  }
  if (have_meta) {
    metadata_version_ = meta.version;
    storage_ = meta.storage;
    compression_format_ = meta.compression_format;
    compression_mode_ = meta.compression_mode;
    ros_distro_ = meta.ros_distro;
    for (const auto& f : meta.files) {
      if (!fs::exists(f, ec)) {
        throw BagError(f + ": " + (storage_ == "mcap" ? "mcap" : "database") + " file named in " +
                       meta_path + " does not exist");
      }
    }
    db_paths_ = meta.files;
  } else {
    std::vector<std::string> found, mcap;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      if (e.path().extension() == ".db3") found.push_back(e.path().string());
      if (e.path().extension() == ".mcap") mcap.push_back(e.path().string());
    }
    if (found.empty() && !mcap.empty()) {
      found = mcap;
      storage_ = "mcap";
    }
    if (found.empty()) {
      if (!meta_unreadable.empty()) {
        throw BagError(meta_unreadable + "; and no .db3 or .mcap file beside it to read instead");
      }
      throw BagError(dir + ": no metadata.yaml and no .db3 file (nor .mcap): not a rosbag2 bag");
    }
    // Order split files by their numeric suffix (<name>_<n>.db3).
    auto index_of = [](const std::string& p) {
      const std::string stem = fs::path(p).stem().string();
      const auto us = stem.rfind('_');
      try {
        return us == std::string::npos ? 0L : std::stol(stem.substr(us + 1));
      } catch (...) {
        return 0L;
      }
    };
    std::sort(found.begin(), found.end(), [&](const std::string& a, const std::string& b) {
      return index_of(a) != index_of(b) ? index_of(a) < index_of(b) : a < b;
    });
    db_paths_ = found;
  }

  std::map<std::string, TopicInfo> db_topics;
  std::map<std::string, uint64_t> db_counts;
  int64_t tmin = 0, tmax = 0;
  bool any = false;
  try {
    // File-mode compression: every file is one zstd stream; read a decompressed copy.
    std::vector<std::string> paths = db_paths_;
    if (compression_mode_ == "FILE") {
      for (auto& p : paths) {
        const fs::path tmp = fs::temp_directory_path() /
                             ("tactile_bag_" + std::to_string(::getpid()) + "_" +
                              std::to_string(reinterpret_cast<uintptr_t>(this)) + "_" +
                              fs::path(p).stem().string());
        temp_files_.push_back(tmp.string());
        codec::decompress_zstd_file(p, tmp.string());
        p = tmp.string();
      }
    }
    if (storage_ == "mcap") {
      for (const auto& p : paths) {
        McapFile mf;
        mf.reader = std::make_unique<mcap::FileReader>();
        mf.reader->open(p);
        mcap_files_.push_back(std::move(mf));
      }
      open_mcap(db_topics, db_counts, tmin, tmax, any);
    } else {
      files_.resize(paths.size());
      for (size_t i = 0; i < paths.size(); ++i) {
        files_[i].path = paths[i];
        open_file(files_[i], db_topics, db_counts, tmin, tmax, any);
      }
    }
  } catch (...) {
    close();
    throw;
  }

  // Topic list: metadata order first, then topics only the databases know.
  std::set<std::string> seen;
  for (const auto& mt : meta.topics) {
    auto it = db_topics.find(mt.info.name);
    topics_.push_back(it != db_topics.end() ? it->second : mt.info);
    if (it != db_topics.end() && topics_.back().offered_qos_profiles.empty()) {
      topics_.back().offered_qos_profiles = mt.info.offered_qos_profiles;
    }
    seen.insert(mt.info.name);
  }
  for (const auto& [name, info] : db_topics) {
    if (seen.count(name) == 0) topics_.push_back(info);
  }
  for (const auto& t : topics_) {
    counts_[t.name] = db_counts.count(t.name) != 0 ? db_counts[t.name] : 0;
    total_count_ += counts_[t.name];
  }
  start_ns_ = any ? tmin : 0;
  end_ns_ = any ? tmax : 0;

  if (!have_meta) {
    metadata_complete_ = false;
    recovery_note_ = meta_unreadable.empty()
                         ? "no metadata.yaml: topics and counts reconstructed from the database"
                         : "metadata.yaml not used (" + meta_unreadable +
                               "): topics and counts reconstructed from the data files";
  } else {
    metadata_complete_ = true;
    std::string note;
    if (meta.message_count != total_count_) {
      note = "metadata.yaml lists " + std::to_string(meta.message_count) +
             " messages but the database holds " + std::to_string(total_count_);
    }
    for (const auto& mt : meta.topics) {
      if (counts_[mt.info.name] != mt.count && note.empty()) {
        note = "metadata.yaml lists " + std::to_string(mt.count) + " messages on '" +
               mt.info.name + "' but the database holds " +
               std::to_string(counts_[mt.info.name]);
      }
    }
    if (topics_.size() != meta.topics.size() && note.empty()) {
      note = "metadata.yaml lists " + std::to_string(meta.topics.size()) +
             " topics but the database holds " + std::to_string(topics_.size());
    }
    if (!note.empty()) {
      metadata_complete_ = false;
      recovery_note_ = note + " (recording not closed?); using the database";
    }
  }
  std::string damage;
  for (const auto& mf : mcap_files_) {
    if (!mf.reader->complete()) {
      metadata_complete_ = false;
      recovery_note_ += (recovery_note_.empty() ? "" : "; ") + mf.reader->path() + ": " +
                        mf.reader->recovery_note();
    }
    if (mf.reader->damaged()) {
      damaged_ = true;
      chunks_skipped_ += mf.reader->chunks_skipped();
      damage += (damage.empty() ? "" : "; ") + mf.reader->path() + ": " + mf.reader->recovery_note();
    }
  }
  for (const auto& f : files_) {
    if (f.note.empty()) continue;
    damaged_ = true;
    metadata_complete_ = false;
    recovery_note_ += (recovery_note_.empty() ? "" : "; ") + f.note + "; " +
                      std::to_string(total_count_) + " messages read";
    damage += (damage.empty() ? "" : "; ") + f.note;
  }
  // An empty result from a damaged bag is an error, never "0 messages".
  if (damaged_ && total_count_ == 0) {
    const std::string what = dir + ": nothing recovered from the damaged bag: " + damage;
    close();
    throw BagError(what);
  }
  // sensor_msgs/Range in Humble's layout (no variance): by its definition where the bag
  // stores one, else by the bag's distro (Humble/Iron, or metadata older than Jazzy's).
  for (const auto& t : topics_) {
    if (t.type != "sensor_msgs/msg/Range") continue;
    bool old_layout;
    if (!t.type_definition.empty() && t.definition_encoding == "ros2msg") {
      old_layout = !definition_has_field(t.type_definition, t.type, t.type, "variance");
    } else if (!ros_distro_.empty()) {
      old_layout = ros_distro_ == "humble" || ros_distro_ == "iron" || ros_distro_ == "foxy" ||
                   ros_distro_ == "galactic";
    } else {
      old_layout = metadata_version_ > 0 && metadata_version_ < 9;
    }
    if (old_layout) upgraded_.push_back(t.name);
  }
  // tactile_msgs/FsmState before its three trailing uint8 fields (reason_code,
  // contact_direction, move_direction): by the definition the bag stores (every rosbag2
  // since Iron and every bag of this workspace stores one).
  for (const auto& t : topics_) {
    if (t.type == "tactile_msgs/msg/FsmState" && !t.type_definition.empty() && t.definition_encoding == "ros2msg" &&
        !definition_has_field(t.type_definition, t.type, t.type, "reason_code")) {
      upgraded_fsm_state_.push_back(t.name);
    }
  }
}

void Reader::open_mcap(std::map<std::string, TopicInfo>& found, std::map<std::string, uint64_t>& counts,
                       int64_t& tmin, int64_t& tmax, bool& any) {
  for (auto& mf : mcap_files_) {
    const auto& r = *mf.reader;
    mf.channel_topic.assign(65536, std::string());
    for (const auto& [id, ch] : r.channels()) {
      mf.channel_topic[id] = ch.topic;
      if (found.count(ch.topic) != 0) continue;
      TopicInfo t;
      t.name = ch.topic;
      t.serialization_format = ch.encoding;
      auto sc = r.schemas().find(ch.schema_id);
      if (sc != r.schemas().end()) {
        t.type = sc->second.name;
        t.type_definition = sc->second.data;
        t.definition_encoding = sc->second.encoding;
      }
      auto q = ch.metadata.find("offered_qos_profiles");
      if (q != ch.metadata.end() && !q->second.empty()) {
        try {
          t.offered_qos_profiles = dump_qos_profiles(parse_qos_profiles(q->second), 9);
        } catch (const BagError&) {
          t.offered_qos_profiles = q->second;
        }
      }
      auto h = ch.metadata.find("topic_type_hash");
      if (h != ch.metadata.end()) t.type_description_hash = h->second;
      found[t.name] = t;
    }
    for (const auto& [id, n] : r.channel_counts()) counts[mf.channel_topic[id]] += n;
    if (r.message_count() > 0) {
      const auto lo = static_cast<int64_t>(r.start_time()), hi = static_cast<int64_t>(r.end_time());
      if (!any || lo < tmin) tmin = lo;
      if (!any || hi > tmax) tmax = hi;
      any = true;
    }
    if (ros_distro_.empty()) {
      auto m = r.metadata().find("rosbag2");
      if (m != r.metadata().end() && m->second.count("ros_distro") != 0) ros_distro_ = m->second.at("ros_distro");
    }
  }
}

void Reader::open_file(File& f, std::map<std::string, TopicInfo>& found,
                       std::map<std::string, uint64_t>& counts, int64_t& tmin, int64_t& tmax,
                       bool& any) {
  const Truncation cut = check_file_header(f.path);
  if (sqlite3_open_v2(f.path.c_str(), &f.db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string e = f.db != nullptr ? sqlite3_errmsg(f.db) : "out of memory";
    throw BagError(f.path + ": cannot open database: " + e);
  }
  sqlite3* db = f.db;
  if (cut.truncated()) {
    // sqlite reads the bytes of a page cut short as zeros: the page passes sqlite's checks
    // with its tail zeroed, so a message stored there would come back altered. Read on only
    // if the last page is cut short (no page missing entirely: sqlite refuses the schema
    // then) and belongs to what the messages do not need (the timestamp index, built last
    // by close(), or the metadata table); read the messages without the index.
    const std::string base = cut.what(f.path);
    if (cut.size / cut.page_size + 1 != cut.pages) throw BagError(base + " (whole pages missing)");
    const std::string owner = page_owner(db, cut.pages);
    if (owner.empty()) throw BagError(base + " (sqlite cannot tell what its last, partial page held)");
    for (const char* needed : {"messages", "topics", "message_definitions", "schema", "sqlite_schema",
                               "sqlite_master"}) {
      if (owner == needed) throw BagError(base + " (its last, partial page belongs to '" + owner + "')");
    }
    f.note = base + "; its last, partial page belongs to '" + owner + "' only: messages read without the index";
    f.not_indexed = true;
  }
  // No string or blob can be larger than the database (and its WAL): a record declaring a
  // larger payload is refused by sqlite (SQLITE_TOOBIG) before it allocates for it.
  {
    std::error_code size_ec;
    uint64_t bytes = fs::file_size(f.path, size_ec);
    const uint64_t wal = fs::file_size(f.path + "-wal", size_ec);
    if (!size_ec) bytes += wal;
    sqlite3_limit(db, SQLITE_LIMIT_LENGTH, static_cast<int>(std::min<uint64_t>(bytes, INT32_MAX)));
  }
  // Tables present (also the first real read: sqlite reports "file is not a database" here).
  std::set<std::string> tables;
  {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT name FROM sqlite_master WHERE type='table'", -1, &s,
                           nullptr) != SQLITE_OK) {
      sql_fail(db, f.path, "read schema");
    }
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) tables.insert(col_text(s, 0));
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) sql_fail(db, f.path, "read schema");
  }
  for (const char* t : {"topics", "messages"}) {
    if (tables.count(t) == 0) {
      throw BagError(f.path + ": not a rosbag2 database: table '" + t + "' is missing");
    }
  }
  std::map<std::string, std::array<std::string, 3>> defs;  // type -> encoding, text, hash
  if (tables.count("message_definitions") != 0) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db,
                           "SELECT topic_type, encoding, encoded_message_definition,"
                           " type_description_hash FROM message_definitions ORDER BY id",
                           -1, &s, nullptr) != SQLITE_OK) {
      sql_fail(db, f.path, "read message_definitions");
    }
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      defs[col_text(s, 0)] = {col_text(s, 1), col_text(s, 2), col_text(s, 3)};
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) sql_fail(db, f.path, "read message_definitions");
  }
  const bool has_qos = has_column(db, f.path, "topics", "offered_qos_profiles");
  const bool has_hash = has_column(db, f.path, "topics", "type_description_hash");
  {
    std::string sql = "SELECT id, name, type, serialization_format";
    sql += has_qos ? ", offered_qos_profiles" : ", ''";
    sql += has_hash ? ", type_description_hash" : ", ''";
    sql += " FROM topics ORDER BY id";
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
      sql_fail(db, f.path, "read topics");
    }
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      TopicInfo t;
      const int64_t id = sqlite3_column_int64(s, 0);
      t.name = col_text(s, 1);
      t.type = col_text(s, 2);
      t.serialization_format = col_text(s, 3);
      const std::string qos = col_text(s, 4);
      if (!qos.empty()) {
        try {
          t.offered_qos_profiles = dump_qos_profiles(parse_qos_profiles(qos), 9);
        } catch (const BagError&) {
          t.offered_qos_profiles = qos;  // keep what ROS wrote; metadata.yaml may do better
        }
      }
      t.type_description_hash = col_text(s, 5);
      auto d = defs.find(t.type);
      if (d != defs.end()) {
        t.definition_encoding = d->second[0];
        t.type_definition = d->second[1];
        if (t.type_description_hash.empty()) t.type_description_hash = d->second[2];
      }
      f.topic_names[id] = t.name;
      if (found.count(t.name) == 0) found[t.name] = t;
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) sql_fail(db, f.path, "read topics");
  }
  {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db,
                           f.not_indexed ? "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp)"
                                           " FROM messages NOT INDEXED GROUP BY topic_id"
                                         : "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp)"
                                           " FROM messages GROUP BY topic_id",
                           -1, &s, nullptr) != SQLITE_OK) {
      sql_fail(db, f.path, "count messages");
    }
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      const int64_t id = sqlite3_column_int64(s, 0);
      auto name = f.topic_names.find(id);
      if (name == f.topic_names.end()) {
        sqlite3_finalize(s);
        throw BagError(f.path + ": messages reference topic id " + std::to_string(id) +
                       " that is not in the topics table");
      }
      counts[name->second] += static_cast<uint64_t>(sqlite3_column_int64(s, 1));
      const int64_t lo = sqlite3_column_int64(s, 2), hi = sqlite3_column_int64(s, 3);
      if (!any || lo < tmin) tmin = lo;
      if (!any || hi > tmax) tmax = hi;
      any = true;
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) sql_fail(db, f.path, "count messages");
  }
}

void Reader::set_topic_filter(const std::vector<std::string>& topics) {
  for (const auto& t : topics) {
    if (find_topic(t) == nullptr) throw BagError(dir_ + ": topic filter: '" + t + "' is not in the bag");
  }
  filter_ = topics;
  iter_ready_ = false;
}

void Reader::reset() { iter_ready_ = false; }

void Reader::prepare_iteration() {
  if (!mcap_files_.empty()) {
    for (auto& mf : mcap_files_) {
      std::vector<uint16_t> ids;
      if (!filter_.empty()) {
        for (const auto& [id, ch] : mf.reader->channels()) {
          if (std::find(filter_.begin(), filter_.end(), ch.topic) != filter_.end()) ids.push_back(id);
        }
        if (ids.empty()) ids.push_back(65535);  // nothing wanted: a channel that cannot match
      }
      mf.reader->set_channel_filter(ids);
    }
    iter_ready_ = true;
    return;
  }
  if (files_.empty()) throw BagError("tactile_bag::Reader: read_next on a reader that is not open");
  for (auto& f : files_) {
    sqlite3_finalize(f.stmt);
    f.stmt = nullptr;
    std::string sql = "SELECT topic_id, timestamp, data, id FROM messages";
    if (f.not_indexed) sql += " NOT INDEXED";
    if (!filter_.empty()) {
      std::string ids;
      for (const auto& [id, name] : f.topic_names) {
        if (std::find(filter_.begin(), filter_.end(), name) != filter_.end()) {
          ids += (ids.empty() ? "" : ",") + std::to_string(id);
        }
      }
      sql += ids.empty() ? " WHERE 0" : " WHERE topic_id IN (" + ids + ")";
    }
    sql += " ORDER BY timestamp, id";
    if (sqlite3_prepare_v2(f.db, sql.c_str(), -1, &f.stmt, nullptr) != SQLITE_OK) {
      sql_fail(f.db, f.path, "prepare message query");
    }
    step(f);
  }
  iter_ready_ = true;
}

void Reader::step(File& f) {
  const int rc = sqlite3_step(f.stmt);
  if (rc == SQLITE_ROW) {
    f.has_row = true;
    f.ts = sqlite3_column_int64(f.stmt, 1);
    f.rowid = sqlite3_column_int64(f.stmt, 3);
  } else if (rc == SQLITE_DONE) {
    f.has_row = false;
  } else {
    f.has_row = false;
    sql_fail(f.db, f.path, "read messages");
  }
}

bool Reader::read_next_mcap(SerializedMessage& out) {
  McapFile* best = nullptr;
  uint64_t best_t = 0;
  for (auto& mf : mcap_files_) {
    uint64_t t;
    if (mf.reader->peek_time(t) && (best == nullptr || t < best_t)) {
      best = &mf;
      best_t = t;
    }
  }
  if (best == nullptr) return false;
  mcap::FileReader::Message m{};
  best->reader->next(m);
  out.topic = best->channel_topic[m.channel_id];
  out.timestamp_ns = static_cast<int64_t>(m.log_time);
  out.data.assign(m.data, m.data + m.size);
  return true;
}

void Reader::finish_message(SerializedMessage& out) {
  if (compression_mode_ == "MESSAGE") {
    codec::decompress(compression_format_, out.data.data(), out.data.size(), codec::kUnknownSize,
                      codec::kMaxDecompressedBytes, scratch_,
                      dir_ + ": message on '" + out.topic + "' at " + std::to_string(out.timestamp_ns) + " ns");
    out.data.swap(scratch_);
  }
  if (!upgraded_.empty() && std::find(upgraded_.begin(), upgraded_.end(), out.topic) != upgraded_.end()) {
    const size_t n = range_payload_size_without_variance(out.data.data(), out.data.size());
    if (n != 0) {
      out.data.resize(n);
      out.data.insert(out.data.end(), 4, 0);  // variance 0: unknown
    }
  }
  if (!upgraded_fsm_state_.empty() &&
      std::find(upgraded_fsm_state_.begin(), upgraded_fsm_state_.end(), out.topic) != upgraded_fsm_state_.end()) {
    // The old layout ends with uint32 transitions, 4-aligned: no trailing padding, so the
    // three uint8 fields follow at once (0: REASON_NONE, DIRECTION_NONE).
    out.data.insert(out.data.end(), 3, 0);
  }
}

bool Reader::read_next(SerializedMessage& out) {
  if (!iter_ready_) prepare_iteration();
  if (!mcap_files_.empty()) {
    if (!read_next_mcap(out)) return false;
    finish_message(out);
    return true;
  }
  File* best = nullptr;
  for (auto& f : files_) {
    if (f.has_row && (best == nullptr || f.ts < best->ts)) best = &f;
  }
  if (best == nullptr) return false;
  const int64_t id = sqlite3_column_int64(best->stmt, 0);
  auto name = best->topic_names.find(id);
  if (name == best->topic_names.end()) {
    throw BagError(best->path + ": message references unknown topic id " + std::to_string(id));
  }
  out.topic = name->second;
  out.timestamp_ns = best->ts;
  const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(best->stmt, 2));
  const int n = sqlite3_column_bytes(best->stmt, 2);
  out.data.assign(blob, blob + (blob != nullptr ? n : 0));
  step(*best);
  finish_message(out);
  return true;
}

}  // namespace tactile_bag
