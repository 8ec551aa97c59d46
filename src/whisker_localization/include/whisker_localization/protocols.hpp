// The paper's bench protocols (002 Table I contact estimation, Table II sweep
// localization) on the linear-stage SITL, driven by a scenario YAML
// (config/scenarios/bench/*.yaml) and reported as JSON (metrics.json). Used by
// `whisker_loc_sitl` and `tactile stage`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace whisker_localization {

/// Runs the protocol a scenario file names (`protocol: table1 | table2`).
/// Throws std::runtime_error naming the file, the key and the reason on a bad
/// scenario. `seed` overrides the scenario's seed.
nlohmann::json run_bench_protocol(const std::string& scenario_path, std::optional<uint64_t> seed = std::nullopt);

/// run_bench_protocol, then writes `<out_dir>/metrics.json`.
nlohmann::json run_bench_protocol_to(const std::string& scenario_path, const std::filesystem::path& out_dir,
                                     std::optional<uint64_t> seed = std::nullopt);

}  // namespace whisker_localization
