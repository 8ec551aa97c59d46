// Scenario files of the SITL (schema: docs/sitl_design.md and
// config/scenarios/README.md): arena, vehicle, pilot script, faults, trials.
// Core layer: no ROS, no messages.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/parameters.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_sim {

/// Error in a scenario file: "<file>: <key.path>: <reason>".
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class VehicleType { kWhiskerCrazyflie, kXplorer, kDuctedQuadrotor, kWhiskerStage };
const char* to_string(VehicleType type);

/// One step of the scenario pilot's script.
struct PilotStep {
  enum class Kind { kTakeoff, kHover, kVelocity, kPosition, kLand };
  Kind kind = Kind::kHover;
  double height = std::numeric_limits<double>::quiet_NaN();   ///< takeoff: target height [m]
  double duration_s = std::numeric_limits<double>::infinity(); ///< time in this step
  Vec2 velocity = Vec2::Zero();  ///< velocity: body-yaw frame (vx forward, vy left) [m/s]
  double yaw_rate = 0.0;         ///< velocity: [rad/s]
  Vec3 position = Vec3::Zero();  ///< position: world [m]
  double yaw = 0.0;              ///< position: [rad]
  /// End condition besides the duration: "" (none), "contact" (a whisker
  /// signal over threshold, or any collision/arm contact for the other vehicles).
  std::string until;
  double timeout_s = std::numeric_limits<double>::infinity();  ///< with `until`: give up after
};

/// Bounds of a scenario's numbers (our choice: a run must neither hang nor overflow the
/// simulator's int64 nanosecond clock): one simulated day, 20 kHz physics (the shipped
/// scenarios use 1-2 kHz), and fault channel indices below 256 (SimLogic then checks the
/// topic's own channel count).
inline constexpr double kMaxDurationS = 86400.0;
inline constexpr double kMaxPhysicsRateHz = 20000.0;
inline constexpr uint64_t kMaxFaultChannel = 255;

/// A fault injected on one topic (applied by the simulator node to its outputs).
struct FaultSpec {
  enum class Type { kDropout, kNan, kOutOfRange, kStuck, kSpike, kLatency, kLoss };
  Type type = Type::kLoss;
  std::string topic;           ///< relative, as the simulator publishes it ("whisker/left/pressure")
  int channel = -1;            ///< -1: every channel of the message
  double start_s = 0.0;
  double duration_s = std::numeric_limits<double>::infinity();
  double probability = 1.0;    ///< per message
  double magnitude = 0.0;      ///< spike size (in the channel's unit)
  double delay_s = 0.0;        ///< latency
};
const char* to_string(FaultSpec::Type type);

struct Scenario {
  std::string name;
  std::string description;
  std::string source;          ///< path of the scenario file (for messages)
  double duration_s = 10.0;
  double physics_rate_hz = 1000.0;
  uint64_t seed = 1;

  // Arena: YAML text of the arena map and where it came from (for errors and
  // relative paths); parsed by Arena::from_yaml_text.
  std::string arena_yaml;
  std::string arena_source;
  std::string arena_key;       ///< key path of the arena in its file ("arena" or "")
  double arena_x = 0.0, arena_y = 0.0, arena_yaw = 0.0;  ///< extra transform [m, m, rad]
  std::optional<std::pair<double, double>> randomize_arena_yaw;  ///< [rad], per trial

  VehicleType vehicle = VehicleType::kWhiskerCrazyflie;
  Vec3 initial_position = Vec3::Zero();
  double initial_yaw = 0.0;    ///< [rad]
  std::string state_estimate = "mocap";  ///< whisker_crazyflie: mocap | flow_deck
  /// Overrides of the vehicle's parameters by field name.
  std::map<std::string, tactile_common::ParamValue> vehicle_params;

  /// Node graph around the simulator, by name (pilot = the scenario pilot
  /// below; the others are defined by `tactile sim`'s graph registry).
  std::string graph = "pilot";
  std::vector<PilotStep> pilot;
  std::vector<FaultSpec> faults;
  /// Parameter overrides of the nodes of the graph, by node name (e.g.
  /// whisker_fsm: {t_max: 0.105}), applied over config/<node>.yaml like a
  /// launch file's per-node parameters.
  std::map<std::string, std::map<std::string, tactile_common::ParamValue>> node_parameters;
  /// Per-scenario metric settings (interpreted by later behaviours).
  std::map<std::string, tactile_common::ParamValue> metrics;
};

/// Reads and validates a scenario file. An arena_file is resolved relative
/// to the scenario file. Unknown keys, wrong types and bad values throw
/// ScenarioError naming the file, the key path and the reason.
Scenario load_scenario(const std::string& path);
Scenario load_scenario_from_string(const std::string& yaml, const std::string& source,
                                   const std::string& base_dir);

}  // namespace tactile_sim
