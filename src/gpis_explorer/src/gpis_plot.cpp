// GPIS picture (000 Fig. 5). See gpis_plot.hpp.
#include "gpis_explorer/gpis_plot.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tactile_common/png.hpp"

namespace gpis_explorer {
namespace {

cv::Scalar ramp(double s) {  // blue -> cyan -> green -> yellow -> red (BGR)
  s = std::clamp(s, 0.0, 1.0);
  const double r = std::clamp(1.5 - std::abs(4.0 * s - 3.0), 0.0, 1.0);
  const double g = std::clamp(1.5 - std::abs(4.0 * s - 2.0), 0.0, 1.0);
  const double b = std::clamp(1.5 - std::abs(4.0 * s - 1.0), 0.0, 1.0);
  return {255 * b, 255 * g, 255 * r};
}

}  // namespace

void write_gpis_png(const std::string& path, const GpisPicture& pic, int side) {
  const auto& m = pic.map;
  if (m.width < 2 || m.height < 2 || static_cast<std::size_t>(m.width) * m.height != m.mean.size() ||
      (!m.variance.empty() && m.variance.size() != m.mean.size()) || !(m.resolution > 0.0)) {
    throw std::invalid_argument(path + ": GpisMap grid is inconsistent (width " + std::to_string(m.width) +
                                ", height " + std::to_string(m.height) + ", mean " + std::to_string(m.mean.size()) +
                                ", variance " + std::to_string(m.variance.size()) + ")");
  }
  side = std::max(side, 200);
  const int margin = 40, legend = 30;
  const double w_m = (m.width - 1) * m.resolution, h_m = (m.height - 1) * m.resolution;
  const double scale = side / std::max(w_m, h_m);
  const int pw = static_cast<int>(std::lround(w_m * scale)), ph = static_cast<int>(std::lround(h_m * scale));
  cv::Mat img(ph + 2 * margin + legend, pw + 2 * margin, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(margin + static_cast<int>(std::lround((p.x() - m.origin_x) * scale)),
                     margin + legend + ph - static_cast<int>(std::lround((p.y() - m.origin_y) * scale)));
  };
  // Uncertainty map: variance (eq. 35) bilinearly upsampled, dark = certain, bright = uncertain.
  if (!m.variance.empty()) {
    cv::Mat var(static_cast<int>(m.height), static_cast<int>(m.width), CV_32F);
    double vmax = 1e-12;
    for (uint32_t j = 0; j < m.height; ++j) {
      for (uint32_t i = 0; i < m.width; ++i) {
        float v = m.variance[j * m.width + i];
        if (!std::isfinite(v)) v = 0.0f;
        var.at<float>(static_cast<int>(m.height - 1 - j), static_cast<int>(i)) = v;  // row 0 at the top = max y
        vmax = std::max(vmax, static_cast<double>(v));
      }
    }
    cv::Mat up, u8, col;
    cv::resize(var, up, cv::Size(pw, ph), 0, 0, cv::INTER_LINEAR);
    up.convertTo(u8, CV_8U, 255.0 / vmax);
    cv::applyColorMap(u8, col, cv::COLORMAP_VIRIDIS);
    col.copyTo(img(cv::Rect(margin, margin + legend, pw, ph)));
  }
  cv::rectangle(img, cv::Rect(margin, margin + legend, pw, ph), cv::Scalar(0, 0, 0), 1);
  for (const auto& w : pic.walls) cv::line(img, px(w.first), px(w.second), cv::Scalar(200, 200, 200), 2, cv::LINE_AA);
  // Trajectory, rainbow by time.
  const std::size_t nt = pic.trajectory.size();
  for (std::size_t k = 1; k < nt; ++k) {
    cv::line(img, px(pic.trajectory[k - 1]), px(pic.trajectory[k]), ramp(static_cast<double>(k) / static_cast<double>(nt)), 2, cv::LINE_AA);
  }
  // Contours (orange, or by curvature: brighter = more negative), chained in order.
  std::vector<uint32_t> starts = m.contour_starts;
  starts.push_back(static_cast<uint32_t>(m.contour.size()));
  for (std::size_t c = 0; c + 1 < starts.size(); ++c) {
    for (uint32_t k = starts[c]; k + 1 < starts[c + 1] && k + 1 < m.contour.size(); ++k) {
      cv::Scalar col(0, 140, 255);
      if (pic.curvature.size() == m.contour.size() && std::isfinite(pic.curvature[k])) {
        const double s = std::clamp(-pic.curvature[k] / 5.0, 0.0, 1.0);
        col = cv::Scalar(0, 80 + 175 * s, 200 + 55 * s);
      }
      cv::line(img, px({m.contour[k].x, m.contour[k].y}), px({m.contour[k + 1].x, m.contour[k + 1].y}), col, 3,
               cv::LINE_AA);
    }
  }
  for (std::size_t i = 0; i < m.training_points.size() && i < m.training_labels.size(); ++i) {
    const cv::Scalar col = m.training_labels[i] == 0 ? cv::Scalar(40, 40, 230) : cv::Scalar(230, 120, 30);
    cv::circle(img, px({m.training_points[i].x, m.training_points[i].y}), 4, col, cv::FILLED, cv::LINE_AA);
  }
  for (const auto& c : m.corners) {
    cv::circle(img, px({c.x, c.y}), 6, cv::Scalar(255, 255, 255), cv::FILLED, cv::LINE_AA);
    cv::circle(img, px({c.x, c.y}), 6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  if (pic.target) cv::circle(img, px(*pic.target), 10, cv::Scalar(255, 80, 0), 2, cv::LINE_AA);
  if (pic.drone) {
    const cv::Point c = px(pic.drone->first);
    const double yaw = pic.drone->second;
    cv::circle(img, c, 7, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
    cv::line(img, c, c + cv::Point(static_cast<int>(14 * std::cos(yaw)), -static_cast<int>(14 * std::sin(yaw))),
             cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
  }
  cv::putText(img, pic.title, cv::Point(margin, 25), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  char axes[96];
  std::snprintf(axes, sizeof axes, "x [%.1f, %.1f] m, y [%.1f, %.1f] m", m.origin_x, m.origin_x + w_m, m.origin_y,
                m.origin_y + h_m);
  cv::putText(img, axes, cv::Point(margin, img.rows - 12), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  tactile_common::write_png_bgr(path, img.data, img.cols, img.rows, img.step);
}

}  // namespace gpis_explorer
