// Reactive navigation of the ducted quadrotor on the wall-effect estimate
// (paper 004, "Reactive navigation with aerodynamics-based collision
// avoidance", Fig. 3b, eq. 12).
//
// Two behaviours turn the EKF's wall estimate {y_hat, psi_hat} and the
// vehicle's pose into a setpoint of the INDI controller:
//
// - Wall following (bug-like): the moving average y_bar of y_hat over
//   Delta t = 1.5 s decides the mode. y_bar < d_dagger = 20 cm: follow the
//   wall, keeping d* = 17 cm along the estimated wall normal
//   (e2^T p_d = d*, e2^T p_dot_d = 0 in the wall frame) and the speed v*
//   (10 or 25 cm/s) along the wall towards the goal. Otherwise free flight
//   towards the goal (position goal: motion capture / GPS) or along the
//   pilot's direction. Wall following ends when y_bar rises above d_dagger
//   or the goal lies away from the wall.
// - Vector field (eq. 12): p_dot_d = v_plus + v_minus, v_plus of size 0.1 m/s
//   towards the goal, v_minus = 9e5 (1.8e-35)^y_hat m/s along the wall
//   normal away from the wall; the position term only repulses (below
//   19 cm).
//
// Directions: psi_hat is the direction from the vehicle to the wall in the
// body frame (WallEstimate.direction); u_w = Rz(yaw) (cos psi_hat, sin psi_hat)
// is that direction in the world. A setpoint's position is p_d; along the
// wall its component equals the current position (so only the velocity
// feed-forward moves the vehicle there), across the wall it sets the
// distance. Core layer: no ROS, no messages, no allocation per tick.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace tactile_fsm {

using Vec2 = Eigen::Vector2d;

struct WallEffectNavParams {
  std::string behaviour = "wall_following";  ///< "wall_following" or "vector_field"
  // Wall following (004: "we set the time window Delta t for y_bar as 1.5 s,
  // the decision threshold as d_dagger = 20 cm, and the wall tracking distance
  // of d* = 17 cm"; "v* is either 10 or 25 cm/s").
  double average_window_s = 1.5;
  double enter_distance = 0.20;   ///< d_dagger [m]
  double follow_distance = 0.17;  ///< d* [m]
  double follow_speed = 0.10;     ///< v* [m/s]
  double free_speed = 0.10;       ///< free-flight speed towards the goal [m/s] (004: approach at 10 cm/s)
  /// Also enter wall following when the raw y_hat is below this, without
  /// waiting for the 1.5 s average (choice: approaching at 10 cm/s the
  /// average lags ~7.5 cm, so the vehicle would reach ~12 cm first; 0 = off).
  /// d_dagger: entering at d* = 17 cm instead left an overshoot of ~2.7 cm,
  /// which at psi_d = 30 / 45 deg put a duct guard on the wall (SITL).
  double safety_distance = 0.20;
  // Vector field (004 eq. 12).
  double attract_speed = 0.10;    ///< v_plus [m/s] (004: 10 cm/s)
  double repulse_gain = 9.0e5;    ///< v_minus = gain base^y_hat [m/s] (004: 9e5 m/s)
  double repulse_base = 1.8e-35;  ///< (004: 1.8e-35 per metre)
  double repulse_max = 0.5;       ///< saturation of v_minus [m/s] (choice: eq. 12 tends to 9e5 m/s)
  double repulse_distance = 0.19; ///< position term repulses only below this [m] (004: 19 cm)
  // Goal.
  double goal_tolerance = 0.10;   ///< goal reached within this horizontal distance [m] (choice)
  double height = 1.0;            ///< flight height [m] (004: 1.0 m)
  double yaw = 0.0;               ///< psi_d, kept constant [rad] (004: psi_d = 0)

  void validate() const;          ///< throws std::invalid_argument naming the field
};

enum class NavState : uint8_t { kFreeFlight, kWallFollowing, kVectorField, kGoalReached };
const char* to_string(NavState s);

struct NavInput {
  double t = 0.0;                 ///< [s]
  bool wall_valid = false;        ///< a wall estimate is available (y_hat, psi_hat finite)
  double wall_distance = 0.0;     ///< y_hat [m]
  double wall_direction = 0.0;    ///< psi_hat, body frame [rad]
  Vec2 position = Vec2::Zero();   ///< world (motion capture / GPS ENU) [m]
  double yaw = 0.0;               ///< vehicle heading [rad]
};

/// The goal: a position (world) or a direction (a pilot's heading, world).
struct NavGoal {
  bool is_position = true;
  Vec2 position = Vec2::Zero();
  double direction = 0.0;         ///< [rad], world
};

struct NavSetpoint {
  Vec2 position = Vec2::Zero();   ///< p_d (horizontal) [m]
  bool position_valid = true;     ///< false: velocity-only (pilot direction, no positioning)
  Vec2 velocity = Vec2::Zero();   ///< p_dot_d [m/s]
  double height = 1.0;
  double yaw = 0.0;
};

/// Moving average of y_hat over a time window (004: y_bar(t) = 1/Delta t int y_hat).
/// Fixed capacity ring buffer (no allocation after construction).
class MovingAverage {
 public:
  MovingAverage(double window_s, size_t capacity = 1024);
  void add(double t, double value);
  double value() const;           ///< NaN when empty
  size_t size() const { return count_; }
  void clear();

 private:
  double window_;
  std::vector<std::pair<double, double>> buf_;
  size_t head_ = 0, count_ = 0;
  double sum_ = 0.0;
};

/// v_minus of 004 eq. 12 (magnitude, saturated).
double repulsive_speed(double y_hat, const WallEffectNavParams& p);

class WallEffectNavigator {
 public:
  explicit WallEffectNavigator(const WallEffectNavParams& params);
  void set_goal(const NavGoal& goal) { goal_ = goal; }
  NavSetpoint step(const NavInput& in);
  NavState state() const { return state_; }
  double averaged_distance() const { return avg_.value(); }
  uint32_t transitions() const { return transitions_; }
  const WallEffectNavParams& params() const { return p_; }

 private:
  void go(NavState s);
  WallEffectNavParams p_;
  NavGoal goal_;
  MovingAverage avg_;
  NavState state_ = NavState::kFreeFlight;
  uint32_t transitions_ = 0;
};

}  // namespace tactile_fsm
