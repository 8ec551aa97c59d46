// The XPLORER explore metrics shared by the graph that flies it (`tactile
// sim`) and the bag re-evaluation (`tactile evaluate`), so the two measure one
// flight the same way: the map's area against the object's (001 Sec. V-D) and
// how each Tactile-turning ended.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "mapping_pcl/point_map.hpp"
#include "tactile_sim/arena.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

/// The scenario's area goal (its `metrics:` section):
/// - `box_size: [l, w]` the true footprint's bounding rectangle [m] -> `map_area_accuracy`
///   (the map's minimum-area rectangle against it, 001 Sec. V-D);
/// - `area_accuracy_of: rectangle | hull` which accuracy is the object's
///   `area_accuracy` (rectangle needs box_size; default: rectangle with box_size, else hull:
///   the map's convex hull against the arena objects' hull, for polygons and cylinders);
/// - `min_area_accuracy: a` in (0, 1]: the explore mission succeeds only with the loop closed
///   AND `area_accuracy` >= a (issue 17's goal; unset: loop closure alone).
struct XplorerAreaGoal {
  std::optional<std::array<double, 2>> box_size;  ///< [length >= width] [m]
  bool rectangle = false;                         ///< area_accuracy is map_area_accuracy
  std::optional<double> min_accuracy;

  /// Throws std::runtime_error naming the file and the key for a bad value.
  static XplorerAreaGoal from(const tactile_sim::Scenario& s);
};

/// Area of the convex hull of every wall end point and cylinder (sampled at
/// 0.5 deg) of the arena [m^2]; 0 for an arena without obstacles.
double object_hull_area(const tactile_sim::Arena& arena);

/// The map as exported (1 cm voxel filter + statistical outlier removal,
/// params of the mapper) measured against the goal: fills map_points,
/// map_length_m, map_width_m, map_height_m, map_area_m2, map_hull_area_m2,
/// true_area_m2 and map_hull_area_accuracy (object_area > 0), true_length_m,
/// true_width_m and map_area_accuracy (box_size), area_accuracy and
/// min_area_accuracy. Returns area_accuracy (unset if it cannot be measured).
std::optional<double> measure_map_area(const mapping_pcl::PointMap& map, const XplorerAreaGoal& goal,
                                       double object_area, nlohmann::json& out);

/// From the FSM's state changes (time, state), in order: how each Tactile-turning ended
/// (001 Sec. V-C4: the rigid UAV turns but never re-establishes contact) and how often a
/// traversal lost the contact. Fills turns_recontacted, turns_without_recontact,
/// turns_closing_the_loop (a turn ended by the loop's closure, loop_turn_min_winding, is
/// neither) and traversal_contact_lost.
void add_turn_outcomes(const std::vector<std::pair<double, std::string>>& states, nlohmann::json& out);

}  // namespace tactile_cli
