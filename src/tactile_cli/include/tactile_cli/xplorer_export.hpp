// `tactile export BAG --ply FILE`: rebuild the XPLORER contact map (paper 001
// Sec. IV-B) from a recorded bag (real or SITL) without flying, and write it
// as PLY. Uses the recorded body wrench (/xplorer/wrench_body) when the bag
// has it, otherwise re-runs xplorer_force_est on the arm IMUs, the IMU and
// the thrust command. Needs /odom.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct ExportOptions {
  std::string bag;              ///< rosbag2 directory
  std::string ply;              ///< output PLY file
  bool binary = false;          ///< binary little endian instead of ASCII
  std::string config_dir = "config";
  /// Where the summary goes as JSON (with its `warnings`): --metrics, default
  /// <ply without .ply>.metrics.json beside the map.
  std::string metrics;
};

/// Returns a summary (messages used, source of the wrench, points, map
/// dimensions). Throws std::runtime_error naming the bag and the missing topic.
nlohmann::json run_export(const ExportOptions& options);

}  // namespace tactile_cli
