// Small fixed-size scalar filters for the XPLORER force estimator (paper 001
// Sec. V-A2: "A median low-pass with a band-stop filter is employed to obtain
// accurate estimates of the arm angles"; Sec. III-A2: "using a median
// low-pass filter" for the CoM estimate). No allocation after construction.
#pragma once

#include <array>
#include <cstddef>

namespace xplorer_force_est {

/// Running median of the last `window` samples (window odd, 1..kMaxWindow).
/// While fewer samples have arrived, the median of those available.
class MedianFilter {
 public:
  static constexpr int kMaxWindow = 15;
  explicit MedianFilter(int window = 5);
  double update(double x);
  void reset();
  int window() const { return window_; }

 private:
  int window_;
  int count_ = 0;
  int next_ = 0;
  std::array<double, kMaxWindow> ring_{};
};

/// First-order low-pass y += a (x - y), a = 1 - exp(-2 pi fc / fs); the first
/// sample initialises the state (no start-up transient).
class LowPassFilter {
 public:
  LowPassFilter(double cutoff_hz = 1.0, double sample_rate_hz = 50.0);
  double update(double x);
  void reset() { initialised_ = false; }
  double alpha() const { return a_; }
  double value() const { return y_; }

 private:
  double a_;
  double y_ = 0.0;
  bool initialised_ = false;
};

/// Second-order band-stop (notch) biquad, RBJ audio-EQ cookbook form:
/// w0 = 2 pi f0 / fs, alpha = sin(w0) / (2 Q),
/// b = [1, -2 cos w0, 1], a = [1 + alpha, -2 cos w0, 1 - alpha] (normalised).
/// Unity gain at DC and Nyquist, zero at f0. Starts in the steady state of its
/// first input.
class BandStopFilter {
 public:
  BandStopFilter(double center_hz = 5.0, double q = 0.7, double sample_rate_hz = 50.0);
  double update(double x);
  void reset() { initialised_ = false; }
  const std::array<double, 3>& b() const { return b_; }
  const std::array<double, 3>& a() const { return a_; }  ///< a[0] == 1

 private:
  std::array<double, 3> b_{}, a_{};
  double x1_ = 0, x2_ = 0, y1_ = 0, y2_ = 0;
  bool initialised_ = false;
};

}  // namespace xplorer_force_est
