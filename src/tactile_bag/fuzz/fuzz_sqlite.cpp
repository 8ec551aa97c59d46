// libFuzzer harness of the sqlite3 bag reader: arbitrary bytes written as the only .db3 file
// of a bag directory without metadata.yaml (so the reader reconstructs topics and counts
// from the database), opened and every message iterated. The reader must either succeed or
// throw BagError: no crash, no sanitizer report, no huge allocation. Seed corpus:
// fuzz/corpus/fuzz_sqlite (a sample bag's database, truncated and damaged copies).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tactile_bag/bag.hpp"

namespace {

// One directory per process, removed at exit.
struct Dir {
  std::string path;
  Dir() {
    std::string t = (std::filesystem::temp_directory_path() / "tactile_fuzz_sqlite_XXXXXX").string();
    if (::mkdtemp(t.data()) == nullptr) std::abort();
    path = t;
  }
  ~Dir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Dir dir;
  const std::string db = dir.path + "/fuzz_0.db3";
  for (const char* suffix : {"-wal", "-shm", "-journal"}) {
    std::error_code ec;
    std::filesystem::remove(db + suffix, ec);
  }
  {
    std::ofstream out(db, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    tactile_bag::Reader r(dir.path);
    tactile_bag::SerializedMessage m;
    size_t n = 0;
    while (r.read_next(m)) n += m.data.size();
    (void)n;
  } catch (const tactile_bag::BagError&) {
  }
  return 0;
}
