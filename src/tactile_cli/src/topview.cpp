#include "png.hpp"
#include "tactile_cli/topview.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "tactile_cli/plot.hpp"

namespace tactile_cli {

using tactile_sim::Vec2;

namespace {

constexpr int kLeft = 70, kRight = 200, kTop = 40, kBottom = 55;
const auto kFont = cv::FONT_HERSHEY_SIMPLEX;

// Wall colours by material name (BGR); other materials purple.
cv::Scalar material_color(const std::string& name) {
  if (name == "rigid") return {60, 60, 60};
  if (name == "glass") return {230, 160, 60};
  if (name == "textile") return {40, 120, 210};
  return {160, 60, 160};
}

// Time colour ramp (blue -> cyan -> green -> yellow -> red), s in [0, 1].
cv::Scalar ramp(double s) {
  s = std::clamp(s, 0.0, 1.0);
  const double r = std::clamp(1.5 - std::abs(4.0 * s - 3.0), 0.0, 1.0);
  const double g = std::clamp(1.5 - std::abs(4.0 * s - 2.0), 0.0, 1.0);
  const double b = std::clamp(1.5 - std::abs(4.0 * s - 1.0), 0.0, 1.0);
  return {255 * b, 255 * g, 255 * r};
}

bool finite(const Vec2& p) { return std::isfinite(p.x()) && std::isfinite(p.y()); }

std::string fmt(double v, double step) {
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(buf, sizeof buf, "%.*f", std::max(0, decimals), v);
  return buf;
}

void draw_cross(cv::Mat& img, cv::Point c, int r, const cv::Scalar& col, int thick) {
  cv::line(img, c + cv::Point(-r, -r), c + cv::Point(r, r), col, thick, cv::LINE_AA);
  cv::line(img, c + cv::Point(-r, r), c + cv::Point(r, -r), col, thick, cv::LINE_AA);
}

void draw_icon(cv::Mat& img, cv::Point c, double yaw, const cv::Scalar& col) {
  // Quadrotor icon: four rotor circles on an X, heading line (screen y is down).
  for (int k = 0; k < 4; ++k) {
    const double a = yaw + M_PI / 4 + k * M_PI / 2;
    const cv::Point r(c.x + static_cast<int>(std::lround(9 * std::cos(a))),
                      c.y - static_cast<int>(std::lround(9 * std::sin(a))));
    cv::line(img, c, r, col, 1, cv::LINE_AA);
    cv::circle(img, r, 4, col, 1, cv::LINE_AA);
  }
  const cv::Point h(c.x + static_cast<int>(std::lround(18 * std::cos(yaw))),
                    c.y - static_cast<int>(std::lround(18 * std::sin(yaw))));
  cv::arrowedLine(img, c, h, col, 2, cv::LINE_AA, 0, 0.35);
}

}  // namespace

TopViewLayout topview_layout(const TopView& view, int width_px) {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  auto add = [&](const Vec2& p) {
    if (!finite(p)) return;
    x0 = std::min(x0, p.x());
    y0 = std::min(y0, p.y());
    x1 = std::max(x1, p.x());
    y1 = std::max(y1, p.y());
  };
  if (view.arena) {
    const auto b = view.arena->bounds();
    if (!b.empty) {
      add(b.min);
      add(b.max);
    }
  }
  for (const auto* v : {&view.trajectory, &view.estimate_trajectory, &view.whisker_contacts,
                        &view.collisions, &view.map_points, &view.targets}) {
    for (const Vec2& p : *v) add(p);
  }
  for (const auto& p : view.poses) add(p.first);
  if (!std::isfinite(x0)) x0 = y0 = -1.0, x1 = y1 = 1.0;
  const double margin = std::max(0.2, 0.1 * std::max(x1 - x0, y1 - y0));
  x0 -= margin, x1 += margin, y0 -= margin, y1 += margin;

  TopViewLayout l;
  l.width = width_px;
  l.left = kLeft;
  l.top = kTop;
  l.plot_width = width_px - kLeft - kRight;
  l.scale = l.plot_width / (x1 - x0);
  // Tall views: limit the height to 1.5 x the width, widen the x range instead.
  const int max_plot_h = static_cast<int>(1.5 * width_px);
  if ((y1 - y0) * l.scale > max_plot_h) {
    l.scale = max_plot_h / (y1 - y0);
    const double cx = 0.5 * (x0 + x1), half = 0.5 * l.plot_width / l.scale;
    x0 = cx - half;
  }
  // Short views: at least 250 px of plot height, centred.
  l.plot_height = std::max(250, static_cast<int>(std::ceil((y1 - y0) * l.scale)));
  const double cy = 0.5 * (y0 + y1);
  l.x_min = x0;
  l.y_max = cy + 0.5 * l.plot_height / l.scale;
  l.height = kTop + l.plot_height + kBottom;
  return l;
}

void write_topview_png(const std::string& path, const TopView& view, int width_px) {
  if (width_px < 300) {
    throw std::invalid_argument(path + ": top view width must be >= 300 px, got " +
                                std::to_string(width_px));
  }
  const TopViewLayout l = topview_layout(view, width_px);
  cv::Mat img(l.height, l.width, CV_8UC3, cv::Scalar(255, 255, 255));
  auto P = [&](const Vec2& p) {
    return cv::Point(static_cast<int>(std::lround(l.px(p.x()))),
                     static_cast<int>(std::lround(l.py(p.y()))));
  };
  const int x_right = l.left + l.plot_width, y_bottom = l.top + l.plot_height;
  const double x_max = l.x_min + l.plot_width / l.scale, y_min = l.y_max - l.plot_height / l.scale;

  // Grid and axes.
  const auto xt = nice_ticks(l.x_min, x_max, 8);
  const auto yt = nice_ticks(y_min, l.y_max, 8);
  const double xs = xt.size() > 1 ? xt[1] - xt[0] : 1.0, ys = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double t : xt) {
    const int x = static_cast<int>(std::lround(l.px(t)));
    cv::line(img, {x, l.top}, {x, y_bottom}, cv::Scalar(235, 235, 235), 1);
    cv::putText(img, fmt(t, xs), {x - 12, y_bottom + 16}, kFont, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
  for (double t : yt) {
    const int y = static_cast<int>(std::lround(l.py(t)));
    cv::line(img, {l.left, y}, {x_right, y}, cv::Scalar(235, 235, 235), 1);
    cv::putText(img, fmt(t, ys), {8, y + 4}, kFont, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
  cv::putText(img, "x [m]", {l.left + l.plot_width / 2 - 15, y_bottom + 36}, kFont, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "y [m]", {8, l.top - 8}, kFont, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

  // Arena.
  std::vector<int> used_materials;
  if (view.arena) {
    const auto& mats = view.arena->materials();
    for (const auto& c : view.arena->cylinders()) {
      const auto col = material_color(mats[c.material].name);
      const int r = std::max(1, static_cast<int>(std::lround(c.radius * l.scale)));
      cv::circle(img, P(c.center), r, col * 0.3 + cv::Scalar(180, 180, 180), cv::FILLED, cv::LINE_AA);
      cv::circle(img, P(c.center), r, col, 3, cv::LINE_AA);
      used_materials.push_back(c.material);
    }
    for (const auto& w : view.arena->walls()) {
      cv::line(img, P(w.a), P(w.b), material_color(mats[w.material].name), 4, cv::LINE_AA);
      used_materials.push_back(w.material);
    }
    std::sort(used_materials.begin(), used_materials.end());
    used_materials.erase(std::unique(used_materials.begin(), used_materials.end()), used_materials.end());
  }

  // The paths are drawn through points >= 2 px apart: a 75 s flight logs 7,500 poses
  // whose consecutive points are mostly under a pixel apart, and drawing each as an
  // anti-aliased segment was most of the picture's cost (2026-11-24: 30 ms -> 3 ms).
  // for_each_segment calls draw(a, b, i, len_px) for the kept segments, the last point
  // always ending one; a non-finite point breaks the path.
  constexpr double kMinSegmentPx = 2.0;
  auto for_each_segment = [&](const std::vector<Vec2>& points, auto&& draw) {
    bool have = false;
    Vec2 a = Vec2::Zero();
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec2& b = points[i];
      if (!finite(b)) {
        have = false;
        continue;
      }
      if (!have) {
        a = b;
        have = true;
        continue;
      }
      const double len_px = (b - a).norm() * l.scale;
      if (len_px < kMinSegmentPx && i + 1 < points.size()) continue;
      draw(a, b, i, len_px);
      a = b;
    }
  };
  // Estimate: dashed grey, 8 px on / 8 px off along the path's length.
  const cv::Scalar grey(150, 150, 150);
  double travelled_px = 0.0;
  for_each_segment(view.estimate_trajectory, [&](const Vec2& a, const Vec2& b, size_t, double len_px) {
    const int pieces = std::max(1, static_cast<int>(len_px / 4));
    for (int k = 0; k < pieces; ++k) {
      const double at = travelled_px + (k + 0.5) * len_px / pieces;
      if (std::fmod(at, 16.0) >= 8.0) continue;
      cv::line(img, P(a + (b - a) * k / pieces), P(a + (b - a) * (k + 1) / pieces), grey, 2, cv::LINE_AA);
    }
    travelled_px += len_px;
  });
  for (const Vec2& p : view.map_points) {
    if (finite(p)) cv::circle(img, P(p), 1, cv::Scalar(200, 120, 30), cv::FILLED, cv::LINE_AA);
  }
  // Trajectory: time colour (the colour of a segment's end point).
  const size_t n = view.trajectory.size();
  for_each_segment(view.trajectory, [&](const Vec2& a, const Vec2& b, size_t i, double) {
    cv::line(img, P(a), P(b), ramp((static_cast<double>(i) - 0.5) / static_cast<double>(std::max<size_t>(1, n - 1))), 2,
             cv::LINE_AA);
  });
  for (const Vec2& p : view.whisker_contacts) {
    if (finite(p)) cv::circle(img, P(p), 3, cv::Scalar(60, 170, 40), cv::FILLED, cv::LINE_AA);
  }
  for (const auto& [p, yaw] : view.poses) {
    if (finite(p) && std::isfinite(yaw)) draw_icon(img, P(p), yaw, cv::Scalar(20, 20, 20));
  }
  for (const Vec2& p : view.collisions) {
    if (finite(p)) draw_cross(img, P(p), 7, cv::Scalar(0, 0, 230), 2);
  }
  for (const Vec2& p : view.targets) {
    if (!finite(p)) continue;
    cv::circle(img, P(p), 9, cv::Scalar(200, 0, 200), 2, cv::LINE_AA);
    cv::circle(img, P(p), 2, cv::Scalar(200, 0, 200), cv::FILLED, cv::LINE_AA);
  }
  cv::rectangle(img, {l.left, l.top}, {x_right, y_bottom}, cv::Scalar(0, 0, 0), 1);

  // Scale bar (bottom-left inside the plot): a nice length near 1/5 of the width.
  {
    // Largest 1, 2 or 5 x 10^k metres not above a quarter of the width.
    const double target = 0.25 * (x_max - l.x_min);
    const double mag = std::pow(10.0, std::floor(std::log10(target)));
    double len_m = mag;
    for (double m : {2.0, 5.0}) {
      if (m * mag <= target) len_m = m * mag;
    }
    const int x = l.left + 15, y = y_bottom - 15, len = static_cast<int>(std::lround(len_m * l.scale));
    cv::rectangle(img, {x - 4, y - 22}, {x + len + 50, y + 6}, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::line(img, {x, y}, {x + len, y}, cv::Scalar(0, 0, 0), 2);
    cv::line(img, {x, y - 5}, {x, y + 5}, cv::Scalar(0, 0, 0), 2);
    cv::line(img, {x + len, y - 5}, {x + len, y + 5}, cv::Scalar(0, 0, 0), 2);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g m", len_m);
    cv::putText(img, buf, {x + len / 2 - 12, y - 9}, kFont, 0.42, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }

  // Legend.
  int ly = l.top + 12;
  const int lx = x_right + 12;
  auto label = [&](const std::string& s, int indent = 32) {
    cv::putText(img, s, {lx + indent, ly + 4}, kFont, 0.42, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    ly += 20;
  };
  if (view.arena) {
    for (int m : used_materials) {
      const auto& mat = view.arena->materials()[m];
      cv::line(img, {lx, ly}, {lx + 24, ly}, material_color(mat.name), 4, cv::LINE_AA);
      label("wall: " + mat.name);
    }
  }
  if (!view.trajectory.empty()) {
    for (int k = 0; k < 24; ++k) cv::line(img, {lx + k, ly}, {lx + k + 1, ly}, ramp(k / 23.0), 3);
    label("path (start->end)");
  }
  if (!view.estimate_trajectory.empty()) {
    cv::line(img, {lx, ly}, {lx + 8, ly}, grey, 2);
    cv::line(img, {lx + 14, ly}, {lx + 22, ly}, grey, 2);
    label("estimate");
  }
  if (!view.whisker_contacts.empty()) {
    cv::circle(img, {lx + 12, ly}, 3, cv::Scalar(60, 170, 40), cv::FILLED, cv::LINE_AA);
    label("whisker contact");
  }
  if (!view.collisions.empty()) {
    draw_cross(img, {lx + 12, ly}, 6, cv::Scalar(0, 0, 230), 2);
    label("collision");
  }
  if (!view.map_points.empty()) {
    cv::circle(img, {lx + 12, ly}, 2, cv::Scalar(200, 120, 30), cv::FILLED, cv::LINE_AA);
    label("map");
  }
  if (!view.targets.empty()) {
    cv::circle(img, {lx + 12, ly}, 7, cv::Scalar(200, 0, 200), 2, cv::LINE_AA);
    label("target");
  }
  if (!view.poses.empty()) {
    ly += 6;
    draw_icon(img, {lx + 12, ly}, 0.0, cv::Scalar(20, 20, 20));
    label("vehicle (heading)", 40);
  }
  if (!view.title.empty()) {
    cv::putText(img, view.title, {l.left, 24}, kFont, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }

  detail::write_png(path, img);
}

}  // namespace tactile_cli
