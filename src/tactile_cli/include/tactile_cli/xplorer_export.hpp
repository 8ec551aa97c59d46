// `tactile export BAG --ply FILE`: rebuild the XPLORER contact map (paper 001
// Sec. IV-B) from a recorded bag (real or SITL) without flying, and write it
// as PLY. Uses the recorded body wrench (/xplorer/wrench_body) when the bag
// has it, otherwise re-runs xplorer_force_est on the arm IMUs, the IMU and
// the thrust command. Needs /odom.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct ExportOptions {
  std::string bag;              ///< rosbag2 directory
  std::string ply;              ///< output PLY file
  bool binary = false;          ///< binary little endian instead of ASCII
  std::string config_dir = "config";
  /// The vehicle's namespace in the bag (--namespace): "" reads the root names the host
  /// records (/odom, /xplorer/wrench_body); "cf1" reads /cf1/odom, ... (a bag of a launch
  /// with namespace:=cf1), and the map's frame is cf1/<frame_id>, as that launch's frame
  /// prefix defaults to cf1/.
  std::string ns;
  /// Where the summary goes as JSON (with its `warnings`): --metrics, default
  /// <ply without .ply>.metrics.json beside the map.
  std::string metrics;
  /// The clock the messages are replayed on (--time):
  ///  - kHeader (default): each message's header stamp, in stamp order. The data's own
  ///    time: a `ros2 bag record` stores receive times, which lag the stamps by the
  ///    recorder's delay (1-6 ms on /clock in SITL) and can swap messages of different
  ///    topics; replayed at the stamps the map is the one the live mapper built.
  ///    Messages are held in a reorder window of kReorderWindowNs of bag time; equal
  ///    stamps keep the bag's order; one whose stamp is older than what was already
  ///    replayed (more than the window late) is replayed at the newest time replayed so
  ///    far; one stamped more than kMaxStampSkewNs from its bag timestamp (unset, another
  ///    clock, corrupt) at its bag timestamp: both counted as warnings. So a message is
  ///    held at most kMaxStampSkewNs + kReorderWindowNs of bag time.
  ///  - kReceive: the bag's timestamps, in bag order (this workspace's own bags store
  ///    the publish time, equal to the stamps).
  enum class Time { kHeader, kReceive };
  Time time = Time::kHeader;
  static constexpr int64_t kReorderWindowNs = 500'000'000;
  static constexpr int64_t kMaxStampSkewNs = 5'000'000'000;
};

/// Returns a summary (messages used, source of the wrench, points, map
/// dimensions). Throws std::runtime_error naming the bag and the missing topic.
nlohmann::json run_export(const ExportOptions& options);

}  // namespace tactile_cli
