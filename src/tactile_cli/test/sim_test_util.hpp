// Shared by the SITL scenario tests: fly a library scenario (config/scenarios)
// with K seeded trials into a private temporary directory, without bag or
// pictures, and return its metrics (the aggregate when K > 1).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

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

/// A library scenario edited for one test (e.g. a shorter duration and a faults: block):
/// each `edits` pair replaces the first occurrence of its first text by its second (a
/// missing text throws, naming it), `append` goes at the end; the arena file is resolved
/// in config/scenarios. One trial from the scenario's seed; returns its metrics.
inline nlohmann::json run_edited_scenario(const std::string& scenario,
                                          std::vector<std::pair<std::string, std::string>> edits,
                                          const std::string& append) {
  namespace fs = std::filesystem;
  const fs::path scenarios = config_dir() / "scenarios";
  std::ifstream in(scenarios / scenario);
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  edits.emplace_back("arena_file: arenas/", "arena_file: " + (scenarios / "arenas").string() + "/");
  for (const auto& [from, to] : edits) {
    const auto at = yaml.find(from);
    if (at == std::string::npos) throw std::runtime_error(scenario + ": no \"" + from + "\" to replace");
    yaml.replace(at, from.size(), to);
  }
  yaml += append;
  const fs::path dir = fs::temp_directory_path() /
                       ("tactile_cli_test_edited_" + fs::path(scenario).stem().string() + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / scenario) << yaml;
  SimOptions o;
  o.scenario = (dir / scenario).string();
  o.out_dir = (dir / "out").string();
  o.config_dir = config_dir().string();
  o.progress = false;
  o.write_bag = false;
  o.write_png = false;
  nlohmann::json m = run_sim(o);
  fs::remove_all(dir);
  return m.contains("per_trial") ? m["per_trial"][0] : m;
}

}  // namespace tactile_cli::test
