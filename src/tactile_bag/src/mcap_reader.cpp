// MCAP reader (see mcap.hpp). The file is memory-mapped; uncompressed chunks are read in
// place. Messages come out in log-time order: blocks (chunks) are opened in order of their
// start time and merged while their time ranges overlap.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "codec.hpp"
#include "mcap.hpp"
#include "tactile_bag/bag.hpp"

namespace tactile_bag::mcap {
namespace {

// Bounds-checked cursor over one record's content; errors name the byte offset.
struct Cur {
  const uint8_t* p;
  uint64_t n;
  uint64_t pos = 0;
  uint64_t base;  // file offset of p[0] (or offset inside the chunk)
  const FileReader* r;
  std::string what;
  std::string where;

  [[noreturn]] void bad(const std::string& why) const {
    throw BagError(where + ": byte " + std::to_string(base + pos) + ": " + what + ": " + why);
  }
  void need(uint64_t k, const char* field) const {
    if (n - pos < k) bad(std::string("field '") + field + "' runs past the end of the record");
  }
  template <class T>
  T get(const char* field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, p + pos, sizeof(T));
    pos += sizeof(T);
    return v;
  }
  std::string str(const char* field) {
    const uint32_t len = get<uint32_t>(field);
    need(len, field);
    std::string s(reinterpret_cast<const char*>(p + pos), len);
    pos += len;
    return s;
  }
  StringMap map(const char* field) {
    const uint32_t len = get<uint32_t>(field);
    need(len, field);
    const uint64_t end = pos + len;
    StringMap m;
    while (pos < end) {
      const uint64_t saved = n;
      n = end;  // entries must stay inside the map
      std::string k = str(field);
      std::string v = str(field);
      n = saved;
      m[k] = v;
    }
    return m;
  }
};

}  // namespace

FileReader::FileReader() = default;

FileReader::~FileReader() {
  if (map_ != nullptr) ::munmap(map_, size_);
}

void FileReader::fail(uint64_t offset, const std::string& what) const {
  throw BagError(path_ + ": byte " + std::to_string(offset) + ": " + what);
}

void FileReader::open(const std::string& path) {
  path_ = path;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw BagError(path + ": cannot open mcap file: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    throw BagError(path + ": cannot stat mcap file: " + std::strerror(errno));
  }
  const auto size = static_cast<size_t>(st.st_size);
  if (size == 0) {
    ::close(fd);
    throw BagError(path + ": file is empty (0 bytes): not an mcap file");
  }
  void* m = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (m == MAP_FAILED) throw BagError(path + ": cannot map mcap file: " + std::strerror(errno));
  ::madvise(m, size, MADV_SEQUENTIAL);
  map_ = m;
  data_ = static_cast<const uint8_t*>(m);
  size_ = size;
  scan();
}

void FileReader::open_buffer(const uint8_t* data, size_t size, const std::string& name) {
  path_ = name;
  data_ = data;
  size_ = size;
  scan();
}

// Parse the records of the data section (or of a chunk: in_chunk). Schemas, channels and
// metadata are collected; messages are appended to *out (pointers into p).
void FileReader::parse_records(const uint8_t* p, uint64_t size, uint64_t base, bool in_chunk,
                               const std::string& where, std::vector<Message>* out) {
  uint64_t pos = 0;
  while (pos < size) {
    if (size - pos < 9) {
      throw BagError(where + ": byte " + std::to_string(base + pos) + ": record header runs past the end (" +
                     std::to_string(size - pos) + " bytes left, 9 needed)");
    }
    const uint8_t op = p[pos];
    uint64_t len;
    std::memcpy(&len, p + pos + 1, 8);
    if (len > size - pos - 9) {
      throw BagError(where + ": byte " + std::to_string(base + pos) + ": record (opcode 0x" +
                     [&] { char b[3]; std::snprintf(b, sizeof b, "%02x", op); return std::string(b); }() +
                     ") declares " + std::to_string(len) + " bytes but only " +
                     std::to_string(size - pos - 9) + " remain (truncated?)");
    }
    Cur c{p + pos + 9, len, 0, base + pos + 9, this, "", where};
    switch (op) {
      case kSchema: {
        c.what = "schema record";
        Schema s;
        s.id = c.get<uint16_t>("id");
        s.name = c.str("name");
        s.encoding = c.str("encoding");
        s.data = c.str("data");
        if (s.id == 0) c.bad("schema id 0 is reserved");
        schemas_[s.id] = s;
        break;
      }
      case kChannel: {
        c.what = "channel record";
        Channel ch;
        ch.id = c.get<uint16_t>("id");
        ch.schema_id = c.get<uint16_t>("schema_id");
        ch.topic = c.str("topic");
        ch.encoding = c.str("message_encoding");
        ch.metadata = c.map("metadata");
        channels_[ch.id] = ch;
        break;
      }
      case kMessage: {
        c.what = "message record";
        Message m{};
        m.channel_id = c.get<uint16_t>("channel_id");
        c.get<uint32_t>("sequence");
        m.log_time = c.get<uint64_t>("log_time");
        c.get<uint64_t>("publish_time");
        m.data = c.p + c.pos;
        m.size = static_cast<size_t>(len - c.pos);
        if (channels_.count(m.channel_id) == 0) {
          c.bad("message on channel " + std::to_string(m.channel_id) +
                " before its channel record (not a valid mcap file)");
        }
        if (out != nullptr) out->push_back(m);
        break;
      }
      case kChunk:
        if (in_chunk) c.bad("chunk inside a chunk");
        break;  // handled by scan()
      case kMetadata: {
        c.what = "metadata record";
        std::string name = c.str("name");
        metadata_[name] = c.map("metadata");
        break;
      }
      case kHeader:
        if (in_chunk) { c.what = "header record"; c.bad("header inside a chunk"); }
        break;
      default:
        break;  // indexes, attachments, statistics: not needed (the file is scanned)
    }
    pos += 9 + len;
  }
}

// A chunk record at `q` whose framing is self-consistent: its length fits before `end`,
// its compression is one of the spec's names and its fields add up to exactly the record
// length (the records field is last). The chunk CRC is checked when the chunk is loaded.
bool FileReader::chunk_at(uint64_t q, uint64_t end) const {
  if (end - q < 9 || data_[q] != kChunk) return false;
  uint64_t len;
  std::memcpy(&len, data_ + q + 1, 8);
  constexpr uint64_t kFixed = 8 + 8 + 8 + 4 + 4 + 8;  // times, size, crc, string length, records length
  if (len < kFixed || len > end - q - 9) return false;
  const uint8_t* body = data_ + q + 9;
  uint64_t t0, t1;
  std::memcpy(&t0, body, 8);
  std::memcpy(&t1, body + 8, 8);
  uint32_t clen;
  std::memcpy(&clen, body + 28, 4);
  if (t0 > t1 || clen > 4 || kFixed + clen > len) return false;
  const std::string comp(reinterpret_cast<const char*>(body + 32), clen);
  if (!comp.empty() && !codec::supported(comp)) return false;
  uint64_t rsize;
  std::memcpy(&rsize, body + 32 + clen, 8);
  return rsize == len - kFixed - clen;
}

// First offset in (from, end) where a self-consistent chunk record starts; `end` if none.
uint64_t FileReader::next_chunk(uint64_t from, uint64_t end) const {
  for (uint64_t q = from + 1; q + 9 <= end;) {
    const void* hit = std::memchr(data_ + q, kChunk, static_cast<size_t>(end - q));
    if (hit == nullptr) break;
    q = static_cast<uint64_t>(static_cast<const uint8_t*>(hit) - data_);
    if (chunk_at(q, end)) return q;
    ++q;
  }
  return end;
}

void FileReader::note_damage(const std::string& what) {
  ++damage_events_;
  if (damage_notes_.size() < 3) damage_notes_.push_back(what);
}

void FileReader::scan() {
  const std::string& f = path_;
  if (size_ < 8 || std::memcmp(data_, kMagic, 8) != 0) {
    throw BagError(f + ": byte 0: not an mcap file (bad magic: expected \\x89MCAP0\\r\\n)");
  }
  // Footer: the last 8 bytes are the magic again, preceded by a 29-byte footer record.
  bool has_footer = size_ >= 8 + 9 + 37 && std::memcmp(data_ + size_ - 8, kMagic, 8) == 0 &&
                    data_[size_ - 8 - 29] == kFooter;
  uint64_t data_end = size_;  // where the data section scan stops at the latest
  if (has_footer) data_end = size_ - 8 - 29;
  // Header record.
  if (size_ < 17 || data_[8] != kHeader) fail(8, "expected the header record (opcode 0x01) after the magic");
  uint64_t pos = 8;
  std::vector<Message> loose;
  std::string note;  // how the data section ends early (no footer)
  while (pos < data_end) {
    if (data_end - pos < 9) {
      note = "file ends inside a record header at byte " + std::to_string(pos);
      bytes_lost_ += data_end - pos;
      break;
    }
    const uint8_t op = data_[pos];
    uint64_t len;
    std::memcpy(&len, data_ + pos + 1, 8);
    if (op == 0 || len > data_end - pos - 9) {
      // The framing is damaged here (a reserved opcode, or a length past the end): go on at
      // the next chunk record that frames itself consistently, or treat the rest as lost.
      const uint64_t next = next_chunk(pos, data_end);
      const std::string why =
          op == 0 ? std::string("record with the reserved opcode 0x00")
                  : "record (opcode " + std::to_string(op) + ") declares " + std::to_string(len) + " bytes but only " +
                        std::to_string(data_end - pos - 9) + " remain" + (has_footer ? " before the footer" : "");
      if (next < data_end) {
        note_damage(f + ": byte " + std::to_string(pos) + ": " + why + "; " + std::to_string(next - pos) +
                    " bytes skipped to the chunk at byte " + std::to_string(next));
        bytes_lost_ += next - pos;
        pos = next;
        continue;
      }
      bytes_lost_ += data_end - pos;
      if (!has_footer && op != 0) {
        note = "file ends inside a record (opcode " + std::to_string(op) + ") at byte " + std::to_string(pos) +
               " (" + std::to_string(data_end - pos) + " bytes lost)";
      } else {
        note_damage(f + ": byte " + std::to_string(pos) + ": " + why + "; the " + std::to_string(data_end - pos) +
                    " bytes from there to " + (has_footer ? "the footer" : "the end") + " hold no readable chunk");
      }
      break;
    }
    const uint8_t* body = data_ + pos + 9;
    bool stop = false;
    try {
      scan_record(op, pos, len, body, loose, stop);
    } catch (const BagError& e) {
      // The record frames itself (its length fits) but its content is damaged: skip it.
      if (op == kChunk) ++chunks_skipped_;
      note_damage(e.what());
    }
    if (stop) break;
    pos += 9 + len;
  }
  if (has_footer) read_summary();
  std::string damage;
  if (damage_events_ > 0) {
    if (chunks_skipped_ > 0) damage = std::to_string(chunks_skipped_) + " damaged chunk(s) skipped";
    if (damage_events_ > chunks_skipped_) {
      damage += (damage.empty() ? "" : ", ") + std::to_string(damage_events_ - chunks_skipped_) +
                " damaged region(s) skipped";
    }
    damage += " (";
    for (size_t i = 0; i < damage_notes_.size(); ++i) damage += (i ? "; " : "") + damage_notes_[i];
    damage += damage_events_ > damage_notes_.size() ? "; ...)" : ")";
  }
  std::string read = std::to_string(total_) + " messages read";
  if (summary_messages_ > total_) {
    read += " of the " + std::to_string(summary_messages_) + " the summary lists (" +
            std::to_string(summary_messages_ - total_) + " lost)";
  }
  if (!has_footer) {
    recovery_note_ = "no mcap footer (recording not closed?)";
    if (!note.empty()) recovery_note_ += ": " + note;
    if (!damage.empty()) recovery_note_ += "; " + damage;
    recovery_note_ += "; " + read + " from the complete records";
  } else if (!damage.empty() || !summary_note_.empty()) {
    recovery_note_ = damage;
    if (!summary_note_.empty()) recovery_note_ += (recovery_note_.empty() ? "" : "; ") + summary_note_;
    recovery_note_ += "; " + read;
  }
  for (const auto& [id, ch] : channels_) {
    if (ch.schema_id != 0 && schemas_.count(ch.schema_id) == 0) {
      throw BagError(f + ": channel " + std::to_string(id) + " ('" + ch.topic + "') refers to schema " +
                     std::to_string(ch.schema_id) + " that the file does not define");
    }
  }
  if (!loose.empty()) {
    Block top;
    top.top_level = true;
    std::stable_sort(loose.begin(), loose.end(),
                     [](const Message& x, const Message& y) { return x.log_time < y.log_time; });
    top.start = loose.front().log_time;
    top.end = loose.back().log_time;
    top.loose = std::move(loose);
    blocks_.push_back(std::move(top));
  }
  std::stable_sort(blocks_.begin(), blocks_.end(),
                   [](const Block& x, const Block& y) { return x.start < y.start; });
  ready_ = false;
}

// One top-level record of the data section (framing already checked). Throws BagError if
// its content is damaged; sets `stop` at the data end record.
void FileReader::scan_record(uint8_t op, uint64_t pos, uint64_t len, const uint8_t* body,
                             std::vector<Message>& loose, bool& stop) {
  const std::string& f = path_;
  if (op == kHeader && pos == 8) {
    Cur c{body, len, 0, pos + 9, this, "header record", f};
    profile_ = c.str("profile");
  } else if (op == kChunk) {
    Cur c{body, len, 0, pos + 9, this, "chunk record", f};
    Block b;
    b.offset = pos;
    b.start = c.get<uint64_t>("message_start_time");
    b.end = c.get<uint64_t>("message_end_time");
    b.uncompressed_size = c.get<uint64_t>("uncompressed_size");
    b.crc = c.get<uint32_t>("uncompressed_crc");
    b.compression = c.str("compression");
    const uint64_t rsize = c.get<uint64_t>("records");
    c.need(rsize, "records");
    b.records = body + c.pos;
    b.records_size = rsize;
    if (!b.compression.empty() && !codec::supported(b.compression)) {
      fail(pos, "chunk record: unknown compression '" + b.compression + "' (supported: none, zstd, lz4)");
    }
    if (b.compression.empty() && rsize != b.uncompressed_size) {
      fail(pos, "chunk record: uncompressed chunk of " + std::to_string(rsize) +
                    " bytes declares uncompressed_size " + std::to_string(b.uncompressed_size));
    }
    // uncompressed_size sizes the decompression: bounded by the cap and by what the
    // compressed bytes can expand to (codec.hpp), before anything is allocated.
    if (!b.compression.empty()) {
      if (b.uncompressed_size > codec::kMaxDecompressedBytes) {
        fail(pos, "chunk record: field 'uncompressed_size' = " + std::to_string(b.uncompressed_size) +
                      " exceeds the cap of " + std::to_string(codec::kMaxDecompressedBytes) + " bytes per chunk");
      }
      if (b.uncompressed_size > codec::max_expansion(b.compression, rsize)) {
        fail(pos, "chunk record: field 'uncompressed_size' = " + std::to_string(b.uncompressed_size) +
                      " cannot come from " + std::to_string(rsize) + " bytes of " + b.compression + " data (at most " +
                      std::to_string(codec::max_expansion(b.compression, rsize)) + ")");
      }
    }
    // Collect schemas, channels and counts now (the chunk is decoded again when read). A
    // chunk without CRC is parsed before anything vouches for it: its definitions are kept
    // only if the whole chunk parses.
    std::map<uint16_t, Schema> schemas_before;
    std::map<uint16_t, Channel> channels_before;
    const bool no_crc = b.crc == 0;
    if (no_crc) {
      schemas_before = schemas_;
      channels_before = channels_;
    }
    Cursor tmp;
    blocks_.push_back(std::move(b));
    try {
      load(blocks_.size() - 1, tmp);
    } catch (...) {
      blocks_.pop_back();
      if (no_crc) {
        schemas_.swap(schemas_before);
        channels_.swap(channels_before);
      }
      throw;
    }
    Block& bb = blocks_.back();
    if (!tmp.messages.empty()) {
      bb.start = tmp.messages.front().log_time;
      bb.end = bb.start;
      for (const auto& m : tmp.messages) {
        bb.end = std::max(bb.end, m.log_time);
        ++counts_[m.channel_id];
        if (total_ == 0 || m.log_time < start_) start_ = m.log_time;
        if (total_ == 0 || m.log_time > end_) end_ = m.log_time;
        ++total_;
      }
    } else {
      blocks_.pop_back();
    }
  } else if (op == kDataEnd) {
    stop = true;  // the summary follows
    if (len >= 4) {
      uint32_t crc;
      std::memcpy(&crc, body, 4);
      if (crc != 0) {
        const uint32_t got = codec::crc32(0, data_, pos);
        if (got != crc) {
          // Every chunk was checked against its own CRC; what else lies in the data section
          // (message indexes, records outside chunks) may be damaged.
          note_damage(f + ": byte " + std::to_string(pos) + ": data section CRC mismatch: stored " +
                      std::to_string(crc) + ", computed " + std::to_string(got) +
                      " (chunks are checked by their own CRCs)");
        }
      }
    }
  } else if (op == kFooter) {
    fail(pos, "footer record in the data section");
  } else {
    std::vector<Message> msgs;
    parse_records(data_ + pos, 9 + len, 0, false, f, &msgs);
    for (const auto& m : msgs) {
      loose.push_back(m);
      ++counts_[m.channel_id];
      if (total_ == 0 || m.log_time < start_) start_ = m.log_time;
      if (total_ == 0 || m.log_time > end_) end_ = m.log_time;
      ++total_;
    }
  }
}

// Summary section (footer present): its CRC, and the message count of its statistics
// record, which says how many messages a damaged file lost. The reader does not need the
// summary otherwise (the data section is scanned), so a damaged one is a note, not an error.
void FileReader::read_summary() {
  const uint8_t* ft = data_ + size_ - 8 - 29;
  uint64_t summary_start;
  uint32_t summary_crc;
  std::memcpy(&summary_start, ft + 9, 8);
  std::memcpy(&summary_crc, ft + 25, 4);
  const uint64_t footer = size_ - 8 - 29;
  if (summary_start == 0) return;
  if (summary_start < 8 || summary_start > footer) {
    summary_note_ = "footer: summary_start " + std::to_string(summary_start) + " is outside the file (summary ignored)";
    return;
  }
  if (summary_crc != 0) {
    const uint32_t got = codec::crc32(0, data_ + summary_start, size_ - 8 - 4 - summary_start);
    if (got != summary_crc) {
      summary_note_ = "summary section CRC mismatch at byte " + std::to_string(summary_start) + ": stored " +
                      std::to_string(summary_crc) + ", computed " + std::to_string(got) + " (summary ignored)";
      return;
    }
  }
  for (uint64_t q = summary_start; footer - q >= 9;) {
    uint64_t len;
    std::memcpy(&len, data_ + q + 1, 8);
    if (len > footer - q - 9) break;
    if (data_[q] == kStatistics && len >= 8) std::memcpy(&summary_messages_, data_ + q + 9, 8);
    q += 9 + len;
  }
}

void FileReader::load(size_t index, Cursor& c) {
  Block& b = blocks_[index];
  c.block = index;
  c.pos = 0;
  c.messages.clear();
  if (b.top_level) {
    c.messages = b.loose;
  } else {
    const uint8_t* rec = b.records;
    uint64_t rsize = b.records_size;
    const std::string where = path_ + ": chunk at byte " + std::to_string(b.offset);
    if (!b.compression.empty()) {
      codec::decompress(b.compression, b.records, b.records_size, b.uncompressed_size,
                        codec::kMaxDecompressedBytes, c.buffer, where);
      rec = c.buffer.data();
      rsize = c.buffer.size();
    }
    if (b.crc != 0) {
      const uint32_t got = codec::crc32(0, rec, rsize);
      if (got != b.crc) {
        throw BagError(where + ": CRC mismatch of the uncompressed records: stored " +
                       std::to_string(b.crc) + ", computed " + std::to_string(got) + " (file corrupt)");
      }
    }
    parse_records(rec, rsize, 0, true, where + ", offset in chunk", &c.messages);
    std::stable_sort(c.messages.begin(), c.messages.end(),
                     [](const Message& x, const Message& y) { return x.log_time < y.log_time; });
  }
  if (!wanted_.empty()) {
    c.messages.erase(std::remove_if(c.messages.begin(), c.messages.end(),
                                    [&](const Message& m) { return !wanted_[m.channel_id]; }),
                     c.messages.end());
  }
}

void FileReader::set_channel_filter(const std::vector<uint16_t>& ids) {
  wanted_.clear();
  if (!ids.empty()) {
    wanted_.assign(65536, false);
    for (uint16_t id : ids) wanted_[id] = true;
  }
  reset();
}

void FileReader::reset() { ready_ = false; }

// Open every block that may hold the next message: all blocks starting no later than the
// earliest pending message.
void FileReader::fill() {
  if (!ready_) {
    active_.clear();
    next_block_ = 0;
    ready_ = true;
  }
  for (;;) {
    active_.erase(std::remove_if(active_.begin(), active_.end(),
                                 [](const std::unique_ptr<Cursor>& c) { return c->pos >= c->messages.size(); }),
                  active_.end());
    if (next_block_ >= blocks_.size()) return;
    bool need = active_.empty();
    if (!need) {
      uint64_t tmin = UINT64_MAX;
      for (const auto& c : active_) tmin = std::min(tmin, c->messages[c->pos].log_time);
      need = blocks_[next_block_].start <= tmin;
    }
    if (!need) return;
    // Chunks whose time ranges overlap are held decompressed together: bounded like one chunk.
    const Block& b = blocks_[next_block_];
    uint64_t held = b.compression.empty() ? 0 : b.uncompressed_size;
    for (const auto& c : active_) held += c->buffer.size();
    if (!active_.empty() && held > memory_cap_) {
      fail(b.offset, "chunk record: " + std::to_string(active_.size() + 1) +
                         " chunks overlapping in time would hold " + std::to_string(held) +
                         " bytes decompressed at once, more than the cap of " + std::to_string(memory_cap_));
    }
    auto c = std::make_unique<Cursor>();
    load(next_block_++, *c);
    active_.push_back(std::move(c));
  }
}

bool FileReader::peek_time(uint64_t& t) {
  fill();
  const Cursor* best = nullptr;
  for (const auto& c : active_) {
    if (best == nullptr || c->messages[c->pos].log_time < best->messages[best->pos].log_time) best = c.get();
  }
  if (best == nullptr) return false;
  t = best->messages[best->pos].log_time;
  return true;
}

bool FileReader::next(Message& out) {
  fill();
  Cursor* best = nullptr;
  for (const auto& c : active_) {  // active_ is in block (file-time) order: ties keep it
    if (best == nullptr || c->messages[c->pos].log_time < best->messages[best->pos].log_time) best = c.get();
  }
  if (best == nullptr) return false;
  out = best->messages[best->pos++];
  return true;
}

}  // namespace tactile_bag::mcap
