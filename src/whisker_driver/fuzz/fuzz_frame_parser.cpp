// libFuzzer harness for the whisker frame parsers (clang: -fsanitize=fuzzer).
// Build: cmake -DWHISKER_DRIVER_FUZZ=ON -DCMAKE_CXX_COMPILER=clang++ ...
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "whisker_driver/frame_parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace whisker_driver;
  TextFrameParser text;
  CsvFrameParser csv;
  std::vector<WhiskerFrame> out;
  // Split the input at a data-dependent point to exercise partial lines.
  const size_t cut = size > 0 ? data[0] % (size + 1) : 0;
  const char* p = reinterpret_cast<const char*>(data);
  for (FrameParser* parser : {static_cast<FrameParser*>(&text), static_cast<FrameParser*>(&csv)}) {
    parser->feed(p, cut, out);
    parser->feed(p + cut, size - cut, out);
  }
  for (const auto& f : out) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(f.pressure[c]) || f.pressure[c] < kMinPressurePa || f.pressure[c] > kMaxPressurePa) std::abort();
      if (std::isinf(f.temperature[c])) std::abort();
    }
  }
  return 0;
}
