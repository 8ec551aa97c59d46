// `tactile evaluate BAG --scenario S --out DIR`: the metrics of `tactile sim`
// computed from a bag recorded while the scenario's graph flew elsewhere --
// typically the SITL launch file under ROS 2 (simulator and nodes as rclcpp
// components, talking over DDS). The bag's messages are replayed in time
// order into the same evaluation objects the graph of `tactile sim` uses,
// and metrics.json gets the same keys, so a DDS flight and an in-process
// flight of one scenario and seed compare field by field.
//
// Graphs and the topics their evaluation needs:
//   whisker_fsm (000): /ground_truth/whisker/{left,right}/contact, /fsm_state,
//     /collisions (optional: a bag without it had no collision).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct EvaluateOptions {
  std::string bag;                ///< rosbag2 directory (sqlite3)
  std::string scenario;           ///< the scenario file that was flown
  std::string out_dir;            ///< metrics.json goes here
  std::string config_dir = "config";
  std::optional<uint64_t> seed;   ///< the flight's seed (default: the scenario's); sets the trial's arena rotation
};

/// Evaluates the bag; returns the metrics written to out_dir/metrics.json.
/// Throws std::runtime_error naming the bag or scenario file and the missing
/// topic or unsupported graph.
nlohmann::json run_evaluate(const EvaluateOptions& options);

}  // namespace tactile_cli
