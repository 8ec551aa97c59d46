// Picture of one GPIS update like 000 Fig. 5 (c1-f2): the uncertainty map
// (posterior variance, eq. 35) with the zero contour coloured by curvature
// (eq. 40), training points (red: surface 0, blue: interior -1), corner
// centroids (white dots, eq. 42-43), the next target (blue hollow circle,
// eq. 46), the trajectory (rainbow by time) and the drone. OpenCV, PNG.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "tactile_msgs/msg/gpis_map.hpp"

namespace gpis_explorer {

struct GpisPicture {
  tactile_msgs::msg::GpisMap map;
  std::vector<Eigen::Vector2d> trajectory;              ///< odometry frame, oldest first
  std::optional<Eigen::Vector2d> target;                ///< next target
  std::optional<std::pair<Eigen::Vector2d, double>> drone;  ///< position, yaw [rad]
  /// Optional true walls (segments, same frame) drawn thin grey for comparison.
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> walls;
  /// Per contour point curvature (000 eq. 40), same order as map.contour;
  /// empty: the contour is drawn orange (000 Fig. 5 c1).
  std::vector<double> curvature;
  std::string title;
};

/// Writes the picture as PNG (side = pixels of the square map area). Throws
/// std::runtime_error naming the file if it cannot be written and
/// std::invalid_argument if the map's grid is inconsistent (width * height
/// != mean.size()).
void write_gpis_png(const std::string& path, const GpisPicture& picture, int side = 600);

}  // namespace gpis_explorer
