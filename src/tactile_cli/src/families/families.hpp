// The scenario families of `tactile scenarios generate` / `tactile sweep`, one
// file each in src/families/ (tactile_cli/scenario_family.hpp).
#pragma once

#include <vector>

#include "tactile_cli/scenario_family.hpp"

namespace tactile_cli::families {

/// Baffle courses for the whisker wall-following FSM (000 Fig. 4 style); the
/// state estimate drawn from mocap / flow_deck / imu_tof, or fixed.
std::vector<ScenarioFamily> baffle_families();
/// Rooms with exits for GPIS exploration (000 Fig. 5 style).
std::vector<ScenarioFamily> room_families();
/// Objects for the XPLORER's traversal and loop closure (001 Sec. V-C).
std::vector<ScenarioFamily> xplorer_object_families();

}  // namespace tactile_cli::families
