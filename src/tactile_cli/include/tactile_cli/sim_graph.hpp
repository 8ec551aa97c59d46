// The node graphs `tactile sim` can fly around the simulator, one registry
// entry per graph (`graph:` key of a scenario). Each graph lives in its own
// file src/graphs/<name>.cpp and is listed once in src/graphs/graphs.cpp.
//
// A graph adds the nodes of one behaviour to the standalone host (the same
// nodes, topics and parameters its launch file starts under ROS 2), runs with
// the simulator, then reports its own metrics and outputs.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactile_cli/host.hpp"
#include "tactile_cli/topview.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

class WhiskerTruth;

/// What a graph factory gets: the scenario, the host with the simulator
/// already on it, and the trial.
struct GraphContext {
  const tactile_sim::Scenario& scenario;
  Host& host;
  std::shared_ptr<tactile_sim::SimLogic> sim;
  uint64_t seed = 0;
  double arena_yaw = 0.0;          ///< the trial's random arena rotation [rad] (0 unless randomized)
  std::filesystem::path out_dir;   ///< where this run writes its files
  WhiskerTruth* whisker_truth = nullptr;  ///< whisker ground truth by stamp (whiskered Crazyflie only)

  /// Parameters of node `node`: the scenario's node_parameters.<node> plus
  /// `extra` (extra wins); errors name the scenario file.
  tactile_common::ParamMap overrides(const std::string& node, const tactile_common::ParamMap& extra = {}) const;
  /// A point given in the scenario's arena frame (e.g. metrics.target) in the
  /// world frame: the trial rotation, then the arena transform.
  tactile_sim::Vec2 arena_to_world(const tactile_sim::Vec2& p) const;
  /// scenario.metrics.<key> as [x, y] in the world frame, if present
  /// (throws naming the scenario file if it is not a pair of numbers).
  std::optional<tactile_sim::Vec2> target(const char* key = "target") const;
  /// scenario.metrics.<key> as a boolean (false if absent; throws if not a bool).
  bool flag(const char* key) const;
};

/// A graph instance for one run.
class SimGraph {
 public:
  virtual ~SimGraph() = default;
  /// The graph's metrics, written to metrics.json under GraphInfo::metrics_key
  /// (nothing if null).
  virtual nlohmann::json metrics() const { return nullptr; }
  /// Whether the behaviour reached its goal (target, script finished);
  /// nullopt when the graph has no goal. A run succeeds when the goal is
  /// reached (or there is none) and nothing collided (unless the scenario
  /// allows collisions).
  virtual std::optional<bool> reached_goal() const { return std::nullopt; }
  /// Adds the graph's own layers to the top view (targets, maps, ...).
  virtual void decorate(TopView& /*view*/) const {}
  /// Writes the graph's own files (maps, pictures) into the run directory.
  virtual void write_outputs(const std::filesystem::path& /*dir*/) const {}
};

struct GraphInfo {
  std::string name;                                ///< the scenario's `graph:` value
  std::string description;                         ///< one line for errors and docs
  std::vector<tactile_sim::VehicleType> vehicles;  ///< vehicles it can fly (empty: any)
  std::vector<std::string> nodes;                  ///< node names accepted under node_parameters
  std::string metrics_key;                         ///< key of SimGraph::metrics() in metrics.json
  /// Metrics (paths like "gpis.travel_distance_m") whose mean and std over the
  /// trials the aggregate metrics.json also reports at the top level as
  /// mean_<leaf> and std_<leaf> (the names the papers' tables use).
  std::vector<std::string> summary_metrics;
  std::function<std::unique_ptr<SimGraph>(GraphContext&)> build;
};

/// Every graph of `tactile sim` (src/graphs/graphs.cpp).
const std::vector<GraphInfo>& sim_graphs();
/// The graph named `name`; throws naming the scenario file and the known graphs.
const GraphInfo& find_sim_graph(const std::string& name, const std::string& source);

}  // namespace tactile_cli
