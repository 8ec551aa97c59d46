// Shared by the SITL scenario tests: fly a library scenario (config/scenarios)
// with K seeded trials into a private temporary directory, without bag or
// pictures, and return its metrics (the aggregate when K > 1).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "tactile_cli/sim_run.hpp"

namespace tactile_cli::test {

inline const std::filesystem::path& config_dir() {
  static const std::filesystem::path dir = TACTILE_CONFIG_DIR;
  return dir;
}

/// `scenario` is a file name in config/scenarios; `seed`: first seed (default: the scenario's).
inline nlohmann::json run_scenario(const std::string& scenario, int trials = 1,
                                   std::optional<uint64_t> seed = std::nullopt) {
  namespace fs = std::filesystem;
  const fs::path out = fs::temp_directory_path() /
                       ("tactile_cli_test_" + fs::path(scenario).stem().string() + "_" + std::to_string(::getpid()));
  fs::remove_all(out);
  SimOptions o;
  o.scenario = (config_dir() / "scenarios" / scenario).string();
  o.out_dir = out.string();
  o.config_dir = config_dir().string();
  o.seed = seed;
  o.trials = trials;
  o.progress = false;
  o.write_bag = false;
  o.write_png = false;
  nlohmann::json m = run_sim(o);
  fs::remove_all(out);
  return m;
}

}  // namespace tactile_cli::test
