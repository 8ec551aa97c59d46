#include "xplorer_force_est/filters.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace xplorer_force_est {

MedianFilter::MedianFilter(int window) : window_(window) {
  if (window < 1 || window > kMaxWindow || window % 2 == 0) {
    throw std::invalid_argument("MedianFilter.window: must be odd and in [1, " + std::to_string(kMaxWindow) +
                                "], got " + std::to_string(window));
  }
}

void MedianFilter::reset() {
  count_ = 0;
  next_ = 0;
}

double MedianFilter::update(double x) {
  ring_[static_cast<size_t>(next_)] = x;
  next_ = (next_ + 1) % window_;
  count_ = std::min(count_ + 1, window_);
  std::array<double, kMaxWindow> s{};
  std::copy_n(ring_.begin(), count_, s.begin());
  const auto mid = s.begin() + count_ / 2;
  std::nth_element(s.begin(), mid, s.begin() + count_);
  if (count_ % 2 == 1) return *mid;
  const double hi = *mid;
  const double lo = *std::max_element(s.begin(), mid);
  return 0.5 * (lo + hi);
}

LowPassFilter::LowPassFilter(double cutoff_hz, double sample_rate_hz) {
  if (!(cutoff_hz > 0.0) || !std::isfinite(cutoff_hz))
    throw std::invalid_argument("LowPassFilter.cutoff_hz: must be finite and > 0, got " + std::to_string(cutoff_hz));
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw std::invalid_argument("LowPassFilter.sample_rate_hz: must be finite and > 0, got " +
                                std::to_string(sample_rate_hz));
  a_ = 1.0 - std::exp(-2.0 * M_PI * cutoff_hz / sample_rate_hz);
}

double LowPassFilter::update(double x) {
  if (!initialised_) {
    y_ = x;
    initialised_ = true;
  } else {
    y_ += a_ * (x - y_);
  }
  return y_;
}

BandStopFilter::BandStopFilter(double center_hz, double q, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw std::invalid_argument("BandStopFilter.sample_rate_hz: must be finite and > 0, got " +
                                std::to_string(sample_rate_hz));
  if (!(center_hz > 0.0) || !(center_hz < 0.5 * sample_rate_hz))
    throw std::invalid_argument("BandStopFilter.center_hz: must be in (0, fs/2 = " +
                                std::to_string(0.5 * sample_rate_hz) + "), got " + std::to_string(center_hz));
  if (!(q > 0.0) || !std::isfinite(q))
    throw std::invalid_argument("BandStopFilter.q: must be finite and > 0, got " + std::to_string(q));
  const double w0 = 2.0 * M_PI * center_hz / sample_rate_hz;
  const double alpha = std::sin(w0) / (2.0 * q);
  const double c = std::cos(w0);
  const double a0 = 1.0 + alpha;
  b_ = {1.0 / a0, -2.0 * c / a0, 1.0 / a0};
  a_ = {1.0, -2.0 * c / a0, (1.0 - alpha) / a0};
}

double BandStopFilter::update(double x) {
  if (!initialised_) {  // steady state of a constant input x (unity DC gain)
    x1_ = x2_ = y1_ = y2_ = x;
    initialised_ = true;
  }
  const double y = b_[0] * x + b_[1] * x1_ + b_[2] * x2_ - a_[1] * y1_ - a_[2] * y2_;
  x2_ = x1_;
  x1_ = x;
  y2_ = y1_;
  y1_ = y;
  return y;
}

}  // namespace xplorer_force_est
