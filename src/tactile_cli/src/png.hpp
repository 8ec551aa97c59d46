// Internal: writing an OpenCV image as PNG with an error that names the file.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

namespace tactile_cli::detail {

inline void write_png(const std::string& path, const cv::Mat& img) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, img);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot write PNG: " + e.what());
  }
  if (!ok) throw std::runtime_error(path + ": cannot write PNG");
}

}  // namespace tactile_cli::detail
