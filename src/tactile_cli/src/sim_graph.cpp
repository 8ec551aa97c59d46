#include "tactile_cli/sim_graph.hpp"

#include <cmath>
#include <stdexcept>
#include <variant>

namespace tactile_cli {

tactile_common::ParamMap GraphContext::overrides(const std::string& node, const tactile_common::ParamMap& extra) const {
  tactile_common::ParamMap m(node, scenario.source + " (node_parameters." + node + ")");
  if (auto it = scenario.node_parameters.find(node); it != scenario.node_parameters.end()) {
    for (const auto& [k, v] : it->second) m.set(k, v);
  }
  for (const auto& [k, v] : extra.values()) m.set(k, v);
  return m;
}

tactile_sim::Vec2 GraphContext::arena_to_world(const tactile_sim::Vec2& p) const {
  const double c0 = std::cos(arena_yaw), s0 = std::sin(arena_yaw);
  const tactile_sim::Vec2 t(c0 * p.x() - s0 * p.y(), s0 * p.x() + c0 * p.y());
  const double c1 = std::cos(scenario.arena_yaw), s1 = std::sin(scenario.arena_yaw);
  return {c1 * t.x() - s1 * t.y() + scenario.arena_x, s1 * t.x() + c1 * t.y() + scenario.arena_y};
}

std::optional<tactile_sim::Vec2> GraphContext::target(const char* key) const {
  auto it = scenario.metrics.find(key);
  if (it == scenario.metrics.end()) return std::nullopt;
  const auto* xy = std::get_if<std::vector<double>>(&it->second);
  if (!xy || xy->size() != 2) throw std::runtime_error(scenario.source + ": metrics." + key + ": expected [x, y]");
  return arena_to_world(tactile_sim::Vec2((*xy)[0], (*xy)[1]));
}

bool GraphContext::flag(const char* key) const {
  auto it = scenario.metrics.find(key);
  if (it == scenario.metrics.end()) return false;
  const bool* b = std::get_if<bool>(&it->second);
  if (!b) throw std::runtime_error(scenario.source + ": metrics." + key + ": expected true or false");
  return *b;
}

}  // namespace tactile_cli
