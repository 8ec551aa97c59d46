// `tactile sim SCENARIO.yaml --out DIR [--seed N] [--trials K]`: flies a
// scenario of the SITL with the node graph it names and writes the bag,
// trajectory.csv, metrics.json and a top-view PNG; K seeded trials are
// aggregated (mean, std, success count); they run on `jobs` worker threads
// (parallel.hpp) with the outputs of a serial run.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct SimOptions {
  std::string scenario;                 ///< scenario file
  std::string out_dir;
  std::string config_dir;               ///< node parameter files (config/)
  /// Parameter profiles (<config_dir>/profiles/<name>.yaml) after the nodes' files, in
  /// order, after the graph's own (gpis_explore: exploration); Host::use_profile.
  std::vector<std::string> profiles;
  std::optional<uint64_t> seed;         ///< default: the scenario's seed
  int trials = 1;                       ///< > 1: out_dir/trial_<k>/ per trial + aggregate
  int jobs = 0;                         ///< trials run at once (parallel.hpp); 0: all cores
  bool progress = true;                 ///< progress line on stderr
  bool write_bag = true;
  bool write_png = true;
};

/// Runs the scenario; returns the metrics written to out_dir/metrics.json
/// (one run) or the aggregate (trials > 1). Throws with file/key/reason on a
/// bad scenario or configuration.
nlohmann::json run_sim(const SimOptions& options);

}  // namespace tactile_cli
