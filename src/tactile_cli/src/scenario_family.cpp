#include "tactile_cli/scenario_family.hpp"

#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>

#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

namespace fs = std::filesystem;
using tactile_sim::Vec2;

const ScenarioFamily* find_scenario_family(const std::string& name) {
  for (const auto& f : scenario_families()) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

const ScenarioFamily& scenario_family(const std::string& name) {
  if (const auto* f = find_scenario_family(name)) return *f;
  std::string known;
  for (const auto& f : scenario_families()) known += (known.empty() ? "" : ", ") + f.name;
  throw std::runtime_error("unknown scenario family '" + name + "' (families: " + known + ")");
}

FamilyEnvironment generate_environment(const ScenarioFamily& family, uint64_t seed) {
  std::string last_reason;
  for (int attempt = 0; attempt < family.max_attempts; ++attempt) {
    FamilyDraw d;
    d.seed = seed;
    d.attempt = attempt;
    // One independent stream per (seed, attempt): a rejected draw does not
    // shift the draws of other seeds.
    d.rng.seed(tactile_sim::stream_seed(seed, 0x17000 + static_cast<uint64_t>(attempt)));
    try {
      FamilyEnvironment env = family.draw(d);
      env.seed = seed;
      env.attempts = attempt + 1;
      // The written file must be a valid scenario with a valid arena.
      const auto sc = tactile_sim::load_scenario_from_string(env.yaml, env.name + ".yaml", ".");
      (void)tactile_sim::Arena::from_yaml_text(sc.arena_yaml, sc.arena_source, sc.arena_key);
      return env;
    } catch (const InvalidDraw& e) {
      last_reason = e.what();
    }
  }
  throw std::runtime_error("family " + family.name + ", seed " + std::to_string(seed) + ": no valid draw in " +
                           std::to_string(family.max_attempts) + " attempts (last: " + last_reason + ")");
}

std::vector<std::string> generate_family(const ScenarioFamily& family, int count, uint64_t seed,
                                         const std::string& out_dir, const std::vector<int>& which) {
  if (count < 1) throw std::invalid_argument("--count must be >= 1");
  std::vector<int> ks = which;
  if (ks.empty()) {
    for (int k = 0; k < count; ++k) ks.push_back(k);
  }
  for (size_t i = 0; i < ks.size(); ++i) {
    if (ks[i] < 0 || ks[i] >= count || (i > 0 && ks[i] <= ks[i - 1])) {
      throw std::invalid_argument("generate_family: environment offsets must ascend within [0, count)");
    }
  }
  fs::create_directories(out_dir);
  std::vector<std::string> paths;
  nlohmann::json index;
  index["family"] = family.name;
  index["description"] = family.description;
  index["seed"] = seed;
  index["count"] = count;
  index["environments"] = nlohmann::json::array();
  for (const int k : ks) {
    const uint64_t s = seed + static_cast<uint64_t>(k);
    const FamilyEnvironment env = generate_environment(family, s);
    const fs::path path = fs::path(out_dir) / (env.name + ".yaml");
    std::ofstream out(path);
    if (!out) throw std::runtime_error(path.string() + ": cannot write");
    out << env.yaml;
    if (!out) throw std::runtime_error(path.string() + ": write failed");
    paths.push_back(path.string());
    index["environments"].push_back(
        {{"name", env.name}, {"seed", s}, {"file", env.name + ".yaml"}, {"attempts", env.attempts}, {"drawn", env.drawn}});
  }
  std::ofstream idx(fs::path(out_dir) / "index.json");
  idx << index.dump(2) << "\n";
  if (!idx) throw std::runtime_error((fs::path(out_dir) / "index.json").string() + ": write failed");
  return paths;
}

double clearance_at(const tactile_sim::Arena& arena, const Vec2& p, double max_dist) {
  const auto h = arena.closest(p, max_dist);
  return h.hit ? h.distance : std::numeric_limits<double>::infinity();
}

bool disc_path_exists(const tactile_sim::Arena& arena, const Vec2& start, const Vec2& goal, double clearance,
                      const Vec2& lo, const Vec2& hi, double cell) {
  const int nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)) + 1;
  const int ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)) + 1;
  if (nx <= 0 || ny <= 0) return false;
  auto cell_of = [&](const Vec2& p, int& i, int& j) {
    i = static_cast<int>(std::lround((p.x() - lo.x()) / cell));
    j = static_cast<int>(std::lround((p.y() - lo.y()) / cell));
    return i >= 0 && j >= 0 && i < nx && j < ny;
  };
  // free[i,j]: -1 unknown, 0 blocked, 1 free (evaluated lazily).
  std::vector<signed char> state(static_cast<size_t>(nx) * static_cast<size_t>(ny), -1);
  std::vector<char> seen(state.size(), 0);
  auto is_free = [&](int i, int j) {
    auto& s = state[static_cast<size_t>(j) * nx + i];
    if (s < 0) {
      const Vec2 p(lo.x() + i * cell, lo.y() + j * cell);
      const auto h = arena.closest(p, clearance);
      // Also inside a cylinder (negative distance) counts as blocked.
      s = (h.hit && h.distance < clearance) ? 0 : 1;
    }
    return s == 1;
  };
  int si, sj, gi, gj;
  if (!cell_of(start, si, sj) || !cell_of(goal, gi, gj)) return false;
  if (!is_free(si, sj) || !is_free(gi, gj)) return false;
  std::deque<std::pair<int, int>> queue{{si, sj}};
  seen[static_cast<size_t>(sj) * nx + si] = 1;
  while (!queue.empty()) {
    const auto [i, j] = queue.front();
    queue.pop_front();
    if (i == gi && j == gj) return true;
    for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= nx || b >= ny) continue;
      auto& sn = seen[static_cast<size_t>(b) * nx + a];
      if (sn || !is_free(a, b)) continue;
      sn = 1;
      queue.emplace_back(a, b);
    }
  }
  return false;
}

std::string yaml_num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  // "-0.0000" -> "0.0000"
  bool zero = true;
  for (char c : s) {
    if (c != '-' && c != '0' && c != '.') zero = false;
  }
  if (zero && !s.empty() && s[0] == '-') s.erase(0, 1);
  return s;
}

}  // namespace tactile_cli
