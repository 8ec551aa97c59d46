// Node instances in the standalone host, one function per node, each the
// counterpart of that node's rclcpp component: same node name, namespace,
// topics (the logic's constants), parameters (config/<node>.yaml + overrides).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"
#include "tactile_sim/logic/pilot_logic.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"
#include "tactile_fsm/wall_effect_nav_logic.hpp"
#include "wall_effect_ekf/indi_control_logic.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"

namespace tactile_cli {

/// whisker_driver in namespace `ns`: a timer at rate_hz publishing on <ns>/pressure.
std::shared_ptr<whisker_driver::WhiskerDriverLogic> add_whisker_driver(
    Host& host, const std::string& ns, const tactile_common::ParamMap& overrides);

/// tdorc_filter in namespace `ns`: <ns>/pressure -> <ns>/signal.
std::shared_ptr<tdorc_filter::TdorcFilterLogic> add_tdorc_filter(
    Host& host, const std::string& ns, const tactile_common::ParamMap& overrides);

/// The whisker front end of the whiskered Crazyflie's graphs (launch/sitl_whisker.launch.py,
/// sitl_explore.launch.py and radio.launch.py compose the same): tdorc_filter in whisker/left and whisker/right, both with
/// `tdorc_overrides`, then tactile_depth with `*depth_overrides` (none without them: a
/// graph that needs the compensated signals only, e.g. the scripted pilot's `until: contact`).
struct WhiskerFrontEnd {
  std::shared_ptr<tdorc_filter::TdorcFilterLogic> left;
  std::shared_ptr<tdorc_filter::TdorcFilterLogic> right;
  std::shared_ptr<tactile_depth::TactileDepthLogic> depth;  ///< null without depth_overrides
};
WhiskerFrontEnd add_whisker_front_end(Host& host, const tactile_common::ParamMap& tdorc_overrides,
                                      const std::optional<tactile_common::ParamMap>& depth_overrides);

/// tactile_depth: /whisker/{left,right}/signal + /odom -> `output_topic`
/// (the node's own /whisker/depth unless an evaluator renames it).
std::shared_ptr<tactile_depth::TactileDepthLogic> add_tactile_depth(
    Host& host, const tactile_common::ParamMap& overrides,
    const std::string& output_topic = tactile_depth::TactileDepthLogic::kOutputTopic);

/// whisker_fsm: /whisker/depth, /whisker/*/signal, /odom -> /cmd_hover, /fsm_state.
///  - Without `arrival_clock` (the simulated hosts): a 50 Hz timer steps it. The
///    simulator's timer fires first at each tick, so the step sees the depth of that
///    tick's pressure: no timer phase in simulated time, and the order of a run is fixed.
///  - With it (real-time hosts: `tactile fly`): event driven like the rclcpp component
///    (tactile_common/event_tick.hpp): it steps when a TactileDepth arrives, at
///    arrival_clock(), and the 50 Hz timer is the watchdog that steps it once depth stops.
std::shared_ptr<tactile_fsm::WhiskerFsmLogic> add_whisker_fsm(Host& host, const tactile_common::ParamMap& overrides,
                                                               std::function<int64_t()> arrival_clock = {});

/// gpis_explorer: /whisker/depth, /odom -> /cmd_hover, /fsm_state at 50 Hz,
/// /gpis/map and /gpis/target after every GPIS update.
std::shared_ptr<gpis_explorer::GpisExplorerLogic> add_gpis_explorer(Host& host,
                                                                   const tactile_common::ParamMap& overrides);

/// whisker_localization (002): /whisker/base_wrench + /odom -> /whisker/localization
/// (LocalizationResult) and /whisker/pose_set (PoseArray), one per moment sample.
std::shared_ptr<whisker_localization::WhiskerLocalizationLogic> add_whisker_localization(
    Host& host, const tactile_common::ParamMap& overrides);

/// The simulator: a timer at the physics rate publishing every sensor and
/// ground-truth topic, subscribed to the setpoint topics.
void add_tactile_sim(Host& host, std::shared_ptr<tactile_sim::SimLogic> sim);

/// The scenario pilot: /whisker/*/signal, /collisions, /odom in; setpoints out at 50 Hz.
void add_scenario_pilot(Host& host, std::shared_ptr<tactile_sim::ScriptedPilotLogic> pilot);

/// wall_effect_ekf (004 eq. 20-25): /imu, /flow, /tof, /thrust_command -> /wall_effect/estimate at 100 Hz.
std::shared_ptr<wall_effect_ekf::WallEffectEkfLogic> add_wall_effect_ekf(Host& host,
                                                                         const tactile_common::ParamMap& overrides);

/// indi_controller (004 eq. 26-36): /wall_effect/setpoint, /odom, /imu, /wall_effect/estimate
/// -> /cmd_rotor_thrust at rate_hz.
std::shared_ptr<wall_effect_ekf::IndiControlLogic> add_indi_controller(Host& host,
                                                                       const tactile_common::ParamMap& overrides);

/// wall_effect_nav (004 wall following / vector field): /wall_effect/estimate, /odom
/// -> /wall_effect/setpoint, /fsm_state at 100 Hz.
std::shared_ptr<tactile_fsm::WallEffectNavLogic> add_wall_effect_nav(Host& host, const tactile_common::ParamMap& overrides);

/// wall_trajectory (004 estimation flight, hold, sweep): /wall_effect/setpoint at 100 Hz.
std::shared_ptr<wall_effect_ekf::WallTrajectoryLogic> add_wall_trajectory(Host& host,
                                                                          const tactile_common::ParamMap& overrides);

}  // namespace tactile_cli
