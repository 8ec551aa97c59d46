// `tactile sweep FAMILY|DIR --count N --seed S --out DIR [--jobs N]` (issue
// 17): flies a scenario family over N generated environments (or every
// scenario file of a directory, e.g. one written by `tactile scenarios
// generate`) and writes a table and a summary:
//   OUT/scenarios/<name>.yaml   the generated environments (FAMILY only) + index.json
//   OUT/runs/<name>/            each run (metrics.json, topview.png; its other files,
//                               e.g. trajectory.csv, map.ply, and bag/ kept for
//                               failures only unless --keep-success-files / --keep-bags)
//   OUT/failures/<name>.png     the top view of every failure
//   OUT/table.csv, table.md     per environment: outcome, collisions (guard, body),
//                               the behaviour's metrics
//   OUT/summary.json, summary.md success rate overall and per state estimate,
//                               metric means, failures, date, machine
// Table and summary are rewritten after every environment, so an interrupted
// sweep keeps what it had. `--shard K/M` flies one deterministic share of the
// environments (for a cluster's array job, scripts/slurm/) and `merge_sweep`
// puts the shards back together (issue 36).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct SweepOptions {
  std::string what;        ///< a family name (scenario_family.hpp) or a directory of scenario files
  int count = 10;          ///< environments (family); with a directory: at most this many (0: all)
  uint64_t seed = 1;       ///< first generator seed (family)
  std::string out_dir;
  std::string config_dir;  ///< node parameter files (config/)
  std::vector<std::string> profiles;  ///< parameter profiles (SimOptions::profiles)
  int jobs = 0;            ///< environments flown at once (0: all cores)
  bool write_bags = true;  ///< record bags (kept for failures)
  bool keep_bags = false;  ///< keep the bags of successes too
  bool keep_success_files = false;  ///< keep every file of successes (trajectory, maps), bag aside
  bool progress = true;    ///< one line per environment on stderr
  /// `--shard K/M`: fly only environments i (0-based, in seed or file order) with
  /// i % M == K - 1, and write OUT/shard.json for `tactile sweep merge`. 0/0: all.
  int shard = 0;
  int shards = 0;
};

/// Parses `K/M` (1 <= K <= M <= 100000); throws std::invalid_argument naming the text.
void parse_shard(const std::string& text, int& shard, int& shards);

struct SweepMergeOptions {
  std::string out_dir;
  std::vector<std::string> shard_dirs;  ///< the OUT of each `tactile sweep --shard K/M`
};

/// Runs the sweep; returns the summary (also OUT/summary.json). A scenario
/// that cannot be flown (bad file) is a row with outcome "error: ..." and
/// counts as a failure. Throws on a bad family/directory or unwritable output.
nlohmann::json run_sweep(const SweepOptions& options);

/// `tactile sweep merge --out DIR SHARD_DIR...`: the table, summary, runs/,
/// failures/ and scenarios/ of the whole sweep from its M shards, identical to the
/// single-machine sweep of the same seeds but for timings, date, machine and load.
/// Throws naming the shard directory and the reason when a shard is missing, repeated,
/// interrupted, of another sweep, or its shard.json is unreadable; nothing is written then.
nlohmann::json merge_sweep(const SweepMergeOptions& options);

}  // namespace tactile_cli
