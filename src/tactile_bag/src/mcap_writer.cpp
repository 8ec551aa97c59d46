// MCAP writer (see mcap.hpp). One writev() syscall per chunk (header, records, message
// indexes); nothing per message but a memcpy into the chunk buffer and an index entry.
#include <fcntl.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>

#include "codec.hpp"
#include "mcap.hpp"
#include "tactile_bag/bag.hpp"

namespace tactile_bag::mcap {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "MCAP records are little-endian");

template <class T>
void put(std::vector<uint8_t>& b, T v) {
  const size_t n = b.size();
  b.resize(n + sizeof(T));
  std::memcpy(b.data() + n, &v, sizeof(T));
}
void put_str(std::vector<uint8_t>& b, const std::string& s) {
  put<uint32_t>(b, static_cast<uint32_t>(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}
void put_map(std::vector<uint8_t>& b, const StringMap& m) {
  uint32_t len = 0;
  for (const auto& [k, v] : m) len += 8 + static_cast<uint32_t>(k.size() + v.size());
  put<uint32_t>(b, len);
  for (const auto& [k, v] : m) {
    put_str(b, k);
    put_str(b, v);
  }
}
// Start a record; returns the position of its length field (patched by end_record).
size_t begin_record(std::vector<uint8_t>& b, uint8_t op) {
  b.push_back(op);
  const size_t at = b.size();
  put<uint64_t>(b, 0);
  return at;
}
void end_record(std::vector<uint8_t>& b, size_t at) {
  const uint64_t len = b.size() - at - 8;
  std::memcpy(b.data() + at, &len, 8);
}

}  // namespace

FileWriter::~FileWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void FileWriter::fail(const std::string& what) const { throw BagError(path_ + ": " + what); }

void FileWriter::emit_pieces(const std::vector<std::pair<const uint8_t*, size_t>>& pieces) {
  std::vector<iovec> iov;
  size_t total = 0;
  for (const auto& [p, n] : pieces) {
    if (n == 0) continue;
    if (cfg_.data_crc) data_crc_ = codec::crc32(data_crc_, p, n);
    iov.push_back({const_cast<uint8_t*>(p), n});
    total += n;
  }
  size_t done = 0, first = 0;
  while (first < iov.size()) {
    const ssize_t n = ::writev(fd_, iov.data() + first, static_cast<int>(std::min<size_t>(iov.size() - first, IOV_MAX)));
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write at byte " + std::to_string(offset_ + done) + ": " + std::strerror(errno));
    }
    done += static_cast<size_t>(n);
    // Drop the pieces written in full, advance into a partly written one.
    size_t left = static_cast<size_t>(n);
    while (first < iov.size() && left >= iov[first].iov_len) {
      left -= iov[first].iov_len;
      ++first;
    }
    if (first < iov.size() && left > 0) {
      iov[first].iov_base = static_cast<uint8_t*>(iov[first].iov_base) + left;
      iov[first].iov_len -= left;
    }
  }
  offset_ += total;
}

void FileWriter::emit(const std::vector<uint8_t>& bytes) {
  if (cfg_.data_crc) data_crc_ = codec::crc32(data_crc_, bytes.data(), bytes.size());
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write at byte " + std::to_string(offset_ + done) + ": " + std::strerror(errno));
    }
    done += static_cast<size_t>(n);
  }
  offset_ += bytes.size();
}

void FileWriter::open(const std::string& path, const WriterConfig& config, const std::string& library) {
  path_ = path;
  if (!config.compression.empty() && !codec::supported(config.compression)) {
    throw BagError(path + ": mcap chunk compression '" + config.compression +
                   "' is not supported (none, zstd, lz4)");
  }
  cfg_ = config;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) fail(std::string("cannot create file: ") + std::strerror(errno));
  out_.assign(kMagic, kMagic + 8);
  const size_t at = begin_record(out_, kHeader);
  put_str(out_, "ros2");
  put_str(out_, library);
  end_record(out_, at);
  emit(out_);
  chunk_.reserve(cfg_.chunk_size + 64 * 1024);
}

uint16_t FileWriter::add_schema(const std::string& name, const std::string& encoding,
                                const std::string& data) {
  for (const auto& s : schemas_) {
    if (s.name == name && s.encoding == encoding && s.data == data) return s.id;
  }
  const auto id = static_cast<uint16_t>(schemas_.size() + 1);  // 0 is "no schema"
  schemas_.push_back({id, name, encoding, data});
  schema_in_chunk_.push_back(false);
  return id;
}

uint16_t FileWriter::add_channel(uint16_t schema_id, const std::string& topic,
                                 const std::string& encoding, const StringMap& metadata) {
  if (channels_.size() >= 65535) fail("more than 65535 channels");
  const auto id = static_cast<uint16_t>(channels_.size());
  channels_.push_back({id, schema_id, topic, encoding, metadata});
  channel_in_chunk_.push_back(false);
  chunk_index_.emplace_back();
  channel_counts_.push_back(0);
  sequence_.push_back(0);
  return id;
}

void FileWriter::in_chunk_channel(uint16_t channel_id) {
  const Channel& c = channels_[channel_id];
  if (c.schema_id != 0 && !schema_in_chunk_[c.schema_id - 1]) {
    const Schema& s = schemas_[c.schema_id - 1];
    const size_t at = begin_record(chunk_, kSchema);
    put<uint16_t>(chunk_, s.id);
    put_str(chunk_, s.name);
    put_str(chunk_, s.encoding);
    put_str(chunk_, s.data);
    end_record(chunk_, at);
    schema_in_chunk_[c.schema_id - 1] = true;
  }
  const size_t at = begin_record(chunk_, kChannel);
  put<uint16_t>(chunk_, c.id);
  put<uint16_t>(chunk_, c.schema_id);
  put_str(chunk_, c.topic);
  put_str(chunk_, c.encoding);
  put_map(chunk_, c.metadata);
  end_record(chunk_, at);
  channel_in_chunk_[channel_id] = true;
}

void FileWriter::write(uint16_t channel_id, uint64_t log_time, const uint8_t* data, size_t size) {
  if (fd_ < 0) fail("write on a closed mcap writer");
  if (channel_id >= channels_.size()) fail("write: unknown channel " + std::to_string(channel_id));
  if (!channel_in_chunk_[channel_id]) in_chunk_channel(channel_id);
  const uint64_t rec_offset = chunk_.size();
  // Message record: opcode, length, channel_id, sequence, log_time, publish_time, data.
  const size_t n = chunk_.size();
  chunk_.resize(n + 1 + 8 + 2 + 4 + 8 + 8 + size);
  uint8_t* p = chunk_.data() + n;
  const uint64_t len = 2 + 4 + 8 + 8 + size;
  const uint32_t seq = sequence_[channel_id]++;
  *p = kMessage;
  std::memcpy(p + 1, &len, 8);
  std::memcpy(p + 9, &channel_id, 2);
  std::memcpy(p + 11, &seq, 4);
  std::memcpy(p + 15, &log_time, 8);
  std::memcpy(p + 23, &log_time, 8);  // publish_time: rosbag2 stores the receive time in both
  if (size > 0) std::memcpy(p + 31, data, size);
  auto& idx = chunk_index_[channel_id];
  idx.push_back(log_time);
  idx.push_back(rec_offset);
  if (chunk_empty_ || log_time < chunk_start_) chunk_start_ = log_time;
  if (chunk_empty_ || log_time > chunk_end_) chunk_end_ = log_time;
  if (message_count_ == 0 || log_time < start_) start_ = log_time;
  if (message_count_ == 0 || log_time > end_) end_ = log_time;
  chunk_empty_ = false;
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= cfg_.chunk_size) flush();
}

void FileWriter::flush() {
  if (fd_ < 0 || chunk_empty_) return;
  const uint32_t crc = cfg_.chunk_crc ? codec::crc32(0, chunk_.data(), chunk_.size()) : 0;
  const std::vector<uint8_t>* records = &chunk_;
  if (!cfg_.compression.empty()) {
    codec::compress(cfg_.compression, chunk_.data(), chunk_.size(), compressed_, cfg_.compression_level);
    records = &compressed_;
  }
  ChunkIndex ci{};
  ci.start = chunk_start_;
  ci.end = chunk_end_;
  ci.offset = offset_;
  ci.compressed = records->size();
  ci.uncompressed = chunk_.size();
  // Chunk record header; the records follow it in the file without being copied.
  out_.clear();
  const size_t at = begin_record(out_, kChunk);
  put<uint64_t>(out_, chunk_start_);
  put<uint64_t>(out_, chunk_end_);
  put<uint64_t>(out_, chunk_.size());
  put<uint32_t>(out_, crc);
  put_str(out_, cfg_.compression);
  put<uint64_t>(out_, records->size());
  const uint64_t chunk_len = out_.size() - at - 8 + records->size();
  std::memcpy(out_.data() + at, &chunk_len, 8);
  ci.length = out_.size() + records->size();
  // Message indexes, after the chunk.
  tail_.clear();
  for (uint16_t ch = 0; ch < chunk_index_.size(); ++ch) {
    auto& idx = chunk_index_[ch];
    if (idx.empty()) continue;
    ci.index_offsets[ch] = offset_ + ci.length + tail_.size();
    const size_t mi = begin_record(tail_, kMessageIndex);
    put<uint16_t>(tail_, ch);
    put<uint32_t>(tail_, static_cast<uint32_t>(idx.size() * 8));
    const size_t n = tail_.size();
    tail_.resize(n + idx.size() * 8);
    std::memcpy(tail_.data() + n, idx.data(), idx.size() * 8);
    end_record(tail_, mi);
    idx.clear();
  }
  ci.index_length = tail_.size();
  emit_pieces({{out_.data(), out_.size()}, {records->data(), records->size()}, {tail_.data(), tail_.size()}});
  chunk_indexes_.push_back(std::move(ci));
  chunk_.clear();
  chunk_empty_ = true;
  std::fill(schema_in_chunk_.begin(), schema_in_chunk_.end(), false);
  std::fill(channel_in_chunk_.begin(), channel_in_chunk_.end(), false);
}

void FileWriter::set_metadata(const std::string& name, const StringMap& metadata) {
  metadata_name_ = name;
  metadata_ = metadata;
}

void FileWriter::close() {
  if (fd_ < 0) return;
  flush();
  out_.clear();
  uint64_t meta_offset = 0, meta_length = 0;
  if (!metadata_name_.empty()) {
    meta_offset = offset_;
    const size_t at = begin_record(out_, kMetadata);
    put_str(out_, metadata_name_);
    put_map(out_, metadata_);
    end_record(out_, at);
    meta_length = out_.size();
    emit(out_);
    out_.clear();
  }
  {
    const size_t at = begin_record(out_, kDataEnd);
    put<uint32_t>(out_, 0);
    end_record(out_, at);
    // The data section CRC covers everything before the Data End record (0: not computed).
    if (cfg_.data_crc) std::memcpy(out_.data() + 9, &data_crc_, 4);
  }
  emit(out_);
  // Summary section.
  const uint64_t summary_start = offset_;
  out_.clear();
  struct Group { uint8_t op; uint64_t start, length; };
  std::vector<Group> groups;
  auto group = [&](uint8_t op, size_t from) {
    if (out_.size() > from) groups.push_back({op, summary_start + from, out_.size() - from});
  };
  size_t from = out_.size();
  for (const auto& s : schemas_) {
    const size_t at = begin_record(out_, kSchema);
    put<uint16_t>(out_, s.id);
    put_str(out_, s.name);
    put_str(out_, s.encoding);
    put_str(out_, s.data);
    end_record(out_, at);
  }
  group(kSchema, from);
  from = out_.size();
  for (const auto& c : channels_) {
    const size_t at = begin_record(out_, kChannel);
    put<uint16_t>(out_, c.id);
    put<uint16_t>(out_, c.schema_id);
    put_str(out_, c.topic);
    put_str(out_, c.encoding);
    put_map(out_, c.metadata);
    end_record(out_, at);
  }
  group(kChannel, from);
  from = out_.size();
  {
    const size_t at = begin_record(out_, kStatistics);
    put<uint64_t>(out_, message_count_);
    put<uint16_t>(out_, static_cast<uint16_t>(schemas_.size()));
    put<uint32_t>(out_, static_cast<uint32_t>(channels_.size()));
    put<uint32_t>(out_, 0);                                   // attachments
    put<uint32_t>(out_, metadata_name_.empty() ? 0 : 1);      // metadata
    put<uint32_t>(out_, static_cast<uint32_t>(chunk_indexes_.size()));
    put<uint64_t>(out_, message_count_ > 0 ? start_ : 0);
    put<uint64_t>(out_, message_count_ > 0 ? end_ : 0);
    uint32_t n = 0;
    for (uint64_t c : channel_counts_) n += c > 0 ? 10 : 0;
    put<uint32_t>(out_, n);
    for (uint16_t ch = 0; ch < channel_counts_.size(); ++ch) {
      if (channel_counts_[ch] == 0) continue;
      put<uint16_t>(out_, ch);
      put<uint64_t>(out_, channel_counts_[ch]);
    }
    end_record(out_, at);
  }
  group(kStatistics, from);
  from = out_.size();
  if (meta_length > 0) {
    const size_t at = begin_record(out_, kMetadataIndex);
    put<uint64_t>(out_, meta_offset);
    put<uint64_t>(out_, meta_length);
    put_str(out_, metadata_name_);
    end_record(out_, at);
  }
  group(kMetadataIndex, from);
  from = out_.size();
  for (const auto& ci : chunk_indexes_) {
    const size_t at = begin_record(out_, kChunkIndex);
    put<uint64_t>(out_, ci.start);
    put<uint64_t>(out_, ci.end);
    put<uint64_t>(out_, ci.offset);
    put<uint64_t>(out_, ci.length);
    put<uint32_t>(out_, static_cast<uint32_t>(ci.index_offsets.size() * 10));
    for (const auto& [ch, off] : ci.index_offsets) {
      put<uint16_t>(out_, ch);
      put<uint64_t>(out_, off);
    }
    put<uint64_t>(out_, ci.index_length);
    put_str(out_, cfg_.compression);
    put<uint64_t>(out_, ci.compressed);
    put<uint64_t>(out_, ci.uncompressed);
    end_record(out_, at);
  }
  group(kChunkIndex, from);
  const uint64_t summary_offset_start = summary_start + out_.size();
  for (const auto& g : groups) {
    const size_t at = begin_record(out_, kSummaryOffset);
    out_.push_back(g.op);
    put<uint64_t>(out_, g.start);
    put<uint64_t>(out_, g.length);
    end_record(out_, at);
  }
  out_.push_back(kFooter);
  put<uint64_t>(out_, 20);  // length known up front: the CRC covers it
  put<uint64_t>(out_, summary_start);
  put<uint64_t>(out_, summary_offset_start);
  const uint32_t summary_crc = codec::crc32(0, out_.data(), out_.size());
  put<uint32_t>(out_, summary_crc);
  out_.insert(out_.end(), kMagic, kMagic + 8);
  emit(out_);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(std::string("close: ") + std::strerror(errno));
}

}  // namespace tactile_bag::mcap
