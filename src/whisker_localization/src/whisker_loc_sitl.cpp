// whisker_loc_sitl: runs the paper's bench protocols (002 Table I contact
// estimation, Table II sweep localization) on the linear-stage SITL and
// writes metrics.json (same as `tactile stage`).
//
//   whisker_loc_sitl SCENARIO.yaml --out DIR [--seed N]
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>

#include "whisker_localization/protocols.hpp"

int main(int argc, char** argv) {
  std::string scenario, out;
  std::optional<uint64_t> seed;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--out") && i + 1 < argc) {
      out = argv[++i];
    } else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (argv[i][0] != '-' && scenario.empty()) {
      scenario = argv[i];
    } else {
      scenario.clear();
      break;
    }
  }
  if (scenario.empty() || out.empty()) {
    std::cerr << "usage: whisker_loc_sitl SCENARIO.yaml --out DIR [--seed N]\n";
    return 2;
  }
  try {
    std::cout << whisker_localization::run_bench_protocol_to(scenario, out, seed).dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "whisker_loc_sitl: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
