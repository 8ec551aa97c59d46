#include "whisker_localization/protocols.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "whisker_localization/stage_sim.hpp"

namespace whisker_localization {

using nlohmann::json;

namespace {

struct Reader {
  std::string file;
  YAML::Node root;
  double num(const YAML::Node& n, const std::string& path, double def) const {
    if (!n || n.IsNull()) return def;
    try {
      return n.as<double>();
    } catch (const YAML::Exception&) {
      throw std::runtime_error(file + ": " + path + ": must be a number");
    }
  }
  /// Refuses a key the protocol does not read (`trails: 2` was ignored and the run used the
  /// default trials): the file, the key path and the keys allowed.
  void allow_only(const YAML::Node& n, const std::string& path, std::initializer_list<const char*> keys) const {
    if (!n || n.IsNull()) return;
    const std::string where = path.empty() ? "(top level)" : path;
    if (!n.IsMap()) throw std::runtime_error(file + ": " + where + ": expected a map");
    for (const auto& kv : n) {
      const std::string k = kv.first.as<std::string>();
      if (std::find_if(keys.begin(), keys.end(), [&](const char* a) { return k == a; }) == keys.end()) {
        std::string list;
        for (const char* a : keys) list += (list.empty() ? "" : ", ") + std::string(a);
        throw std::runtime_error(file + ": " + (path.empty() ? k : path + "." + k) + ": unknown key (allowed: " +
                                 list + ")");
      }
    }
  }
  /// A whole number in [lo, hi] (a count or a seed): "2.5", "1e3", "-1" for a seed or
  /// a value out of range stop with the file, the key and the value as written, never
  /// truncated or wrapped into range.
  template <class T>
  T integer(const YAML::Node& n, const std::string& path, T def, T lo, T hi) const {
    if (!n || n.IsNull()) return def;
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!n.IsScalar()) throw std::runtime_error(file + ": " + path + ": must be an integer in " + range);
    const std::string& text = n.Scalar();
    T v{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec == std::errc::result_out_of_range || (ec == std::errc() && end == text.data() + text.size() && (v < lo || v > hi))) {
      throw std::runtime_error(file + ": " + path + ": must be in " + range + ", got " + text);
    }
    if (ec != std::errc() || end != text.data() + text.size()) {
      throw std::runtime_error(file + ": " + path + ": must be an integer in " + range + ", got \"" + text + "\"");
    }
    return v;
  }
  std::vector<double> nums(const YAML::Node& n, const std::string& path, const std::vector<double>& def,
                           double scale) const {
    if (!n || n.IsNull()) return def;
    if (!n.IsSequence()) throw std::runtime_error(file + ": " + path + ": must be a list of numbers");
    std::vector<double> v;
    for (std::size_t i = 0; i < n.size(); ++i) v.push_back(num(n[i], path + "[" + std::to_string(i) + "]", 0.0) * scale);
    return v;
  }
  bool flag(const YAML::Node& n, const std::string& path, bool def) const {
    if (!n || n.IsNull()) return def;
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      throw std::runtime_error(file + ": " + path + ": must be true or false");
    }
  }
};

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

json run_bench_protocol(const std::string& scenario_path, std::optional<uint64_t> seed) {
  Reader r{scenario_path, {}};
  try {
    r.root = YAML::LoadFile(scenario_path);
  } catch (const std::exception& e) {
    throw std::runtime_error(scenario_path + ": cannot read scenario: " + e.what());
  }
  r.allow_only(r.root, "", {"name", "description", "protocol", "seed", "noise", "table1", "table2"});
  r.allow_only(r.root["noise"], "noise", {"relative", "absolute", "bounded"});
  r.allow_only(r.root["table1"], "table1", {"contacts_mm", "displacements_mm", "trials"});
  r.allow_only(r.root["table2"], "table2", {"sweep_starts_mm", "steps", "step_mm", "fillet_radius_mm", "attack_deg",
                                            "penetration_mm", "compare_possibilistic"});
  std::string protocol;
  try {
    protocol = r.root["protocol"] ? r.root["protocol"].as<std::string>() : "";
  } catch (const YAML::Exception&) {
    throw std::runtime_error(scenario_path + ": protocol: must be \"table1\" or \"table2\"");
  }
  const uint64_t seed_value =
      seed ? *seed : r.integer<uint64_t>(r.root["seed"], "seed", 1, 0, std::numeric_limits<uint64_t>::max());
  MomentNoise noise;
  const YAML::Node nz = r.root["noise"];
  noise.relative = r.num(nz ? nz["relative"] : YAML::Node(), "noise.relative", noise.relative);
  noise.absolute = r.num(nz ? nz["absolute"] : YAML::Node(), "noise.absolute", noise.absolute);
  json m;
  m["scenario"] = r.root["name"] ? r.root["name"].as<std::string>() : scenario_path;
  m["protocol"] = protocol;
  m["seed"] = seed_value;
  if (protocol == "table1") {
    Table1Params p;
    p.noise = noise;
    p.seed = seed_value;
    const YAML::Node t = r.root["table1"];
    p.contacts = r.nums(t ? t["contacts_mm"] : YAML::Node(), "table1.contacts_mm", p.contacts, 1e-3);
    p.displacements = r.nums(t ? t["displacements_mm"] : YAML::Node(), "table1.displacements_mm", p.displacements, 1e-3);
    p.trials = r.integer<int>(t ? t["trials"] : YAML::Node(), "table1.trials", p.trials, 1, std::numeric_limits<int>::max());
    json rows = json::array();
    for (const auto& row : run_table1(p)) {
      rows.push_back({{"p_x_mm", row.p_x * 1e3},
                      {"t_y_mm", row.t_y * 1e3},
                      {"m0_mNm", row.m0 * 1e3},
                      {"phi_a_rad", row.phi_a},
                      {"ours_distance_mm", number(row.ours_mean * 1e3)},
                      {"ours_error_pct", number(row.ours_error_pct)},
                      {"baseline_distance_mm", row.baseline_mean * 1e3},
                      {"baseline_error_pct", row.baseline_error_pct},
                      {"ours_failures", row.ours_failures}});
    }
    m["whisker_localization"] = {{"table1", rows}, {"trials", p.trials}, {"noise_relative", noise.relative},
                                 {"noise_absolute_Nm", noise.absolute}};
  } else if (protocol == "table2") {
    Table2Params p;
    p.noise = noise;
    p.seed = seed_value;
    p.bounded_noise = r.flag(nz ? nz["bounded"] : YAML::Node(), "noise.bounded", false);
    const YAML::Node t = r.root["table2"];
    p.sweep_starts = r.nums(t ? t["sweep_starts_mm"] : YAML::Node(), "table2.sweep_starts_mm", p.sweep_starts, 1e-3);
    p.steps = r.integer<int>(t ? t["steps"] : YAML::Node(), "table2.steps", p.steps, 4, std::numeric_limits<int>::max());
    p.step = r.num(t ? t["step_mm"] : YAML::Node(), "table2.step_mm", p.step * 1e3) * 1e-3;
    p.fillet_radius = r.num(t ? t["fillet_radius_mm"] : YAML::Node(), "table2.fillet_radius_mm", p.fillet_radius * 1e3) * 1e-3;
    p.attack_deg = r.num(t ? t["attack_deg"] : YAML::Node(), "table2.attack_deg", p.attack_deg);
    p.penetration = r.num(t ? t["penetration_mm"] : YAML::Node(), "table2.penetration_mm", p.penetration * 1e3) * 1e-3;
    json variants = json::object();
    const bool both = r.flag(t ? t["compare_possibilistic"] : YAML::Node(), "table2.compare_possibilistic", true);
    for (bool poss : {false, true}) {
      if (poss && !both) break;
      p.localizer.possibilistic = poss;
      json sweeps = json::array();
      double mean = 0.0;
      const auto rows = run_table2(p);
      for (const auto& s : rows) {
        sweeps.push_back({{"sweep_id", s.id},
                          {"mean_localization_error_mm", number(s.mean_error_mm)},
                          {"std_localization_error_mm", number(s.std_error_mm)},
                          {"localized_steps", s.localized_steps},
                          {"localizing_steps", s.localizing_steps},
                          {"localized_mean_error_mm", number(s.localized_mean_error_mm)},
                          {"final_error_mm", number(s.final_error_mm)},
                          {"final_spread_mm", number(s.final_spread_mm)},
                          {"final_set_size", s.final_set_size},
                          {"truth_kept_fraction", s.truth_kept_fraction},
                          {"resets", s.resets},
                          {"contact_failures", s.contact_failures},
                          {"profile_points", s.profile_points},
                          {"profile_mean_error_mm", s.profile_mean_error_mm},
                          {"profile_max_error_mm", s.profile_max_error_mm}});
        mean += s.mean_error_mm / static_cast<double>(rows.size());
      }
      variants[poss ? "possibilistic" : "deterministic"] = {{"sweeps", sweeps},
                                                            {"mean_localization_error_mm", number(mean)}};
    }
    m["whisker_localization"] = {{"table2", variants},
                                 {"noise_relative", noise.relative},
                                 {"noise_bounded", p.bounded_noise},
                                 {"epsilon", p.localizer.epsilon}};
  } else {
    throw std::runtime_error(scenario_path + ": protocol: must be \"table1\" or \"table2\", got \"" + protocol + "\"");
  }
  return m;
}

json run_bench_protocol_to(const std::string& scenario_path, const std::filesystem::path& out_dir,
                           std::optional<uint64_t> seed) {
  json m = run_bench_protocol(scenario_path, seed);
  std::filesystem::create_directories(out_dir);
  std::ofstream f(out_dir / "metrics.json");
  f << m.dump(2) << "\n";
  if (!f) throw std::runtime_error((out_dir / "metrics.json").string() + ": cannot write");
  return m;
}

}  // namespace whisker_localization
