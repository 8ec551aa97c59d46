#include "png.hpp"
#include "tactile_cli/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace tactile_cli {

namespace {

cv::Scalar bgr(const Rgb& c) { return cv::Scalar(c.b, c.g, c.r); }

std::string format_tick(double v, double step) {
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step)));
  std::snprintf(buf, sizeof buf, "%.*f", std::max(0, decimals), v);
  return buf;
}

void dashed_hline(cv::Mat& img, int x0, int x1, int y, const cv::Scalar& color) {
  for (int x = x0; x < x1; x += 12) {
    cv::line(img, {x, y}, {std::min(x + 6, x1), y}, color, 1, cv::LINE_AA);
  }
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int count) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / std::max(1, count);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  std::vector<double> ticks;
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) {
    ticks.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  }
  return ticks;
}

void write_plot_png(const std::string& path, const std::vector<Panel>& panels,
                    const std::string& x_label, int width, int panel_height) {
  const int left = 90, right = 190, top = 30, bottom = 45;
  const int height = static_cast<int>(panels.size()) * panel_height + bottom;
  cv::Mat img(std::max(height, 1), width, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto font = cv::FONT_HERSHEY_SIMPLEX;

  // Shared x range over all panels.
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  for (const auto& p : panels) {
    for (const auto& s : p.series) {
      for (double x : s.x) {
        if (std::isfinite(x)) {
          x_lo = std::min(x_lo, x);
          x_hi = std::max(x_hi, x);
        }
      }
    }
  }
  if (!std::isfinite(x_lo)) x_lo = 0, x_hi = 1;
  if (x_hi <= x_lo) x_hi = x_lo + 1;

  for (size_t pi = 0; pi < panels.size(); ++pi) {
    const Panel& p = panels[pi];
    const int y0 = static_cast<int>(pi) * panel_height + top;
    const int y1 = static_cast<int>(pi + 1) * panel_height - 10;
    const int x0 = left, x1 = width - right;

    double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
    if (p.y_range) {
      y_lo = p.y_range->first;
      y_hi = p.y_range->second;
    } else {
      for (const auto& s : p.series) {
        for (double y : s.y) {
          if (std::isfinite(y)) {
            y_lo = std::min(y_lo, y);
            y_hi = std::max(y_hi, y);
          }
        }
      }
      for (double h : p.horizontal_lines) {
        y_lo = std::min(y_lo, h);
        y_hi = std::max(y_hi, h);
      }
      if (!std::isfinite(y_lo)) y_lo = 0, y_hi = 1;
      const double pad = 0.05 * std::max(y_hi - y_lo, 1e-9);
      y_lo -= pad;
      y_hi += pad;
    }
    auto px = [&](double x) { return x0 + static_cast<int>((x - x_lo) / (x_hi - x_lo) * (x1 - x0)); };
    auto py = [&](double y) {
      const double c = std::clamp(y, y_lo, y_hi);
      return y1 - static_cast<int>((c - y_lo) / (y_hi - y_lo) * (y1 - y0));
    };

    for (const auto& [a, b] : p.spans) {
      cv::rectangle(img, {px(a), y0}, {px(b), y1}, cv::Scalar(225, 235, 250), cv::FILLED);
    }
    for (double t : nice_ticks(y_lo, y_hi, 5)) {
      const int y = py(t);
      cv::line(img, {x0, y}, {x1, y}, cv::Scalar(235, 235, 235), 1);
      const auto step = nice_ticks(y_lo, y_hi, 5);
      const double st = step.size() > 1 ? step[1] - step[0] : 1.0;
      cv::putText(img, format_tick(t, st), {8, y + 4}, font, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
    }
    const auto xt = nice_ticks(x_lo, x_hi, 10);
    const double xst = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
    for (double t : xt) {
      const int x = px(t);
      cv::line(img, {x, y0}, {x, y1}, cv::Scalar(235, 235, 235), 1);
      cv::putText(img, format_tick(t, xst), {x - 10, y1 + 15}, font, 0.4, cv::Scalar(60, 60, 60), 1,
                  cv::LINE_AA);
    }
    cv::rectangle(img, {x0, y0}, {x1, y1}, cv::Scalar(0, 0, 0), 1);
    for (double h : p.horizontal_lines) dashed_hline(img, x0, x1, py(h), cv::Scalar(0, 0, 200));

    for (size_t si = 0; si < p.series.size(); ++si) {
      const Series& s = p.series[si];
      std::vector<cv::Point> pts;
      const size_t n = std::min(s.x.size(), s.y.size());
      auto flush = [&] {
        if (pts.size() > 1) cv::polylines(img, pts, false, bgr(s.color), 1, cv::LINE_AA);
        pts.clear();
      };
      for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
          flush();
          continue;
        }
        pts.emplace_back(px(s.x[i]), py(s.y[i]));
      }
      flush();
      const int ly = y0 + 14 + static_cast<int>(si) * 16;
      cv::line(img, {x1 + 10, ly - 4}, {x1 + 30, ly - 4}, bgr(s.color), 2);
      cv::putText(img, s.label, {x1 + 35, ly}, font, 0.42, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    cv::putText(img, p.title, {x0, y0 - 8}, font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, p.y_label, {x0 + 6, y0 + 16}, font, 0.4, cv::Scalar(90, 90, 90), 1, cv::LINE_AA);
  }
  cv::putText(img, x_label, {width / 2 - 40, height - 8}, font, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  detail::write_png(path, img);
}

}  // namespace tactile_cli
