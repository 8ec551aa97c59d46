// Top view of a simulated run written as PNG with OpenCV: arena walls
// coloured by material, cylinders, the true trajectory coloured by time, the
// estimated trajectory (dashed grey), whisker contact points, collisions (red
// crosses) and vehicle icons at a few poses; axes in metres, scale bar, legend.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_cli {

struct TopView {
  const tactile_sim::Arena* arena = nullptr;  ///< optional
  std::vector<tactile_sim::Vec2> trajectory;           ///< true path, coloured by time (first -> last)
  std::vector<tactile_sim::Vec2> estimate_trajectory;  ///< optional, dashed grey
  std::vector<tactile_sim::Vec2> whisker_contacts;     ///< points
  std::vector<tactile_sim::Vec2> collisions;           ///< red crosses
  std::vector<tactile_sim::Vec2> map_points;           ///< a behaviour's map (small blue dots)
  std::vector<tactile_sim::Vec2> targets;              ///< goals / targets (magenta rings)
  std::vector<std::pair<tactile_sim::Vec2, double>> poses;  ///< vehicle icons: position, yaw [rad]
  std::string title;
};

/// World -> pixel mapping of a top view (equal scale on both axes, y up).
struct TopViewLayout {
  int width = 0, height = 0;        ///< image size [px]
  int left = 0, top = 0;            ///< plot area origin [px]
  int plot_width = 0, plot_height = 0;
  double x_min = 0.0, y_max = 0.0;  ///< world coordinates of the plot area's top-left corner [m]
  double scale = 1.0;               ///< [px/m]
  double px(double x) const { return left + (x - x_min) * scale; }
  double py(double y) const { return top + (y_max - y) * scale; }
};

/// Layout write_topview_png uses: bounds of the arena and all points with a
/// margin of 10 % (at least 0.2 m), equal axis scale.
TopViewLayout topview_layout(const TopView& view, int width_px = 900);

/// Writes the top view as PNG. Throws std::runtime_error naming the file if it
/// cannot be written, std::invalid_argument (naming the file) if width_px < 300.
/// Non-finite points are skipped.
void write_topview_png(const std::string& path, const TopView& view, int width_px = 900);

}  // namespace tactile_cli
