// Internal: writing an OpenCV image as PNG with an error that names the file.
#pragma once

#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "tactile_common/png.hpp"

namespace tactile_cli::detail {

/// `img` is 8-bit BGR (CV_8UC3), as every plot of the host draws.
inline void write_png(const std::string& path, const cv::Mat& img) {
  if (img.type() != CV_8UC3) throw std::runtime_error(path + ": cannot write PNG: not an 8-bit BGR image");
  tactile_common::write_png_bgr(path, img.data, img.cols, img.rows, img.step);
}

}  // namespace tactile_cli::detail
