// Corrupt bags (issue 32): bounded memory for sizes read from a file, and the recovery rules
// of the mcap reader (README "Corrupt bags"): every intact chunk around a damaged one is
// read, the damage is counted and said, and a damaged bag with nothing recovered is an error.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "mcap.hpp"
#include "bag_test_files.hpp"
#include "tactile_bag/bag.hpp"

namespace fs = std::filesystem;
using tactile_bag::BagError;
using tactile_bag::Reader;
using tactile_bag::SerializedMessage;
using tactile_bag::Writer;
using tactile_bag::WriterOptions;
using tactile_bag::test::read_file;
using tactile_bag::test::TempDir;
using tactile_bag::test::write_file;

namespace {

// ---- A hand-made mcap file (independent of our writer): little-endian records -------------

void put_u8(std::string& b, uint8_t v) { b.push_back(static_cast<char>(v)); }
void put_u32(std::string& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_u64(std::string& b, uint64_t v) {
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_str(std::string& b, const std::string& s) {
  put_u32(b, static_cast<uint32_t>(s.size()));
  b += s;
}
void put_record(std::string& b, uint8_t op, const std::string& content) {
  put_u8(b, op);
  put_u64(b, content.size());
  b += content;
}

const std::string kMagic("\x89MCAP0\r\n", 8);

/// A zstd frame (RFC 8878) whose header declares `content_size` (8-byte Frame_Content_Size
/// field) but whose only block is `payload` stored raw: what a corrupt or crafted chunk
/// looks like. single_segment: the window is the content size (the decoder would size its
/// buffer by it); otherwise a 128 KiB window.
std::string zstd_frame_declaring(uint64_t content_size, const std::string& payload, bool single_segment) {
  std::string f;
  put_u32(f, 0xFD2FB528u);                       // magic
  put_u8(f, single_segment ? 0xE0 : 0xC0);       // FCS_Field_Size 8 bytes, single segment?
  if (!single_segment) put_u8(f, (7 << 3) | 0);  // window descriptor: 2^(10+7) = 128 KiB
  put_u64(f, content_size);
  const uint32_t header = (static_cast<uint32_t>(payload.size()) << 3) | 1u;  // raw, last block
  f.push_back(static_cast<char>(header & 0xFF));
  f.push_back(static_cast<char>((header >> 8) & 0xFF));
  f.push_back(static_cast<char>((header >> 16) & 0xFF));
  return f + payload;
}

/// An mcap file: magic, header, one zstd chunk (the given frame and declared
/// uncompressed_size, CRC 0 = not computed), data end, footer, magic.
std::string mcap_with_zstd_chunk(const std::string& frame, uint64_t uncompressed_size) {
  std::string b = kMagic, c;
  put_str(c, "ros2");
  put_str(c, "crafted");
  put_record(b, 0x01, c);
  c.clear();
  put_u64(c, 0);                  // message_start_time
  put_u64(c, 0);                  // message_end_time
  put_u64(c, uncompressed_size);  // uncompressed_size
  put_u32(c, 0);                  // uncompressed_crc
  put_str(c, "zstd");
  put_u64(c, frame.size());
  c += frame;
  put_record(b, 0x06, c);
  c.clear();
  put_u32(c, 0);
  put_record(b, 0x0F, c);  // data end
  c.clear();
  put_u64(c, 0);
  put_u64(c, 0);
  put_u32(c, 0);
  put_record(b, 0x02, c);  // footer without summary
  return b + kMagic;
}

std::string bag_with_file(const TempDir& tmp, const std::string& name, const std::string& bytes) {
  const std::string dir = tmp.sub(name);
  fs::create_directories(dir);
  write_file(dir + "/" + name + "_0.mcap", bytes);
  return dir;
}

// The crafted inputs of issue 32: chunk records whose zstd frame header declares a content
// size that the record does not (or a size no data of that length can produce).
struct Crafted {
  const char* name;
  std::string bytes;
  std::vector<std::string> reason;  // fragments the error must contain
};

std::vector<Crafted> crafted_inputs() {
  const std::string garbage(64, 'x');
  std::vector<Crafted> v;
  // Issue 32 case: record says 0 bytes, the frame 4 GB (it was allocated and zero-filled).
  v.push_back({"frame_4g_record_0", mcap_with_zstd_chunk(zstd_frame_declaring(4'000'000'000ULL, garbage, true), 0),
               {"chunk at byte 36", "zstd frame header declares a content size of 4000000000 bytes",
                "container declares 0 bytes"}});
  // Both say 12 GiB (ended in std::bad_alloc): over the per-chunk cap.
  const uint64_t g12 = 12ULL << 30;
  v.push_back({"both_12g", mcap_with_zstd_chunk(zstd_frame_declaring(g12, garbage, true), g12),
               {"byte 36", "uncompressed_size", std::to_string(g12), "exceeds the cap"}});
  // Both say 600 MiB, under the cap, but 81 bytes of zstd cannot expand to that.
  const uint64_t m600 = 600ULL << 20;
  v.push_back({"both_600m", mcap_with_zstd_chunk(zstd_frame_declaring(m600, garbage, false), m600),
               {"byte 36", "uncompressed_size", "cannot come from"}});
  // 600 MiB declared by both with enough bytes behind it to pass the expansion bound: the
  // data (raw garbage) decompresses to far less; the buffer grows only with real output.
  const std::string big(20'000, 'y');
  v.push_back({"both_600m_20k", mcap_with_zstd_chunk(zstd_frame_declaring(m600, big, false), m600),
               {"chunk at byte 36", "zstd"}});
  return v;
}

// VmSize of this process, bytes.
uint64_t vm_size() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmSize:", 0) == 0) return std::stoull(line.substr(7)) * 1024;
  }
  return 0;
}

}  // namespace

// Every crafted input fails with an error naming the file, the byte offset and the field or
// the reason, without allocating what the file declares.
TEST(BoundedMemory, CraftedZstdDeclarationsFailWithAClearError) {
  TempDir tmp("corrupt");
  for (const auto& c : crafted_inputs()) {
    const std::string dir = bag_with_file(tmp, c.name, c.bytes);
    try {
      Reader r(dir);
      ADD_FAILURE() << c.name << ": no error";
    } catch (const BagError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(std::string(c.name) + "_0.mcap"), std::string::npos) << what;
      EXPECT_NE(what.find("nothing recovered"), std::string::npos) << what;
      for (const auto& f : c.reason) EXPECT_NE(what.find(f), std::string::npos) << c.name << ": '" << f << "' in " << what;
    }
  }
}

// The same inputs in a child process whose address space is limited to what it uses plus
// 192 MiB: each must end in a BagError (exit 0), not std::bad_alloc or a kill. Before the
// fix the 4 GB / 12 GiB / 600 MiB declarations were allocated and the child aborted.
TEST(BoundedMemory, CraftedInputsFailCleanlyUnderAnAddressSpaceLimit) {
  TempDir tmp("corrupt");
  for (const auto& c : crafted_inputs()) {
    const std::string dir = bag_with_file(tmp, c.name, c.bytes);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      struct rlimit lim {};
      lim.rlim_cur = lim.rlim_max = vm_size() + (192ULL << 20);
      if (::setrlimit(RLIMIT_AS, &lim) != 0) ::_exit(3);
      int code = 0;
      try {
        Reader r(dir);
        code = 1;  // no error
      } catch (const BagError&) {
        code = 0;
      } catch (const std::bad_alloc&) {
        code = 2;
      } catch (...) {
        code = 4;
      }
      ::_exit(code);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << c.name << ": child killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 0) << c.name << " (1: no error, 2: std::bad_alloc, 3: setrlimit, 4: other)";
  }
}

// ---- Corrupt-bag matrix ----------------------------------------------------------------------

namespace {

constexpr int kChunks = 5;
constexpr int kPerChunk = 20;

// Byte ranges of the top-level chunk records of an mcap file (walking the record framing).
struct Span {
  uint64_t begin, end;
};
std::vector<Span> chunk_spans(const std::string& b) {
  std::vector<Span> out;
  uint64_t pos = 8;
  while (pos + 9 <= b.size()) {
    const auto op = static_cast<uint8_t>(b[pos]);
    uint64_t len;
    std::memcpy(&len, b.data() + pos + 1, 8);
    if (op == 0x06) out.push_back({pos, pos + 9 + len});
    if (op == 0x0F) break;  // data end
    pos += 9 + len;
  }
  return out;
}

// A bag of kChunks chunks of kPerChunk messages; message i carries i in its payload and
// timestamp 1000 + i.
std::string write_matrix_bag(const std::string& dir, const std::string& compression) {
  WriterOptions o;
  o.storage = "mcap";
  o.compression = compression;
  o.flush_interval = std::chrono::milliseconds(0);
  o.chunk_size = 1 << 20;
  o.ros_distro = "kilted";
  Writer w(o);
  w.open(dir);
  tactile_bag::TopicInfo t;
  t.name = "/n";
  t.type = "std_msgs/msg/String";
  t.type_definition = "string data\n";
  w.create_topic(t);
  for (int i = 0; i < kChunks * kPerChunk; ++i) {
    std::vector<uint8_t> data(40, static_cast<uint8_t>(i));
    std::memcpy(data.data(), &i, sizeof i);
    w.write("/n", 1000 + i, data);
    if ((i + 1) % kPerChunk == 0) w.flush();
  }
  const std::string file = w.db_path();
  w.close();
  return file;
}

// The chunk indexes (0-based) whose messages a read returned, checked to be whole chunks
// in timestamp order.
std::set<int> chunks_read(Reader& r) {
  std::set<int> chunks;
  SerializedMessage m;
  int64_t last = -1;
  uint64_t n = 0;
  while (r.read_next(m)) {
    int i;
    std::memcpy(&i, m.data.data(), sizeof i);
    EXPECT_EQ(m.timestamp_ns, 1000 + i);
    EXPECT_GT(m.timestamp_ns, last);
    last = m.timestamp_ns;
    chunks.insert(i / kPerChunk);
    ++n;
  }
  EXPECT_EQ(n, r.message_count());
  EXPECT_EQ(n, chunks.size() * kPerChunk) << "only whole chunks";
  return chunks;
}

struct Case {
  const char* name;
  // Damages the file's bytes given the chunk spans; returns nothing.
  std::function<void(std::string&, const std::vector<Span>&)> damage;
  std::set<int> chunks;           // chunks recovered; empty: open() must fail
  uint64_t skipped;               // chunks counted as skipped
  std::vector<std::string> note;  // fragments of recovery_note() (or of the error)
};

class CorruptMcap : public ::testing::TestWithParam<std::string> {};

}  // namespace

// The matrix of the README ("Corrupt bags"): truncations at several offsets, a bit flip in
// one and in two chunks, a damaged chunk length, a zeroed region across a chunk boundary.
TEST_P(CorruptMcap, RecoversEveryIntactChunk) {
  const std::string compression = GetParam();
  TempDir tmp("corrupt");
  const std::string good_dir = tmp.sub("good");
  const std::string good_file = write_matrix_bag(good_dir, compression);
  const std::string good = read_file(good_file);
  const auto spans = chunk_spans(good);
  ASSERT_EQ(spans.size(), static_cast<size_t>(kChunks));
  auto mid = [](const Span& s) { return s.begin + (s.end - s.begin) / 2; };
  auto flip = [&](std::string& b, const Span& s) { b[mid(s) + 5] = static_cast<char>(b[mid(s) + 5] ^ 0x10); };
  const std::vector<Case> cases = {
      {"intact", [](std::string&, const std::vector<Span>&) {}, {0, 1, 2, 3, 4}, 0, {}},
      {"cut_in_header", [](std::string& b, const std::vector<Span>&) { b.resize(20); }, {}, 0,
       {"nothing recovered", "no mcap footer", "file ends inside a record (opcode 1) at byte 8"}},
      {"cut_in_chunk_1", [&](std::string& b, const std::vector<Span>& s) { b.resize(mid(s[0])); }, {}, 0,
       {"nothing recovered", "file ends inside a record (opcode 6) at byte " + std::to_string(spans[0].begin)}},
      {"cut_in_chunk_3", [&](std::string& b, const std::vector<Span>& s) { b.resize(mid(s[2])); }, {0, 1}, 0,
       {"no mcap footer", "opcode 6) at byte " + std::to_string(spans[2].begin), "40 messages read"}},
      {"cut_after_chunk_5", [&](std::string& b, const std::vector<Span>& s) { b.resize(s[4].end + 3); }, {0, 1, 2, 3, 4},
       0, {"no mcap footer", "file ends inside a record header", "100 messages read"}},
      {"cut_in_summary", [&](std::string& b, const std::vector<Span>&) { b.resize(b.size() - 60); }, {0, 1, 2, 3, 4}, 0,
       {"no mcap footer", "100 messages read"}},
      {"flip_in_chunk_2", [&](std::string& b, const std::vector<Span>& s) { flip(b, s[1]); }, {0, 2, 3, 4}, 1,
       {"1 damaged chunk(s) skipped", "chunk at byte " + std::to_string(spans[1].begin), "80 messages read of the 100",
        "(20 lost)"}},
      {"flip_in_chunks_2_and_4",
       [&](std::string& b, const std::vector<Span>& s) {
         flip(b, s[1]);
         flip(b, s[3]);
       },
       {0, 2, 4}, 2, {"2 damaged chunk(s) skipped", "60 messages read of the 100"}},
      {"chunk_3_length_damaged",
       [&](std::string& b, const std::vector<Span>& s) { b[s[2].begin + 8] = static_cast<char>(0x7F); },
       {0, 1, 3, 4}, 0,
       {"1 damaged region(s) skipped", "byte " + std::to_string(spans[2].begin), "bytes skipped to the chunk at byte " + std::to_string(spans[3].begin),
        "80 messages read of the 100"}},
      {"zeroed_across_chunks_2_3",
       [&](std::string& b, const std::vector<Span>& s) {
         std::memset(&b[s[1].end - 16], 0, s[2].begin + 16 - (s[1].end - 16));
       },
       {0, 3, 4}, 1, {"1 damaged chunk(s) skipped, 1 damaged region(s) skipped", "reserved opcode 0x00", "60 messages read"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string dir = tmp.sub(std::string(c.name) + (compression.empty() ? "_none" : "_" + compression));
    fs::create_directories(dir);
    fs::copy_file(good_dir + "/metadata.yaml", dir + "/metadata.yaml");
    std::string bytes = good;
    c.damage(bytes, spans);
    write_file(dir + "/" + fs::path(good_file).filename().string(), bytes);
    if (c.chunks.empty()) {
      try {
        Reader r(dir);
        ADD_FAILURE() << "no error; read " << r.message_count() << " messages";
      } catch (const BagError& e) {
        for (const auto& f : c.note) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << f << " in " << e.what();
      }
      continue;
    }
    Reader r(dir);
    EXPECT_EQ(chunks_read(r), c.chunks);
    EXPECT_EQ(r.message_count(), c.chunks.size() * kPerChunk);
    EXPECT_EQ(r.chunks_skipped(), c.skipped);
    // Data lost: all but the intact file and the one cut inside its summary (after the data).
    const std::string name = c.name;
    EXPECT_EQ(r.damaged(), name != "intact" && name != "cut_in_summary");
    EXPECT_EQ(r.metadata_complete(), c.note.empty()) << r.recovery_note();
    for (const auto& f : c.note) EXPECT_NE(r.recovery_note().find(f), std::string::npos) << f << " in " << r.recovery_note();
  }
}

INSTANTIATE_TEST_SUITE_P(Compression, CorruptMcap, ::testing::Values("", "zstd", "lz4"),
                         [](const auto& p) { return p.param.empty() ? std::string("none") : p.param; });

// A garbage metadata.yaml beside an intact mcap file: read like a missing one, with the note.
TEST(CorruptBag, GarbageMetadataBesideAnIntactMcapFile) {
  TempDir tmp("corrupt");
  const std::string dir = tmp.sub("g");
  write_matrix_bag(dir, "zstd");
  write_file(dir + "/metadata.yaml", std::string("\x01\x02 not: [yaml", 14));
  Reader r(dir);
  EXPECT_EQ(r.message_count(), static_cast<uint64_t>(kChunks * kPerChunk));
  EXPECT_EQ(r.storage_identifier(), "mcap");
  EXPECT_FALSE(r.damaged());
  EXPECT_NE(r.recovery_note().find("metadata.yaml not used"), std::string::npos) << r.recovery_note();
}

// sqlite3 cut short (issue 32: 1 byte short refused the whole bag). sqlite reads the bytes
// past the end as zeros, so the bag is read on only where what was cut held nothing the
// messages need: here the timestamp index, which close() builds last.
TEST(CorruptBag, TruncatedSqliteIsReadWhereOnlyTheIndexWasCut) {
  TempDir tmp("corrupt");
  const std::string dir = tmp.sub("sq");
  WriterOptions o;
  o.storage = "sqlite3";
  Writer w(o);
  w.open(dir);
  tactile_bag::TopicInfo t;
  t.name = "/n";
  t.type = "std_msgs/msg/String";
  t.type_definition = "string data\n";
  w.create_topic(t);
  for (int i = 0; i < 100; ++i) {
    std::vector<uint8_t> data(40, static_cast<uint8_t>(i));
    std::memcpy(data.data(), &i, sizeof i);
    w.write("/n", 1000 + i, data);
  }
  const std::string db = w.db_path();
  w.close();
  const std::string good = read_file(db);
  const size_t page = 4096;
  ASSERT_EQ(good.size() % page, 0u);
  auto read_all = [&](size_t cut) {
    write_file(db, good.substr(0, good.size() - cut));
    Reader r(dir);
    EXPECT_EQ(r.message_count(), 100u);
    EXPECT_TRUE(r.damaged());
    EXPECT_FALSE(r.metadata_complete());
    EXPECT_NE(r.recovery_note().find("database is truncated: " + std::to_string(good.size() - cut) + " bytes"),
              std::string::npos)
        << r.recovery_note();
    SerializedMessage m;
    int i = 0;
    while (r.read_next(m)) {
      int v;
      std::memcpy(&v, m.data.data(), sizeof v);
      EXPECT_EQ(v, i);
      EXPECT_EQ(m.timestamp_ns, 1000 + i);
      std::vector<uint8_t> expected(40, static_cast<uint8_t>(i));
      std::memcpy(expected.data(), &i, sizeof i);
      EXPECT_EQ(m.data, expected);
      ++i;
    }
    EXPECT_EQ(i, 100);
    return r.recovery_note();
  };
  // 1 byte and 1000 bytes short: the last page (the index) is partial.
  for (size_t cut : {size_t{1}, size_t{1000}}) {
    EXPECT_NE(read_all(cut).find("its last, partial page belongs to 'timestamp_idx' only"), std::string::npos);
  }
  // Whole pages missing, or cut into the messages: an error naming the file and the sizes.
  for (size_t keep : {good.size() - page, good.size() / 2 + 100}) {
    write_file(db, good.substr(0, keep));
    try {
      Reader r(dir);
      ADD_FAILURE() << "no error";
    } catch (const BagError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(db + ": database is truncated: " + std::to_string(keep) + " bytes"), std::string::npos)
          << what;
    }
  }
}

// Chunks whose time ranges overlap are decompressed and held together while merging; their
// sum is bounded like one chunk (a crafted file of many overlapping, highly compressed
// chunks would otherwise hold them all). Here the cap is lowered to 2.5 chunks' worth.
TEST(BoundedMemory, OverlappingChunksHeldTogetherAreCapped) {
  TempDir tmp("corrupt");
  const std::string dir = tmp.sub("overlap");
  WriterOptions o;
  o.storage = "mcap";
  o.compression = "zstd";
  o.flush_interval = std::chrono::milliseconds(0);
  o.chunk_size = 1 << 20;
  Writer w(o);
  w.open(dir);
  tactile_bag::TopicInfo t;
  t.name = "/n";
  t.type = "std_msgs/msg/String";
  t.type_definition = "string data\n";
  w.create_topic(t);
  for (int k = 0; k < 4; ++k) {  // 4 chunks over the same time range
    for (int i = 0; i < 20; ++i) w.write("/n", 1000 + i, std::vector<uint8_t>(40, static_cast<uint8_t>(k)));
    w.flush();
  }
  const std::string file = w.db_path();
  w.close();
  auto read_all = [&](uint64_t cap) {
    tactile_bag::mcap::FileReader r;
    r.open(file);
    if (cap != 0) r.set_memory_cap(cap);
    tactile_bag::mcap::FileReader::Message m{};
    uint64_t n = 0;
    while (r.next(m)) ++n;
    return n;
  };
  EXPECT_EQ(read_all(0), 80u);
  const std::string bytes = read_file(file);
  const auto spans = chunk_spans(bytes);
  ASSERT_EQ(spans.size(), 4u);
  uint64_t chunk;  // the first chunk's uncompressed_size (the others are as large)
  std::memcpy(&chunk, bytes.data() + spans[0].begin + 9 + 16, 8);
  EXPECT_EQ(read_all(4 * chunk), 80u);
  try {
    read_all(chunk * 5 / 2);
    ADD_FAILURE() << "no error";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("chunks overlapping in time would hold"), std::string::npos) << e.what();
  }
}
