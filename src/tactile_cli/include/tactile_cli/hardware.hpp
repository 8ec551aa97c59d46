// `tactile fly`, `tactile bench`, `tactile scan`: the standalone host against
// hardware (or the simulated Crazyflie), in wall-clock time.
//
//   fly    whisker pipeline (TDORC x2 -> tactile_depth -> whisker FSM) fed by
//          crazyflie_bridge over a CRTP link (radio://, usb://, udp://), its
//          hover setpoints sent back; every message recorded in a bag.
//   bench  the whisker bench rig: whisker_driver (serial) -> TDORC per whisker,
//          recorded in a bag.
//   scan   Crazyradios, Crazyflies on USB, simulated Crazyflies on UDP.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tactile_cli {

struct FlyOptions {
  std::string uri;              ///< cflib URI; overrides crazyflie_bridge.yaml's uri
  std::string out_dir;
  std::string config_dir;
  std::string scenario;         ///< optional: node_parameters and metrics.target of a scenario
  /// Fly the simulated Crazyflie of this scenario, started in-process on a
  /// free UDP port (real sockets, wall-clock physics); implies `scenario`.
  std::string sim_scenario;
  double sim_loss = 0.0;        ///< injected UDP loss of the simulated Crazyflie (both directions)
  double duration_s = 60.0;     ///< run time from the connect; then the bridge lands (if flying)
  /// Nothing flies without it: take off to takeoff_height (crazyflie_bridge.yaml
  /// or the option below), then hand over to the behaviour. Without it the link
  /// is checked, the sensors recorded and the run ends on the ground.
  bool takeoff = false;
  double takeoff_height = 0.0;  ///< [m]; <= 0: crazyflie_bridge.yaml's takeoff_height
  bool arm = false;             ///< send the arming request before take-off (a Crazyflie that requires arming)
  /// The old take-off-on-connect (bridge autostart: the behaviour flies as soon
  /// as its setpoints and the log are fresh); for SITL tests only.
  bool autostart = false;
  bool write_bag = true;
  bool progress = true;
  /// Keystrokes when stdin is a terminal: t take off (and hand over), l land,
  /// space emergency stop, a arm. Off for library callers; the command turns
  /// it on unless --no-teleop.
  bool teleop = false;
  /// Test seam: called every tick with the host time [ns] and the bridge's
  /// mode (an exception thrown here takes the exception landing path).
  std::function<void(int64_t, const char*)> on_tick;
};
/// Runs until the duration elapsed and the vehicle is on the ground (at most
/// duration + 15 s), or SIGINT / SIGTERM: airborne, the bridge lands first
/// (bounded by shutdown_land_timeout_s, then emergency stop), a second signal
/// stops the motors at once; an exception takes the same landing path (and is
/// rethrown after metrics.json is written). Writes bag/ and metrics.json
/// (end_reason, mode_history, operator commands, final status, link_packets_sent,
/// link_packets_lost, latency, bridge and pipeline counters; with sim_scenario
/// also the simulator's ground-truth summary and collisions). Returns the metrics.
nlohmann::json run_fly(const FlyOptions& options);

struct BenchOptions {
  std::string left_port = "/dev/ttyUSB0";   ///< whisker 1 (text protocol)
  std::string right_port;                   ///< whisker 2 (CSV protocol); empty: left only
  std::string out_dir;
  std::string config_dir;
  double duration_s = 60.0;
  bool write_bag = true;
};
nlohmann::json run_bench(const BenchOptions& options);

/// One line per device found ("uri  description").
std::vector<std::string> run_scan(const std::string& udp_host);

}  // namespace tactile_cli
