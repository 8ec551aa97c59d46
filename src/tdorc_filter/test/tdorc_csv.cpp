// Test helper (not installed): runs TdorcWhisker over CSV samples so an
// independent Python implementation can be compared sample by sample.
//
//   tdorc_csv <mode> <window> <contact_threshold> <absolute 0|1> [learn_delay contact_hold 0|1 max_contact_hold [hold_release_fraction [hold_release_samples [hold_release_drop [hold_level_samples [max_drift_slope [hold_quiet_rms hold_quiet_samples]]]]]]]
//   stdin:  one sample per line: S_r0,S_r1,S_r2
//   stdout: ready,contact,drift_frozen,S_c0,S_c1,S_c2,S_p0,S_p1,S_p2,contact0,contact1,contact2
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>

#include "tdorc_filter/tdorc.hpp"

int main(int argc, char** argv) {
  if (argc != 5 && (argc < 8 || argc > 15 || argc == 14)) {
    std::cerr << "usage: tdorc_csv <tdorc|tdoc|bandpass> <window> <threshold> <absolute 0|1>"
                 " [<learn_delay> <contact_hold 0|1> <max_contact_hold> [<hold_release_fraction> [<hold_release_samples> [<hold_release_drop> [<hold_level_samples> [<max_drift_slope> [<hold_quiet_rms> <hold_quiet_samples>]]]]]]]\n";
    return 2;
  }
  try {
    tdorc_filter::Params p;
    p.mode = tdorc_filter::mode_from_string(argv[1]);
    p.window = std::atoi(argv[2]);
    p.contact_threshold = std::strtod(argv[3], nullptr);
    p.absolute_threshold = std::atoi(argv[4]) != 0;
    if (argc >= 8) {
      p.learn_delay = std::atoi(argv[5]);
      p.contact_hold = std::atoi(argv[6]) != 0;
      p.max_contact_hold = std::atoi(argv[7]);
    }
    if (argc >= 9) p.hold_release_fraction = std::strtod(argv[8], nullptr);
    if (argc >= 10) p.hold_release_samples = std::atoi(argv[9]);
    if (argc >= 11) p.hold_release_drop = std::strtod(argv[10], nullptr);
    if (argc >= 12) p.hold_level_samples = std::atoi(argv[11]);
    if (argc >= 13) p.max_drift_slope = std::strtod(argv[12], nullptr);
    if (argc >= 15) {
      p.hold_quiet_rms = std::strtod(argv[13], nullptr);
      p.hold_quiet_samples = std::atoi(argv[14]);
    }
    tdorc_filter::TdorcWhisker w(p);
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line.empty()) continue;
      std::array<double, 3> r{};
      std::istringstream is(line);
      char comma = 0;
      if (!(is >> r[0] >> comma >> r[1] >> comma >> r[2])) {
        std::cerr << "bad line: " << line << "\n";
        return 1;
      }
      const auto o = w.update(r);
      std::printf("%d,%d,%d", o.ready ? 1 : 0, o.contact ? 1 : 0, o.drift_frozen ? 1 : 0);
      for (const auto& c : o.channel) std::printf(",%.17g", c.calibrated);
      for (const auto& c : o.channel) std::printf(",%.17g", c.compensated);
      for (const auto& c : o.channel) std::printf(",%d", c.contact ? 1 : 0);
      std::printf("\n");
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
