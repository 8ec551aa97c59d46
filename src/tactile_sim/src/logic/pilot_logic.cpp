#include "tactile_sim/logic/pilot_logic.hpp"

#include <cmath>

#include "tactile_common/time.hpp"

namespace tactile_sim {

ScriptedPilotLogic::ScriptedPilotLogic(std::vector<PilotStep> script, VehicleType vehicle,
                                       const Vec3& initial_position, double initial_yaw)
    : script_(std::move(script)), vehicle_(vehicle), position_sp_(initial_position), yaw_sp_(initial_yaw) {
  for (size_t i = 0; i < script_.size(); ++i) {
    if (script_[i].kind == PilotStep::Kind::kPosition && vehicle_ == VehicleType::kWhiskerCrazyflie) {
      throw ScenarioError("pilot[" + std::to_string(i) +
                          "]: position steps need a position-controlled vehicle; the whiskered "
                          "Crazyflie flies hover (velocity) setpoints");
    }
  }
}

void ScriptedPilotLogic::on_whisker_signal(const tactile_msgs::msg::WhiskerSignal& msg) {
  if (msg.contact) contact_ = true;
}

void ScriptedPilotLogic::on_collision(const tactile_msgs::msg::CollisionEvent&) {
  if (vehicle_ != VehicleType::kWhiskerCrazyflie) contact_ = true;
}

void ScriptedPilotLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  odom_position_ = Vec3(p.x, p.y, p.z);
  odom_yaw_ = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  have_odom_ = true;
}

void ScriptedPilotLogic::start_step(int64_t now_ns) {
  step_start_ns_ = now_ns;
  contact_ = false;
  if (step_ >= script_.size()) return;
  const PilotStep& s = script_[step_];
  // Position vehicles: a new step starts from where the vehicle is, so a
  // setpoint that ran ahead (e.g. pressed against a wall) does not wind up.
  if (vehicle_ != VehicleType::kWhiskerCrazyflie && have_odom_) {
    position_sp_.x() = odom_position_.x();
    position_sp_.y() = odom_position_.y();
    yaw_sp_ = odom_yaw_;
  }
  if (s.kind == PilotStep::Kind::kTakeoff) {
    height_ = s.height;
    position_sp_.z() = s.height;
  } else if (s.kind == PilotStep::Kind::kPosition) {
    position_sp_ = s.position;
    yaw_sp_ = s.yaw;
    height_ = s.position.z();
  }
}

ScriptedPilotLogic::Outputs ScriptedPilotLogic::on_timer(int64_t now_ns) {
  if (!started_) {
    started_ = true;
    last_ns_ = now_ns;
    start_step(now_ns);
  }
  const double dt = tactile_common::to_seconds(now_ns - last_ns_);
  last_ns_ = now_ns;

  // Advance through finished steps.
  while (step_ < script_.size()) {
    const PilotStep& s = script_[step_];
    const double elapsed = tactile_common::to_seconds(now_ns - step_start_ns_);
    bool done = false;
    if (!s.until.empty()) {
      if (contact_) {
        done = true;
        if (std::isnan(stats_.contact_time_s)) stats_.contact_time_s = tactile_common::to_seconds(now_ns);
      } else if (elapsed >= s.timeout_s) {
        done = true;
        ++stats_.steps_timed_out;
      }
    }
    if (elapsed >= s.duration_s) done = true;
    if (s.kind == PilotStep::Kind::kTakeoff && !std::isfinite(s.duration_s) && elapsed >= 2.0) done = true;
    if (s.kind == PilotStep::Kind::kLand) done = false;  // the last thing a script does
    if (!done) break;
    ++stats_.steps_completed;
    ++step_;
    start_step(now_ns);
  }
  if (step_ >= script_.size() ||
      (step_ + 1 == script_.size() && script_[step_].kind == PilotStep::Kind::kLand)) {
    stats_.finished = true;
  }

  // Setpoint of the current step (the last step's once the script ran out).
  const PilotStep* s = step_ < script_.size() ? &script_[step_] : nullptr;
  Vec2 v = Vec2::Zero();
  double yaw_rate = 0.0;
  bool land = false;
  if (s) {
    if (s->kind == PilotStep::Kind::kVelocity) {
      v = s->velocity;
      yaw_rate = s->yaw_rate;
    }
    land = s->kind == PilotStep::Kind::kLand;
  }
  Outputs out;
  if (vehicle_ == VehicleType::kWhiskerCrazyflie) {
    tactile_msgs::msg::HoverSetpoint sp;
    tactile_common::to_stamp(now_ns, sp.header.stamp);
    sp.header.frame_id = "base_link";
    sp.vx = v.x();
    sp.vy = v.y();
    sp.yaw_rate = yaw_rate;
    sp.height = land ? 0.0 : height_;
    sp.land = land;
    out.hover = sp;
  } else {
    // Position vehicles: a moving position setpoint; body-yaw velocity
    // rotated into the world by the setpoint yaw.
    const double c = std::cos(yaw_sp_), sn = std::sin(yaw_sp_);
    position_sp_.x() += (c * v.x() - sn * v.y()) * dt;
    position_sp_.y() += (sn * v.x() + c * v.y()) * dt;
    yaw_sp_ += yaw_rate * dt;
    if (land) position_sp_.z() = 0.0;
    geometry_msgs::msg::PoseStamped sp;
    tactile_common::to_stamp(now_ns, sp.header.stamp);
    sp.header.frame_id = "odom";  // tracked with the vehicle's estimate (REP 105; was map)
    sp.pose.position.x = position_sp_.x();
    sp.pose.position.y = position_sp_.y();
    sp.pose.position.z = position_sp_.z();
    sp.pose.orientation.z = std::sin(yaw_sp_ / 2.0);
    sp.pose.orientation.w = std::cos(yaw_sp_ / 2.0);
    out.position = sp;
  }
  return out;
}

}  // namespace tactile_sim
