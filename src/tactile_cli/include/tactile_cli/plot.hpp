// Line plots written as PNG with OpenCV (every picture of the workspace is
// drawn with OpenCV): stacked panels sharing the time axis.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace tactile_cli {

struct Rgb {
  unsigned char r = 0, g = 0, b = 0;
};

struct Series {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  Rgb color;
};

struct Panel {
  std::string title;
  std::string y_label;
  std::vector<Series> series;
  std::vector<double> horizontal_lines;  ///< dashed reference lines (e.g. a threshold)
  /// Shaded x intervals (e.g. true contact episodes).
  std::vector<std::pair<double, double>> spans;
  std::optional<std::pair<double, double>> y_range;  ///< fixed y limits, else from data
};

/// Writes the panels stacked vertically into a PNG. Throws std::runtime_error
/// naming the file if it cannot be written. Non-finite points are skipped.
void write_plot_png(const std::string& path, const std::vector<Panel>& panels,
                    const std::string& x_label, int width = 1400, int panel_height = 260);

/// "Nice" tick positions covering [lo, hi] (about `count` of them).
std::vector<double> nice_ticks(double lo, double hi, int count = 6);

}  // namespace tactile_cli
