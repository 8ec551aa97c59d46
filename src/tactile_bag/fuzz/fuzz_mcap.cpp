// libFuzzer harness of the mcap reader: arbitrary bytes parsed as an mcap file and every
// message iterated. The reader must either succeed or throw BagError: no crash, no
// sanitizer report, no huge allocation. Seed corpus: any .mcap file (e.g. one written by
// `tactile_bag_tool write-sample DIR --storage mcap`).
// Build: cmake -DTACTILE_BAG_FUZZ=ON with CXX=clang++.
#include <cstddef>
#include <cstdint>

#include "mcap.hpp"
#include "tactile_bag/bag.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    tactile_bag::mcap::FileReader r;
    r.open_buffer(data, size, "fuzz.mcap");
    tactile_bag::mcap::FileReader::Message m{};
    size_t n = 0;
    while (r.next(m)) {
      n += m.size;
    }
    (void)n;
  } catch (const tactile_bag::BagError&) {
  }
  return 0;
}
