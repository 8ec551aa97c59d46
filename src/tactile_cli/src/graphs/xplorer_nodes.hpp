// The XPLORER nodes on the standalone host (paper 001), each the counterpart
// of its rclcpp component: same node name, topics (the logic's constants)
// and parameters (config/<node>.yaml + overrides).
#pragma once

#include <memory>

#include "mapping_pcl/xplorer_map_logic.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

namespace tactile_cli {

/// xplorer_force_est: /arm_imu, /imu, /thrust_command -> /xplorer/wrench, /xplorer/wrench_body.
std::shared_ptr<xplorer_force_est::XplorerForceEstLogic> add_xplorer_force_est(
    Host& host, const tactile_common::ParamMap& overrides);

/// xplorer_fsm: /xplorer/wrench, /odom -> /cmd_position, /xplorer/fsm_state at 50 Hz.
std::shared_ptr<tactile_fsm::XplorerFsmLogic> add_xplorer_fsm(Host& host, const tactile_common::ParamMap& overrides);

/// xplorer_mapping: /xplorer/wrench_body, /odom -> /xplorer/map (PointCloud2) at rate_hz stamping.
std::shared_ptr<mapping_pcl::XplorerMapLogic> add_xplorer_mapping(Host& host, const tactile_common::ParamMap& overrides);

}  // namespace tactile_cli
