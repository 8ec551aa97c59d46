// Procedural scenario families (issue 17): seeded draws of environments from
// documented distributions, validated and written out as standalone scenario
// files that `tactile sim` flies alone. `tactile scenarios generate FAMILY
// --count N --seed S --out DIR` writes them; `tactile sweep` flies them.
//
// One registry entry per family (src/families/families.cpp lists them; each
// family lives in its own file src/families/<name>.cpp). Environment k of a
// generation is drawn from seed S + k alone, so `--seed 5012 --count 1`
// redraws exactly the 13th environment of `--seed 5000`.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_cli {

/// A drawn environment does not satisfy its family's validity rules; the
/// generator draws again (next attempt) on this error.
class InvalidDraw : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One drawn, validated environment.
struct FamilyEnvironment {
  std::string name;       ///< scenario name, e.g. "baffles_5003" (also the file stem)
  uint64_t seed = 0;      ///< generator seed (also the scenario's simulation seed)
  int attempts = 1;       ///< draws until one was valid (rejections = attempts - 1)
  std::string yaml;       ///< the complete scenario file (inline arena)
  nlohmann::json drawn;   ///< the drawn parameters (also written as comments in the file)
};

/// What a family's draw function gets: its random source for this attempt.
struct FamilyDraw {
  uint64_t seed = 0;
  int attempt = 0;
  std::mt19937_64 rng;
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  int uniform_int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v.at(static_cast<size_t>(uniform_int(0, static_cast<int>(v.size()) - 1))); }
};

struct ScenarioFamily {
  std::string name;          ///< FAMILY argument, e.g. "baffles"
  std::string description;   ///< one line
  std::string distribution;  ///< the documented distribution and validity rules (printed by `scenarios list`)
  /// metrics.json paths (e.g. "fsm.depth_in_band_fraction") that the sweep
  /// table lists per environment and the summary averages.
  std::vector<std::string> table_metrics;
  /// Draws one environment for `draw` (seed, attempt, rng) and returns it with
  /// `yaml` and `drawn` filled; throws InvalidDraw when the draw breaks a
  /// validity rule (the caller draws again, up to max_attempts).
  std::function<FamilyEnvironment(FamilyDraw&)> draw;
  int max_attempts = 200;
};

/// Every registered family (src/families/families.cpp).
const std::vector<ScenarioFamily>& scenario_families();
/// The family named `name`; nullptr if there is none.
const ScenarioFamily* find_scenario_family(const std::string& name);
/// Same, throwing with the list of known families.
const ScenarioFamily& scenario_family(const std::string& name);

/// Draws environment `seed` of `family` (attempts 0, 1, ... until one is
/// valid) and checks that the written scenario loads (scenario schema and
/// arena validation). Throws std::runtime_error naming family, seed and the
/// last rejection reason if no attempt is valid.
FamilyEnvironment generate_environment(const ScenarioFamily& family, uint64_t seed);

/// Generates environments seed .. seed + count - 1 into out_dir as
/// <name>.yaml plus index.json (family, seeds, drawn parameters, attempts);
/// returns the written scenario paths in seed order. With `which` (offsets k in
/// [0, count), ascending: a sweep shard's share), only environments seed + k of
/// those k; index.json still says `count` and lists the ones written.
std::vector<std::string> generate_family(const ScenarioFamily& family, int count, uint64_t seed,
                                         const std::string& out_dir, const std::vector<int>& which = {});

// --- helpers for the families' validity rules ------------------------------

/// A free path for a disc of radius `clearance` from `start` to `goal` inside
/// the box [lo, hi] (grid search, cells of `cell` metres; obstacles are every
/// wall and cylinder of the arena).
bool disc_path_exists(const tactile_sim::Arena& arena, const tactile_sim::Vec2& start,
                      const tactile_sim::Vec2& goal, double clearance, const tactile_sim::Vec2& lo,
                      const tactile_sim::Vec2& hi, double cell = 0.02);

/// Distance from p to the nearest surface of the arena (infinity if empty
/// within max_dist).
double clearance_at(const tactile_sim::Arena& arena, const tactile_sim::Vec2& p, double max_dist = 10.0);

/// Number formatting for the written YAML (fixed, 4 decimals, no "-0.0000").
std::string yaml_num(double v, int decimals = 4);

}  // namespace tactile_cli
