// rosbag2 reader and writer without ROS (sqlite3 storage plugin, metadata.yaml).
//
// Format (see README.md for the full description):
//   <dir>/metadata.yaml         rosbag2_bagfile_information, version 9 by default
//   <dir>/<basename(dir)>_0.db3 sqlite3 database, schema version 4:
//     schema(schema_version, ros_distro), metadata(id, metadata_version, metadata),
//     topics(id, name, type, serialization_format, offered_qos_profiles,
//            type_description_hash),
//     message_definitions(id, topic_type, encoding, encoded_message_definition,
//                         type_description_hash),
//     messages(id, topic_id, timestamp, data) + index on timestamp.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace tactile_bag {
namespace mcap {
class FileWriter;
class FileReader;
}  // namespace mcap

/// Every error of this library. The message names the file and the reason.
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TopicInfo {
  std::string name;
  std::string type;                          ///< e.g. "tactile_msgs/msg/WhiskerPressure"
  std::string serialization_format = "cdr";
  /// QoS profiles as YAML text (a sequence of maps). Written by the Writer in the
  /// encoding of the chosen metadata version; read back normalised to the Jazzy (v9)
  /// spelling (string enums). Empty on write: default_qos_profiles().
  std::string offered_qos_profiles;
  std::string type_definition;               ///< full definition text (ros2msg)
  std::string definition_encoding = "ros2msg";
  std::string type_description_hash;         ///< "RIHS01_<hex>" or empty
};

struct SerializedMessage {
  std::string topic;
  int64_t timestamp_ns = 0;
  std::vector<uint8_t> data;
};

/// One QoS profile as rosbag2 stores it.
struct QosProfile {
  struct Time {
    int64_t sec = 0;
    int64_t nsec = 0;
  };
  static constexpr Time kInfinite{9223372036LL, 854775807LL};  // RMW_DURATION_INFINITE
  std::string history = "unknown";     // system_default|keep_last|keep_all|unknown
  int64_t depth = 0;
  std::string reliability = "reliable";  // system_default|reliable|best_effort|unknown|best_available
  std::string durability = "volatile";   // system_default|transient_local|volatile|unknown|best_available
  Time deadline = kInfinite;
  Time lifespan = kInfinite;
  std::string liveliness = "automatic";  // system_default|automatic|manual_by_node|manual_by_topic|unknown|best_available
  Time liveliness_lease_duration = kInfinite;
  bool avoid_ros_namespace_conventions = false;
};

/// Parse offered_qos_profiles text (both spellings: integer enums of metadata <= 8,
/// string enums of metadata 9). Throws BagError naming `context` and the key.
std::vector<QosProfile> parse_qos_profiles(const std::string& yaml_text,
                                           const std::string& context = "offered_qos_profiles");
/// Serialise profiles as YAML text; metadata_version < 9 uses integer enums.
std::string dump_qos_profiles(const std::vector<QosProfile>& profiles, int metadata_version = 9);
/// What ROS 2 Jazzy's recorder stores for a reliable / volatile publisher.
std::string default_qos_profiles(int metadata_version = 9);

struct WriterOptions {
  /// rosbag2 metadata version: 9 (Jazzy/Kilted; read by Jazzy and rosbags),
  /// 8 (Iron) or 5 (Humble: QoS as a string with integer enums). 0: the version of
  /// ros_distro (9 when that is empty too).
  int metadata_version = 0;
  /// Open transactions are committed at least this often (wall time), by write()
  /// and by a background thread while idle. A SIGKILL loses at most this window.
  /// 0: nothing is committed by wall time, so the file's bytes depend on the messages
  /// alone (a reproducible recording: a simulation flown twice, or on more workers, writes
  /// the same file): mcap chunks are written by chunk_size, a sqlite3 transaction is
  /// committed every chunk_size bytes of messages, and a SIGKILL loses at most that much.
  std::chrono::milliseconds flush_interval{250};
  /// Distro the bag is for (humble, iron, jazzy, kilted; tactile_bag/distro.hpp): stored in
  /// metadata (v >= 8) and the schema table, and selecting the standard types' layouts
  /// (Humble/Iron: sensor_msgs/Range without `variance`: definition and payload are
  /// converted on write) and the RIHS01 type_description_hash written for every topic
  /// (iron and later; a hash given in TopicInfo is kept). Empty: the distro whose format
  /// the metadata version follows (jazzy, iron, humble), and no hashes are computed.
  std::string ros_distro;
  /// Storage: "sqlite3" (the library's default, unchanged for existing callers) or "mcap"
  /// (what `ros2 bag record` writes since Iron; the default of the `tactile` writers).
  std::string storage = "sqlite3";
  /// mcap chunk compression: "" (none: rosbag2's default), "zstd" or "lz4".
  std::string compression;
  /// mcap: uncompressed bytes per chunk (a chunk is also written every flush_interval).
  /// sqlite3 with flush_interval 0: message bytes per transaction.
  uint64_t chunk_size = 768 * 1024;
};

class Writer {
 public:
  Writer();
  explicit Writer(WriterOptions options);
  ~Writer();  ///< closes
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Create the bag directory (it must not exist or be empty), the database
  /// <dir>/<basename>_0.db3 and a first metadata.yaml.
  void open(const std::string& dir);
  bool is_open() const { return db_ != nullptr || mcap_ != nullptr; }

  /// A created topic by number, for writes without a name lookup (a recorder's hot path).
  /// Numbers are given in creation order from 0 and stay valid until the next open().
  using TopicId = std::size_t;

  /// Register a topic; a second call with the same name and type is a no-op, with
  /// another type an error. Returns the topic's number.
  TopicId create_topic(const TopicInfo& topic);
  bool has_topic(const std::string& name) const;
  /// Type of a created topic; empty if the topic does not exist.
  std::string topic_type(const std::string& name) const;

  void write(const std::string& topic, int64_t timestamp_ns, const uint8_t* data, size_t size);
  void write(const std::string& topic, int64_t timestamp_ns, const std::vector<uint8_t>& data) {
    write(topic, timestamp_ns, data.data(), data.size());
  }
  /// Number of a created topic; throws BagError if it has not been created.
  TopicId topic_id(const std::string& name) const;
  void write(TopicId topic, int64_t timestamp_ns, const uint8_t* data, size_t size);
  /// Typed write (defined in tactile_bag/typed.hpp): serialises with tactile_msgs CDR
  /// and creates the topic from MessageTraits<T> on first use.
  template <class T>
  void write(const std::string& topic, int64_t timestamp_ns, const T& msg);

  /// Commit pending messages now.
  void flush();
  /// Commit, rewrite metadata.yaml with the final counts, close the database.
  void close();

  /// Path of the storage file (.db3 or .mcap).
  const std::string& db_path() const { return db_path_; }
  uint64_t message_count() const;
  const WriterOptions& options() const { return opt_; }

 private:
  struct TopicState {
    TopicInfo info;
    int64_t id = 0;
    uint64_t count = 0;
    bool drop_range_variance = false;  ///< Humble/Iron bag: cut Range's trailing variance
    std::vector<QosProfile> qos;       ///< offered_qos_profiles, parsed once
    std::string metadata_yaml;         ///< its metadata.yaml `topic_metadata` block, emitted once
  };
  TopicState derived_topic_state(const TopicInfo& topic) const;
  void prepare_topic_locked(TopicState& st) const;
  void write_locked(TopicState& st, int64_t timestamp_ns, const uint8_t* data, size_t size);
  void write_mcap_locked(TopicState& st, int64_t timestamp_ns, const uint8_t* data, size_t size);
  bool flush_due_locked();
  void exec(const char* sql);
  void begin_locked();
  void commit_locked();
  void write_metadata_locked(const std::string* inner = nullptr);
  std::string metadata_yaml_locked(bool with_root) const;
  void flusher_main();
  [[noreturn]] void fail(const std::string& what) const;

  WriterOptions opt_;
  std::string dir_, db_path_, db_name_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  std::unique_ptr<mcap::FileWriter> mcap_;
  bool hash_types_ = false;
  std::map<std::string, TopicState> topics_;
  std::vector<std::string> topic_order_;
  std::vector<TopicState*> by_id_;  // TopicId -> state (std::map nodes do not move)
  uint32_t writes_since_clock_ = 0;
  uint64_t bytes_since_commit_ = 0;   ///< message bytes since the last commit (flush_interval 0)
  size_t chunks_at_dirty_ = 0;        ///< mcap chunks in the file when metadata became dirty
  std::map<std::string, bool> defined_types_;
  bool in_txn_ = false;
  bool metadata_dirty_ = false;  ///< a topic was created since metadata.yaml was written
  uint64_t count_ = 0;
  int64_t min_ts_ = 0, max_ts_ = 0;
  std::chrono::steady_clock::time_point last_commit_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread flusher_;
};

class Reader {
 public:
  Reader();
  explicit Reader(const std::string& dir);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// Read metadata.yaml (versions 1..9) and the .db3 files it names. Topics, counts
  /// and times always come from the databases; a missing or stale metadata.yaml (a
  /// killed recording) is reconstructed from them (see metadata_complete()).
  void open(const std::string& dir);
  void close();

  const std::vector<TopicInfo>& topics() const { return topics_; }
  const TopicInfo* find_topic(const std::string& name) const;
  uint64_t message_count() const { return total_count_; }
  uint64_t message_count(const std::string& topic) const;
  int64_t start_time_ns() const { return start_ns_; }
  int64_t end_time_ns() const { return end_ns_; }       ///< last timestamp
  int64_t duration_ns() const { return end_ns_ - start_ns_; }
  int metadata_version() const { return metadata_version_; }  ///< 0 without metadata.yaml
  /// "sqlite3" or "mcap".
  const std::string& storage_identifier() const { return storage_; }
  /// compression_format / compression_mode of metadata.yaml ("" when not compressed).
  const std::string& compression_format() const { return compression_format_; }
  const std::string& compression_mode() const { return compression_mode_; }
  /// ros_distro of the bag (metadata.yaml v >= 8, the sqlite schema table or the mcap
  /// "rosbag2" metadata record); empty if the bag does not say.
  const std::string& ros_distro() const { return ros_distro_; }
  /// Topics of type sensor_msgs/msg/Range recorded in Humble's layout (no variance): read
  /// with a variance of 0 ("unknown") appended, so they decode as the current type.
  const std::vector<std::string>& upgraded_range_topics() const { return upgraded_; }
  /// Topics of type tactile_msgs/msg/FsmState recorded before reason_code,
  /// contact_direction and move_direction were appended (their stored definition lacks
  /// reason_code): read with the three uint8 fields appended as 0 (REASON_NONE,
  /// DIRECTION_NONE), so they decode as the current type.
  const std::vector<std::string>& upgraded_fsm_state_topics() const { return upgraded_fsm_state_; }
  bool metadata_complete() const { return metadata_complete_; }
  /// What was reconstructed or lost, with the file, byte offset and reason (empty when the
  /// bag is complete).
  const std::string& recovery_note() const { return recovery_note_; }
  /// Data was lost reading the bag (mcap: a truncated tail, damaged chunks skipped, a
  /// damaged region skipped): the messages read are what could be recovered. A damaged bag
  /// from which nothing is recovered is a BagError from open(), never an empty bag.
  bool damaged() const { return damaged_; }
  /// mcap chunks skipped as damaged (CRC mismatch, undecodable, inconsistent sizes).
  uint64_t chunks_skipped() const { return chunks_skipped_; }
  const std::vector<std::string>& files() const { return db_paths_; }

  /// Restrict iteration to these topics (empty: all) and restart from the first message.
  void set_topic_filter(const std::vector<std::string>& topics);
  /// Restart iteration from the first message.
  void reset();
  /// Next message in timestamp order (ties: insertion order); false at the end.
  bool read_next(SerializedMessage& out);

 private:
  struct File {
    std::string path;
    sqlite3* db = nullptr;
    sqlite3_stmt* stmt = nullptr;
    std::map<int64_t, std::string> topic_names;  // topic id -> name
    bool has_row = false;
    int64_t ts = 0;
    int64_t rowid = 0;
    bool not_indexed = false;  ///< truncated: read the messages table without its index
    std::string note;          ///< what was lost (truncation), for recovery_note()
  };
  void open_file(File& f, std::map<std::string, TopicInfo>& found,
                 std::map<std::string, uint64_t>& counts, int64_t& tmin, int64_t& tmax,
                 bool& any);
  void step(File& f);
  void prepare_iteration();
  void open_mcap(std::map<std::string, TopicInfo>& found, std::map<std::string, uint64_t>& counts,
                 int64_t& tmin, int64_t& tmax, bool& any);
  bool read_next_mcap(SerializedMessage& out);
  void finish_message(SerializedMessage& out);

  std::string dir_;
  std::string storage_ = "sqlite3", compression_format_, compression_mode_, ros_distro_;
  std::vector<File> files_;
  struct McapFile {
    std::unique_ptr<mcap::FileReader> reader;
    std::vector<std::string> channel_topic;  // channel id -> topic
  };
  std::vector<McapFile> mcap_files_;
  std::vector<std::string> temp_files_;  // decompressed copies of file-compressed bags
  std::vector<std::string> upgraded_;
  std::vector<std::string> upgraded_fsm_state_;
  std::vector<uint8_t> scratch_;
  std::vector<std::string> db_paths_;
  std::vector<TopicInfo> topics_;
  std::map<std::string, uint64_t> counts_;
  std::vector<std::string> filter_;
  uint64_t total_count_ = 0;
  int64_t start_ns_ = 0, end_ns_ = 0;
  int metadata_version_ = 0;
  bool metadata_complete_ = false;
  bool damaged_ = false;
  uint64_t chunks_skipped_ = 0;
  std::string recovery_note_;
  bool iter_ready_ = false;
};

}  // namespace tactile_bag
