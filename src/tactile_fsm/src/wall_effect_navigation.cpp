// Wall-effect reactive navigation (004 eq. 12, wall following); see the header.
#include "tactile_fsm/wall_effect_navigation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace tactile_fsm {
namespace {

void positive(const char* f, double v) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument(std::string("WallEffectNavParams.") + f + ": must be finite and > 0, got " + std::to_string(v));
}
Vec2 rot(double a, const Vec2& v) {
  return Vec2(std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y());
}

}  // namespace

void WallEffectNavParams::validate() const {
  if (behaviour != "wall_following" && behaviour != "vector_field")
    throw std::invalid_argument("WallEffectNavParams.behaviour: must be 'wall_following' or 'vector_field', got '" + behaviour + "'");
  positive("average_window_s", average_window_s);
  positive("enter_distance", enter_distance);
  positive("follow_distance", follow_distance);
  if (follow_distance >= enter_distance)
    throw std::invalid_argument("WallEffectNavParams.follow_distance: must be < enter_distance (004: d* < d_dagger), got " + std::to_string(follow_distance));
  positive("follow_speed", follow_speed);
  positive("free_speed", free_speed);
  if (!(safety_distance >= 0.0) || !std::isfinite(safety_distance))
    throw std::invalid_argument("WallEffectNavParams.safety_distance: must be finite and >= 0, got " + std::to_string(safety_distance));
  positive("attract_speed", attract_speed);
  positive("repulse_gain", repulse_gain);
  if (!(repulse_base > 0.0 && repulse_base < 1.0))
    throw std::invalid_argument("WallEffectNavParams.repulse_base: must be in (0, 1), got " + std::to_string(repulse_base));
  positive("repulse_max", repulse_max);
  positive("repulse_distance", repulse_distance);
  positive("goal_tolerance", goal_tolerance);
  positive("height", height);
  if (!std::isfinite(yaw)) throw std::invalid_argument("WallEffectNavParams.yaw: must be finite");
}

const char* to_string(NavState s) {
  switch (s) {
    case NavState::kFreeFlight: return "FREE_FLIGHT";
    case NavState::kWallFollowing: return "WALL_FOLLOWING";
    case NavState::kVectorField: return "VECTOR_FIELD";
    case NavState::kGoalReached: return "GOAL_REACHED";
  }
  return "?";
}

MovingAverage::MovingAverage(double window_s, size_t capacity) : window_(window_s), buf_(capacity) {}

void MovingAverage::clear() {
  head_ = count_ = 0;
  sum_ = 0.0;
}

void MovingAverage::add(double t, double value) {
  // Drop samples older than the window, and the oldest if full.
  while (count_ > 0) {
    const size_t tail = (head_ + buf_.size() - count_) % buf_.size();
    if (t - buf_[tail].first <= window_ && count_ < buf_.size()) break;
    sum_ -= buf_[tail].second;
    --count_;
  }
  buf_[head_] = {t, value};
  head_ = (head_ + 1) % buf_.size();
  ++count_;
  sum_ += value;
}

double MovingAverage::value() const {
  return count_ ? sum_ / static_cast<double>(count_) : std::numeric_limits<double>::quiet_NaN();
}

double repulsive_speed(double y_hat, const WallEffectNavParams& p) {
  // 004 eq. 12: |v_minus| = 9e5 m/s (1.8e-35)^y_hat, saturated (choice).
  return std::min(p.repulse_max, p.repulse_gain * std::pow(p.repulse_base, std::max(0.0, y_hat)));
}

WallEffectNavigator::WallEffectNavigator(const WallEffectNavParams& params)
    : p_((params.validate(), params)), avg_(params.average_window_s) {
  if (p_.behaviour == "vector_field") state_ = NavState::kVectorField;
}

void WallEffectNavigator::go(NavState s) {
  if (s != state_) {
    state_ = s;
    ++transitions_;
  }
}

NavSetpoint WallEffectNavigator::step(const NavInput& in) {
  NavSetpoint sp;
  sp.height = p_.height;
  sp.yaw = p_.yaw;
  sp.position = in.position;
  sp.position_valid = goal_.is_position;
  if (in.wall_valid) avg_.add(in.t, in.wall_distance);
  const double y_bar = avg_.value();
  // Direction to the wall in the world, and the goal direction.
  const Vec2 u = rot(in.yaw, Vec2(std::cos(in.wall_direction), std::sin(in.wall_direction)));
  Vec2 to_goal(std::cos(goal_.direction), std::sin(goal_.direction));
  if (goal_.is_position) {
    const Vec2 d = goal_.position - in.position;
    if (state_ == NavState::kGoalReached || d.norm() < p_.goal_tolerance) {
      go(NavState::kGoalReached);
      sp.position = goal_.position;
      return sp;  // hold the goal
    }
    to_goal = d.normalized();
  }

  if (p_.behaviour == "vector_field") {
    // 004 eq. 12: p_dot_d = v_plus + v_minus.
    sp.velocity = p_.attract_speed * to_goal;
    if (in.wall_valid) {
      sp.velocity += -repulsive_speed(in.wall_distance, p_) * u;
      // Position term: only repulsion, below repulse_distance (004: 19 cm).
      if (in.wall_distance < p_.repulse_distance) {
        sp.position = in.position + (in.wall_distance - p_.repulse_distance) * u;
        sp.position_valid = true;
      }
    }
    return sp;
  }

  // Wall following.
  const bool near = in.wall_valid && ((std::isfinite(y_bar) && y_bar < p_.enter_distance) ||
                                      in.wall_distance < p_.safety_distance);
  if (state_ == NavState::kFreeFlight && near && to_goal.dot(u) > 0.0) go(NavState::kWallFollowing);
  if (state_ == NavState::kWallFollowing && (!near || to_goal.dot(u) < -0.2)) go(NavState::kFreeFlight);
  if (state_ == NavState::kFreeFlight) {
    sp.velocity = p_.free_speed * to_goal;
    return sp;
  }
  // Keep d* along the wall normal, v* along the wall towards the goal.
  const Vec2 tangent(-u.y(), u.x());
  const double sign = tangent.dot(to_goal) >= 0.0 ? 1.0 : -1.0;
  sp.position = in.position + (in.wall_distance - p_.follow_distance) * u;
  sp.position_valid = true;
  sp.velocity = sign * p_.follow_speed * tangent;
  return sp;
}

}  // namespace tactile_fsm
