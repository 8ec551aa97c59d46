// Robot models (tactile_common::RobotModel: links fixed to base_link) of the
// simulated vehicles, derived from the same parameter structs the physics
// uses, so the static transforms, the URDF (robot_description) and the
// simulation share one geometry. Frames (REP 103: x forward, y left, z up):
//
// - whiskered Crazyflie (000): whisker_left / whisker_right at the whisker bases
//   (whisker_base_x ahead of the centre, +-whisker_spacing/2 left/right), x along
//   the undeformed shaft (pitched up by the placement angle alpha); imu_link,
//   flow (x forward) and tof_down (x down: sensor_msgs/Range measures along x) at
//   the centre of mass, where the sensor models of sensors.hpp measure.
// - XPLORER (001): arm0..arm3 at the hinges (x along the undeflected arm,
//   Xplorer::kArmDirections), arm<i>_imu at arm_imu_position along the arm,
//   rotor<i> at arm_length; imu_link at the centre. The arms' deflections are not
//   joints here: the arm IMU messages carry them (the links show the rest pose).
// - ducted quadrotor (004): rotor0..rotor3 at (+-rotor_offset, +-rotor_offset),
//   counter-clockwise from the front-right one (DuctedQuad's order); imu_link,
//   flow, tof_down at the centre.
// - whisker stage (002): whisker_base at the stage origin, x along the whisker.
#pragma once

#include "tactile_common/frames.hpp"
#include "tactile_sim/crazyflie.hpp"
#include "tactile_sim/ducted_quad.hpp"
#include "tactile_sim/whisker_stage.hpp"
#include "tactile_sim/xplorer.hpp"

namespace tactile_sim {

tactile_common::RobotModel robot_model(const CrazyflieParams& p);
tactile_common::RobotModel robot_model(const XplorerParams& p);
tactile_common::RobotModel robot_model(const DuctedQuadParams& p);
tactile_common::RobotModel robot_model(const WhiskerStageParams& p);

}  // namespace tactile_sim
