// MCAP storage (https://mcap.dev/spec, format version 0) as rosbag2's mcap plugin uses it:
// profile "ros2", schemas with encoding "ros2msg", channels with message encoding "cdr" and
// metadata {offered_qos_profiles, topic_type_hash}, chunked data with message indexes, a
// summary section (schemas, channels, statistics, chunk and metadata indexes, summary
// offsets) and a footer. Written and read without the mcap library (none is packaged in
// Debian): little-endian records <opcode u8><length u64><content>.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace tactile_bag::mcap {

inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Op : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05,
  kChunk = 0x06, kMessageIndex = 0x07, kChunkIndex = 0x08, kAttachment = 0x09,
  kAttachmentIndex = 0x0A, kStatistics = 0x0B, kMetadata = 0x0C, kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E, kDataEnd = 0x0F,
};

using StringMap = std::map<std::string, std::string>;

struct WriterConfig {
  std::string compression;            ///< "" (none, rosbag2's default), "zstd" or "lz4"
  uint64_t chunk_size = 768 * 1024;   ///< uncompressed bytes per chunk (mcap's default)
  int compression_level = 1;
  bool chunk_crc = true;              ///< CRC-32 of every chunk's uncompressed records
  /// CRC-32 of the whole data section in the Data End record. Off by default, as in the
  /// mcap C++ library rosbag2's mcap plugin uses (McapWriterOptions::enableDataCRC = false):
  /// every message is already covered by its chunk's CRC, and a second pass over the
  /// whole recording costs as much as the chunk CRCs themselves. 0 in the file means
  /// "not computed" (mcap specification, Data End).
  bool data_crc = false;
};

/// Buffered writer: records go to an in-memory chunk; a full chunk (or flush()) is
/// compressed and written with its message indexes in one write() call.
class FileWriter {
 public:
  FileWriter() = default;
  ~FileWriter();
  FileWriter(const FileWriter&) = delete;
  FileWriter& operator=(const FileWriter&) = delete;

  void open(const std::string& path, const WriterConfig& config, const std::string& library);
  bool is_open() const { return fd_ >= 0; }
  uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t add_channel(uint16_t schema_id, const std::string& topic, const std::string& encoding,
                       const StringMap& metadata);
  void write(uint16_t channel_id, uint64_t log_time, const uint8_t* data, size_t size);
  /// Write the open chunk (if any) to the file.
  void flush();
  /// Metadata record written (in the data section) at close.
  void set_metadata(const std::string& name, const StringMap& metadata);
  /// Flush, write the data end, summary, footer and closing magic; close the file.
  void close();
  const std::string& path() const { return path_; }
  /// Chunks written to the file so far.
  size_t chunk_count() const { return chunk_indexes_.size(); }

 private:
  struct Schema { uint16_t id; std::string name, encoding, data; };
  struct Channel { uint16_t id, schema_id; std::string topic, encoding; StringMap metadata; };
  struct ChunkIndex {
    uint64_t start, end, offset, length, index_length, compressed, uncompressed;
    std::map<uint16_t, uint64_t> index_offsets;
  };
  void emit(const std::vector<uint8_t>& bytes);
  /// Writes the pieces in order with writev (a chunk is not copied behind its header).
  void emit_pieces(const std::vector<std::pair<const uint8_t*, size_t>>& pieces);
  void in_chunk_channel(uint16_t channel_id);
  [[noreturn]] void fail(const std::string& what) const;

  std::string path_;
  int fd_ = -1;
  WriterConfig cfg_;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::vector<uint8_t> chunk_, compressed_, out_, tail_;
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_empty_ = true;
  std::vector<std::vector<uint64_t>> chunk_index_;   // per channel: (time, offset) pairs
  std::vector<bool> schema_in_chunk_, channel_in_chunk_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<uint64_t> channel_counts_;
  uint64_t message_count_ = 0, start_ = 0, end_ = 0;
  std::vector<uint32_t> sequence_;
  std::string metadata_name_;
  StringMap metadata_;
};

/// One MCAP file opened for reading (memory-mapped). A file without footer (a recording that
/// was killed) is read up to its last complete record; a damaged chunk (CRC mismatch,
/// undecodable, sizes that do not add up) is skipped and counted; damaged framing between
/// chunks is skipped to the next chunk record that frames itself consistently. recovery_note()
/// says what was lost. What cannot be read at all (bad magic, no header) is a BagError
/// naming the file, the byte offset and the reason.
class FileReader {
 public:
  struct Schema { uint16_t id = 0; std::string name, encoding, data; };
  struct Channel { uint16_t id = 0, schema_id = 0; std::string topic, encoding; StringMap metadata; };
  struct Message { uint16_t channel_id; uint64_t log_time; const uint8_t* data; size_t size; };

  FileReader();
  ~FileReader();
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;

  void open(const std::string& path);
  /// Parse an in-memory file (the fuzz harness, tests); `name` names it in errors. The
  /// buffer must outlive the reader.
  void open_buffer(const uint8_t* data, size_t size, const std::string& name);

  const std::string& path() const { return path_; }
  const std::string& profile() const { return profile_; }
  const std::map<uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<uint16_t, Channel>& channels() const { return channels_; }
  const std::map<uint16_t, uint64_t>& channel_counts() const { return counts_; }
  uint64_t message_count() const { return total_; }
  uint64_t start_time() const { return start_; }
  uint64_t end_time() const { return end_; }
  bool complete() const { return recovery_note_.empty(); }
  /// Data lost: a truncated tail, damaged chunks skipped (CRC mismatch, undecodable,
  /// inconsistent sizes), a damaged region skipped to the next chunk, a damaged summary.
  bool damaged() const {
    return bytes_lost_ > 0 || damage_events_ > 0 || !summary_note_.empty();
  }
  uint64_t chunks_skipped() const { return chunks_skipped_; }
  uint64_t bytes_lost() const { return bytes_lost_; }
  /// Message count of the summary's statistics record (0: none, or the summary is damaged).
  uint64_t summary_message_count() const { return summary_messages_; }
  const std::string& recovery_note() const { return recovery_note_; }
  /// Metadata records by name (rosbag2 writes "rosbag2": serialized_metadata, ros_distro).
  const std::map<std::string, StringMap>& metadata() const { return metadata_; }

  /// Bytes of decompressed chunks held at once while iterating (chunks whose time ranges
  /// overlap are merged); default codec::kMaxDecompressedBytes (1 GiB). More is a BagError.
  void set_memory_cap(uint64_t bytes) { memory_cap_ = bytes; }

  /// Restrict iteration to these channel ids (empty: all) and restart.
  void set_channel_filter(const std::vector<uint16_t>& ids);
  void reset();
  /// Next message in log-time order (ties: file order). The data pointer is valid until
  /// the next call.
  bool next(Message& out);
  /// Log time of the next message without consuming it (false at the end).
  bool peek_time(uint64_t& t);

 private:
  struct Block {       // a chunk, or the messages outside chunks
    uint64_t offset = 0;          // byte offset of the chunk record in the file
    uint64_t start = 0, end = 0;
    std::string compression;
    const uint8_t* records = nullptr;
    uint64_t records_size = 0, uncompressed_size = 0;
    uint32_t crc = 0;
    bool top_level = false;
    std::vector<Message> loose;   // top-level messages (top_level == true)
  };
  struct Cursor {
    size_t block = 0;
    std::vector<uint8_t> buffer;   // decompressed records (empty if pointing into the map)
    std::vector<Message> messages;  // sorted by time
    size_t pos = 0;
  };
  void scan();
  void scan_record(uint8_t op, uint64_t pos, uint64_t len, const uint8_t* body, std::vector<Message>& loose,
                   bool& stop);
  void read_summary();
  bool chunk_at(uint64_t q, uint64_t end) const;
  uint64_t next_chunk(uint64_t from, uint64_t end) const;
  void note_damage(const std::string& what);
  void parse_records(const uint8_t* p, uint64_t size, uint64_t base, bool in_chunk,
                     const std::string& where, std::vector<Message>* out);
  void load(size_t block, Cursor& c);
  void fill();
  [[noreturn]] void fail(uint64_t offset, const std::string& what) const;

  std::string path_, profile_, recovery_note_;
  uint64_t memory_cap_ = uint64_t{1} << 30;  // codec::kMaxDecompressedBytes
  uint64_t chunks_skipped_ = 0, bytes_lost_ = 0, damage_events_ = 0, summary_messages_ = 0;
  std::vector<std::string> damage_notes_;  // the first three, for recovery_note()
  std::string summary_note_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  void* map_ = nullptr;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  std::map<uint16_t, uint64_t> counts_;
  std::map<std::string, StringMap> metadata_;
  uint64_t total_ = 0, start_ = 0, end_ = 0;
  std::vector<Block> blocks_;       // sorted by start time
  std::vector<bool> wanted_;        // by channel id (empty: all)
  std::vector<std::unique_ptr<Cursor>> active_;
  size_t next_block_ = 0;
  bool ready_ = false;
};

}  // namespace tactile_bag::mcap
