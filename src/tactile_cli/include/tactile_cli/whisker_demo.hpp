// `tactile demo`: the whisker signal demo. Records simulated whisker bags
// (whisker_driver with the simulated source, ground truth alongside) in the
// standalone host, then replays each through driver -> TDORC (tactile replay).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct DemoOptions {
  std::string out_dir;
  std::string config_dir;
  uint64_t seed = 1;
  /// Free-flight duration from take-off [s]. 90 s: the duration the signal
  /// model was calibrated on (tactile_sim docs).
  double hover_s = 90.0;
};

/// Records `out_dir/<case>/raw_bag` for the cases "free_flight" (no contact)
/// and "contact" (one contact episode on both whiskers), replays each into
/// `out_dir/<case>/`, and writes `out_dir/summary.json`. Returns the summary.
nlohmann::json run_whisker_demo(const DemoOptions& options);

/// Records one simulated flight into `bag_dir`, from take-off to the end of
/// the hover: whisker_driver (source sim) for both whiskers plus
/// /ground_truth/whisker/<side>/contact. Contact episodes (both whiskers):
/// start times [s after take-off], durations and peak base moments.
void record_sim_whisker_bag(const std::string& bag_dir, const std::string& config_dir, uint64_t seed,
                            double hover_s, const std::vector<double>& contact_start_s,
                            const std::vector<double>& contact_duration_s,
                            const std::vector<double>& contact_peak_nm);

}  // namespace tactile_cli
