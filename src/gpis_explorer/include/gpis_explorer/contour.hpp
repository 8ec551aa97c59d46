// Zero level set of a grid by marching squares, with the segments chained into
// ordered contours (paper 000 Fig. S4f: "we predict the value of each point on
// a generated grid and extract contour segments where z = 0 using the marching
// squares method. These contour segments are then connected sequentially as
// contour points").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace gpis_explorer {

/// A regular grid of sample nodes: node (i, j) is at
/// (origin_x + i * resolution, origin_y + j * resolution), i < width,
/// j < height; values are row-major, index j * width + i (as GpisMap).
struct GridSpec {
  double origin_x = -2.0;
  double origin_y = -2.0;
  double resolution = 4.0 / 9.0;
  uint32_t width = 10;
  uint32_t height = 10;

  /// A grid of n x n nodes spanning size x size metres centred on (cx, cy).
  static GridSpec centred(double cx, double cy, double size, uint32_t n);
  std::size_t count() const { return static_cast<std::size_t>(width) * height; }
  Eigen::Vector2d node(uint32_t i, uint32_t j) const {
    return {origin_x + i * resolution, origin_y + j * resolution};
  }
  /// All nodes as columns, row-major order.
  Eigen::Matrix2Xd nodes() const;
  bool contains(const Eigen::Vector2d& p) const;
  /// Throws std::invalid_argument "GridSpec.<field>: <reason>".
  void validate() const;
};

/// One chained contour: points in order along the level set.
struct Contour {
  std::vector<Eigen::Vector2d> points;
  /// true: the last point connects back to the first (not repeated);
  /// false: both ends lie on the grid border (the level set leaves the grid).
  bool closed = false;
};

/// Marching squares on `values` (row-major, grid.count() entries) at level 0.
/// A node is "above" when its value is >= 0. Ambiguous saddle cells are
/// resolved by the mean of the four corners. Edge crossings are linearly
/// interpolated. Segments are chained through their shared cell edges, so each
/// crossing appears once; open contours are returned first, then closed ones.
/// Non-finite values count as "below" (no crossing invented from NaN).
std::vector<Contour> marching_squares(const GridSpec& grid, const std::vector<double>& values);

}  // namespace gpis_explorer
