// Evaluation of the wall-effect EKF's published estimate against the
// simulator's /ground_truth/wall (paper 004 Fig. 4a), one implementation for
// the graph `wall_effect` (in flight, src/graphs/wall_effect.cpp) and for
// `tactile evaluate` (the same messages replayed from a bag, src/evaluate.cpp):
// RMSE of distance and direction while the vehicle is within 20 cm of the wall
// over the setpoint script's window (004: 1.8 cm, 13.6 deg over t = 10-70 s),
// NEES of (distance, direction) with the published covariance, and the
// tracking errors of the motion-capture odometry against the setpoint script
// (004: 1.7 cm, 0.4 deg).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>

#include "nav_msgs/msg/odometry.hpp"
#include "nlohmann/json.hpp"
#include "tactile_cli/executor.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"

namespace tactile_cli {

/// Running sum / sum of squares of a scalar error.
struct Accumulator {
  double sum = 0.0, sum2 = 0.0;
  size_t n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return n ? sum / static_cast<double>(n) : NAN; }
  double rms() const { return n ? std::sqrt(sum2 / static_cast<double>(n)) : NAN; }
  double std() const {
    if (n < 2) return NAN;
    const double m = mean();
    return std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - m * m));
  }
};

/// A finite number, else JSON null.
inline nlohmann::json json_number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

/// Angle wrapped to (-pi, pi].
inline double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

class WallEffectEvaluation {
 public:
  static constexpr const char* kTruthWallTopic = "ground_truth/wall";
  static constexpr const char* kTruthOdomTopic = "ground_truth/odom";
  static constexpr double kNearWall = 0.20;  ///< [m] 004: "within 20 cm from the wall"

  /// The window of the setpoint script: t = 10-70 s for 004's estimation
  /// flight, from 5 s after t_start otherwise.
  explicit WallEffectEvaluation(const wall_effect_ekf::TrajectoryParams& tp);

  /// Subscribes to the truth (/ground_truth/wall, /ground_truth/odom), the
  /// setpoint script and the EKF's estimate, in this order. `near_wall` is
  /// called for every estimate that was counted within 20 cm of the wall (the
  /// graph adds its full-state NEES there).
  void subscribe(Bus& bus, std::function<void(const tactile_msgs::msg::WallEstimate&)> near_wall = {});

  /// One estimate: counted when there is a detected true wall and its stamp is
  /// in the window. Returns true when it was within 20 cm of the wall.
  bool on_estimate(const tactile_msgs::msg::WallEstimate& est);

  /// mode, window_s, samples_within_20cm, rmse_distance_cm, rmse_direction_deg,
  /// mean_distance_error_cm, rmse_distance_all_cm, nees_distance_direction,
  /// tracking_rms_y_cm, tracking_rms_yaw_deg.
  void write(nlohmann::json& m) const;

  const tactile_msgs::msg::WallEstimate& truth() const { return truth_; }
  bool have_truth() const { return have_truth_; }
  const nav_msgs::msg::Odometry& odometry() const { return odom_; }
  bool have_odometry() const { return have_odom_; }

 private:
  std::string mode_;
  double t0_ = 0.0, t1_ = INFINITY;
  tactile_msgs::msg::WallEstimate truth_;
  nav_msgs::msg::Odometry odom_, sp_;
  bool have_truth_ = false, have_odom_ = false, have_sp_ = false;
  Accumulator dist_, dir_, all_dist_, nees_, track_y_, track_yaw_;
  std::function<void(const tactile_msgs::msg::WallEstimate&)> near_wall_;
};

}  // namespace tactile_cli
