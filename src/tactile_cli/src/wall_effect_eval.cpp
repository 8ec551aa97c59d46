#include "tactile_cli/wall_effect_eval.hpp"

#include <utility>

#include "tactile_common/geometry.hpp"
#include "tactile_common/time.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"

namespace tactile_cli {

WallEffectEvaluation::WallEffectEvaluation(const wall_effect_ekf::TrajectoryParams& tp) : mode_(tp.mode) {
  if (tp.mode == "estimation_flight") {
    t0_ = 10.0;  // 004: RMSE over t = 10 s to 70 s
    t1_ = 70.0;
  } else {
    t0_ = tp.t_start + 5.0;
    t1_ = INFINITY;
  }
}

void WallEffectEvaluation::subscribe(Bus& bus, std::function<void(const tactile_msgs::msg::WallEstimate&)> near_wall) {
  near_wall_ = std::move(near_wall);
  bus.subscribe<tactile_msgs::msg::WallEstimate>(kTruthWallTopic, [this](const tactile_msgs::msg::WallEstimate& m) {
    truth_ = m;
    have_truth_ = true;
  });
  bus.subscribe<nav_msgs::msg::Odometry>(kTruthOdomTopic, [this](const nav_msgs::msg::Odometry& m) {
    odom_ = m;
    have_odom_ = true;
  });
  bus.subscribe<nav_msgs::msg::Odometry>(wall_effect_ekf::WallTrajectoryLogic::kOutputTopic,
                                         [this](const nav_msgs::msg::Odometry& m) {
                                           sp_ = m;
                                           have_sp_ = true;
                                         });
  bus.subscribe<tactile_msgs::msg::WallEstimate>(
      wall_effect_ekf::WallEffectEkfLogic::kOutputTopic, [this](const tactile_msgs::msg::WallEstimate& m) {
        if (on_estimate(m) && near_wall_) near_wall_(m);
      });
}

bool WallEffectEvaluation::on_estimate(const tactile_msgs::msg::WallEstimate& est) {
  if (!have_truth_ || !truth_.wall_detected) return false;
  const double t = tactile_common::to_seconds(tactile_common::from_stamp(est.header.stamp));
  if (t < t0_ || t > t1_) return false;
  const double e_d = est.distance - truth_.distance;
  const double e_a = wrap_angle(est.direction - truth_.direction);
  all_dist_.add(e_d);
  const bool near = truth_.distance < kNearWall;
  if (near) {
    dist_.add(e_d);
    dir_.add(e_a * 180.0 / M_PI);
    // NEES of (distance, direction) with the published covariance.
    const double a = est.covariance[0], b = est.covariance[1], d = est.covariance[4];
    const double det = a * d - b * b;
    if (det > 0.0) nees_.add((d * e_d * e_d - 2.0 * b * e_d * e_a + a * e_a * e_a) / det);
  }
  if (have_odom_ && have_sp_) {
    track_y_.add(odom_.pose.pose.position.y - sp_.pose.pose.position.y);
    const auto& q = odom_.pose.pose.orientation;
    const auto& qs = sp_.pose.pose.orientation;
    const double yaw = tactile_common::yaw_of(q);
    const double yaw_sp = 2.0 * std::atan2(qs.z, qs.w);
    track_yaw_.add(wrap_angle(yaw - yaw_sp) * 180.0 / M_PI);
  }
  return near;
}

void WallEffectEvaluation::write(nlohmann::json& m) const {
  m["mode"] = mode_;
  m["window_s"] = {t0_, std::isfinite(t1_) ? nlohmann::json(t1_) : nlohmann::json(nullptr)};
  m["samples_within_20cm"] = dist_.n;
  m["rmse_distance_cm"] = json_number(100.0 * dist_.rms());
  m["rmse_direction_deg"] = json_number(dir_.rms());
  m["mean_distance_error_cm"] = json_number(100.0 * dist_.mean());
  m["rmse_distance_all_cm"] = json_number(100.0 * all_dist_.rms());
  m["nees_distance_direction"] = json_number(nees_.mean());  // 2 for a consistent filter
  m["tracking_rms_y_cm"] = json_number(100.0 * track_y_.rms());
  m["tracking_rms_yaw_deg"] = json_number(track_yaw_.rms());
}

}  // namespace tactile_cli
