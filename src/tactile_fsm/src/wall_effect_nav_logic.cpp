#include "tactile_fsm/wall_effect_nav_logic.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/time.hpp"
#include "tactile_fsm/geo_goal.hpp"
#include "tactile_common/geometry.hpp"

namespace tactile_fsm {

using tactile_common::ParamMap;

NavGoal WallEffectNavLogic::Params::goal() const {
  NavGoal g;
  if (goal_mode == "direction") {
    g.is_position = false;
    g.direction = direction_deg * M_PI / 180.0;
  } else if (goal_mode == "gps") {
    const auto enu = wgs84_to_enu(gps_origin, gps_goal);  // WGS84 -> local ENU (GeographicLib)
    g.position = Vec2(enu[0], enu[1]);
  } else {
    g.position = Vec2(goal_x, goal_y);
  }
  return g;
}

void WallEffectNavLogic::Params::validate() const {
  nav.validate();
  if (goal_mode != "position" && goal_mode != "gps" && goal_mode != "direction")
    throw std::invalid_argument("WallEffectNavLogic.goal_mode: must be 'position', 'gps' or 'direction', got '" + goal_mode + "'");
  if (!std::isfinite(goal_x) || !std::isfinite(goal_y) || !std::isfinite(direction_deg))
    throw std::invalid_argument("WallEffectNavLogic.goal_x: goal_x, goal_y and direction_deg must be finite");
  safety.validate("WallEffectNavLogic");  // max_input_age_s finite > 0, failsafe_land_after_s finite >= 0
  if (!(failsafe_land_speed > 0.0) || !std::isfinite(failsafe_land_speed)) {
    throw std::invalid_argument("WallEffectNavLogic.failsafe_land_speed: must be finite and > 0, got " +
                                std::to_string(failsafe_land_speed));
  }
  if (goal_mode == "gps") (void)goal();  // throws naming origin/point and the field
}

ParamMap WallEffectNavLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  const Params d;
  const WallEffectNavParams& n = d.nav;
  ParamMap m(kNodeName, "defaults");
  // The node's parameter spec (config/wall_effect_nav.yaml, docs/wall_effect_navigation.md):
  // value, description (from the WallEffectNavParams / Params comments; "choice" where 004
  // gives no value), unit and the range params_from()/validate() accept for the key alone
  // (follow_distance < enter_distance is validate()'s relation, named in the text). Every
  // key is read at start (ros2 param set: read-only): the y_hat average window and the
  // navigator's state are built from them.
  m.set("behaviour", n.behaviour,
        {"wall_following (004 \"Reactive navigation\", Fig. 3b) or vector_field (004 eq. 12)", "", {}, false,
         tactile_common::paper("004 \"Reactive navigation\", Fig. 3b; eq. 12")});
  m.set("average_window_s", n.average_window_s,
        {"Delta t, window of the average y_bar of y_hat (004: 1.5 s)", "s", positive(), false,
         tactile_common::paper("004 \"Collision avoidance flight\": Delta t = 1.5 s")});
  m.set("enter_distance", n.enter_distance,
        {"d_dagger, y_bar below this enters wall following (004: 20 cm); > follow_distance", "m", positive(), false,
         tactile_common::paper("004 \"Collision avoidance flight\": d = 20 cm")});
  m.set("follow_distance", n.follow_distance,
        {"d*, wall tracking distance (004: 17 cm); < enter_distance", "m", positive(), false,
         tactile_common::paper("004 \"Collision avoidance flight\": d* = 17 cm")});
  m.set("follow_speed", n.follow_speed, {"v*, speed along the wall (004: 10 or 25 cm/s)", "m/s", positive(), false,
        tactile_common::paper("004 \"Collision avoidance flight\": 10 or 25 cm/s")});
  m.set("free_speed", n.free_speed,
        {"free-flight speed towards the goal (004: approach at 10 cm/s)", "m/s", positive(), false,
         tactile_common::paper("004: approach at 10 cm/s")});
  m.set("safety_distance", n.safety_distance,
        {"also enter wall following at once when the raw y_hat is below this, without waiting for the average "
         "(choice: d_dagger); 0: off", "m", at_least(0.0), false, tactile_common::choice("d_dagger")});
  m.set("attract_speed", n.attract_speed, {"v_plus, attraction to the goal (004 eq. 12: 10 cm/s)", "m/s", positive(),
                                           false, tactile_common::paper("004 eq. 12: 10 cm/s")});
  m.set("repulse_gain", n.repulse_gain,
        {"v_minus = gain * base^y_hat (004 eq. 12: 9e5 m/s)", "m/s", positive(), false,
         tactile_common::paper("004 eq. 12: 9e5 m/s")});
  m.set("repulse_base", n.repulse_base,
        {"base of v_minus (004 eq. 12: 1.8e-35 per metre of y_hat)", "", ParamRange{0.0, 1.0, true, true}, false,
         tactile_common::paper("004 eq. 12: 1.8e-35")});
  m.set("repulse_max", n.repulse_max,
        {"saturation of v_minus (choice: eq. 12 tends to 9e5 m/s at the wall)", "m/s", positive(), false,
         tactile_common::choice()});
  m.set("repulse_distance", n.repulse_distance,
        {"the position term repulses only below this (004: 19 cm)", "m", positive(), false,
         tactile_common::paper("004 Fig. 9d: minimum y_hat of 19 cm")});
  m.set("goal_tolerance", n.goal_tolerance,
        {"goal reached within this horizontal distance (choice)", "m", positive(), false, tactile_common::choice()});
  m.set("height", n.height, {"flight height (004: 1.0 m)", "m", positive(), false,
        tactile_common::paper("004: 1.0 m")});
  m.set("yaw_deg", n.yaw * 180.0 / M_PI, {"psi_d, heading kept constant (004: 0); finite", "deg", {}, false,
        tactile_common::paper("004: psi_d = 0")});
  m.set("goal_mode", d.goal_mode,
        {"position (goal_x, goal_y in the world), gps (gps_goal as ENU of gps_origin, GeographicLib) or direction "
         "(pilot heading direction_deg)", "", {}, false, tactile_common::choice()});
  m.set("goal_x", d.goal_x, {"goal x in the world frame (goal_mode position); finite", "m", {}, false,
        tactile_common::choice()});
  m.set("goal_y", d.goal_y, {"goal y in the world frame (goal_mode position); finite", "m", {}, false,
        tactile_common::choice()});
  m.set("gps_origin", std::vector<double>(d.gps_origin.begin(), d.gps_origin.end()),
        {"[lat, lon, alt] of the local ENU origin (goal_mode gps; WGS84)", "deg, deg, m", {}, false,
         tactile_common::choice()});
  m.set("gps_goal", std::vector<double>(d.gps_goal.begin(), d.gps_goal.end()),
        {"[lat, lon, alt] of the goal (goal_mode gps; WGS84)", "deg, deg, m", {}, false, tactile_common::choice()});
  m.set("direction_deg", d.direction_deg,
        {"pilot heading direction in the world (goal_mode direction); finite", "deg", {}, false,
         tactile_common::choice()});
  m.set("max_input_age_s", d.safety.max_input_age_s,
        {"older odometry or wall estimate: FAILSAFE_HOVER where the drone was last known, until both are fresh "
         "again (choice)", "s", positive(), false, tactile_common::choice("10 ticks of the 50 Hz whisker FSM")});
  m.set("failsafe_land_after_s", d.safety.failsafe_land_after_s,
        {"FAILSAFE_HOVER this long -> FAILSAFE_LAND (choice: the whisker FSM's 2 s)", "s", at_least(0.0), false,
         tactile_common::choice("the whisker FSM's 2 s")});
  m.set("failsafe_land_speed", d.failsafe_land_speed,
        {"FAILSAFE_LAND: z velocity-only at minus this, x, y held; the INDI controller's thrust winds down on the "
         "floor (choice: the Crazyflie bridge's land_speed)", "m/s", positive(), false,
         tactile_common::choice("the Crazyflie bridge's land_speed")});
  return m;
}

WallEffectNavLogic::Params WallEffectNavLogic::params_from(const ParamMap& m) {
  Params p;
  WallEffectNavParams& n = p.nav;
  n.behaviour = m.get_string("behaviour");
  n.average_window_s = m.get_double("average_window_s");
  n.enter_distance = m.get_double("enter_distance");
  n.follow_distance = m.get_double("follow_distance");
  n.follow_speed = m.get_double("follow_speed");
  n.free_speed = m.get_double("free_speed");
  n.safety_distance = m.get_double("safety_distance");
  n.attract_speed = m.get_double("attract_speed");
  n.repulse_gain = m.get_double("repulse_gain");
  n.repulse_base = m.get_double("repulse_base");
  n.repulse_max = m.get_double("repulse_max");
  n.repulse_distance = m.get_double("repulse_distance");
  n.goal_tolerance = m.get_double("goal_tolerance");
  n.height = m.get_double("height");
  n.yaw = m.get_double("yaw_deg") * M_PI / 180.0;
  p.goal_mode = m.get_string("goal_mode");
  p.goal_x = m.get_double("goal_x");
  p.goal_y = m.get_double("goal_y");
  auto triple = [&m](const char* key) {
    const std::vector<double> v = m.get_double_array(key);
    if (v.size() != 3) throw m.error(key, "must be [lat_deg, lon_deg, alt_m], got " + std::to_string(v.size()) + " values");
    return std::array<double, 3>{{v[0], v[1], v[2]}};
  };
  p.gps_origin = triple("gps_origin");
  p.gps_goal = triple("gps_goal");
  p.direction_deg = m.get_double("direction_deg");
  p.safety.max_input_age_s = m.get_double("max_input_age_s");
  p.safety.failsafe_land_after_s = m.get_double("failsafe_land_after_s");
  p.failsafe_land_speed = m.get_double("failsafe_land_speed");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    std::string field = what.substr(0, what.find(':'));
    const std::string head = field.substr(0, field.find('.'));
    if (head == "WallEffectNavParams" || head == "WallEffectNavLogic") {
      field = field.substr(field.find('.') + 1);
      field = field.substr(0, field.find('.'));
    } else {
      field = head;
    }
    if (field == "origin") field = "gps_origin";
    if (field == "point") field = "gps_goal";
    if (field == "yaw") field = "yaw_deg";
    throw m.error(m.has(field) ? field : "goal_mode", what);
  }
  return p;
}

WallEffectNavLogic::WallEffectNavLogic(const Params& params)
    : params_((params.validate(), params)),
      nav_(params.nav),
      safety_(params.safety, {SafetyInput::kOdometry, SafetyInput::kWallEstimate}),
      last_state_(nav_.state()) {
  nav_.set_goal(params_.goal());
}

void WallEffectNavLogic::on_wall(const tactile_msgs::msg::WallEstimate& msg) {
  ++stats_.walls;
  if (!std::isfinite(msg.distance) || !std::isfinite(msg.direction)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  wall_distance_ = msg.distance;
  wall_direction_ = msg.direction;
  wall_ns_ = tactile_common::from_stamp(msg.header.stamp);
  have_wall_ = true;
}

void WallEffectNavLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.odometry;
  const auto& p = msg.pose.pose;
  const auto& q = p.orientation;
  if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) || !std::isfinite(q.w) || !std::isfinite(q.z) ||
      !std::isfinite(q.x) || !std::isfinite(q.y)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  position_ = Vec2(p.position.x, p.position.y);
  yaw_ = tactile_common::yaw_of(q);
  if (!msg.header.frame_id.empty()) odom_frame_ = msg.header.frame_id;
  odom_ns_ = tactile_common::from_stamp(msg.header.stamp);
  have_odom_ = true;
}

std::string WallEffectNavLogic::behaviour_name() const {
  return params_.nav.behaviour == "vector_field" ? "wall_effect_vector_field" : "wall_effect_following";
}

nav_msgs::msg::Odometry WallEffectNavLogic::failsafe_setpoint(int64_t now_ns, bool landing) const {
  nav_msgs::msg::Odometry m;
  tactile_common::to_stamp(now_ns, m.header.stamp);
  m.header.frame_id = odom_frame_;  // the frame of the odometry's positions
  m.child_frame_id = odom_frame_;   // the twist is a world velocity too
  m.pose.pose.position.x = hover_.x();
  m.pose.pose.position.y = hover_.y();
  m.pose.pose.orientation.z = std::sin(0.5 * params_.nav.yaw);
  m.pose.pose.orientation.w = std::cos(0.5 * params_.nav.yaw);
  if (landing) {
    // z velocity-only (NaN position: IndiControlLogic's velocity-only axis): the
    // descent needs no height, and on the floor the measured acceleration stays above
    // the commanded one, so INDI's incremental thrust (004 eq. 34) winds down to zero.
    m.pose.pose.position.z = std::numeric_limits<double>::quiet_NaN();
    m.twist.twist.linear.z = -params_.failsafe_land_speed;
  } else {
    m.pose.pose.position.z = params_.nav.height;  // zero velocity: hover
  }
  return m;
}

WallEffectNavLogic::Outputs WallEffectNavLogic::on_timer(int64_t now_ns) {
  Outputs out;
  ++stats_.ticks;
  const double t = tactile_common::to_seconds(now_ns);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double odom_stamp = have_odom_ ? tactile_common::to_seconds(odom_ns_) : nan;
  const double wall_stamp = have_wall_ ? tactile_common::to_seconds(wall_ns_) : nan;
  const double max_age = params_.safety.max_input_age_s;
  const bool odom_fresh = input_is_fresh(t, odom_stamp, max_age);
  if (!odom_fresh) ++stats_.ticks_without_odometry;
  if (have_wall_ && !input_is_fresh(t, wall_stamp, max_age)) ++stats_.ticks_wall_stale;
  // Guarded once both inputs have come: before the first wall estimate the navigator
  // flies without one (wall_valid false, as the EKF starts), before the first odometry
  // nothing is published (the INDI controller holds where it started).
  const SafetyVerdict v = safety_.step(t, {odom_stamp, wall_stamp}, have_odom_ && have_wall_);
  if (!v.nominal()) {
    if (v.entered) {
      ++safety_transitions_;
      if (v.state == SafetyState::kFailsafeHover) {
        ++stats_.failsafe_hovers;
        hover_ = position_;  // where the drone was last known (the odometry may be the stale input)
        previous_state_ = to_string(nav_.state());
      } else {
        ++stats_.failsafe_landings;
        previous_state_ = "FAILSAFE_HOVER";
      }
      reason_ = v.text;
      reason_code_ = static_cast<uint8_t>(v.reason);
      state_since_ns_ = now_ns;
    }
    out.setpoint = failsafe_setpoint(now_ns, v.landing());
    if (v.entered || now_ns - last_state_pub_ns_ >= 500'000'000) {
      tactile_msgs::msg::FsmState s;
      tactile_common::to_stamp(now_ns, s.header.stamp);
      s.behaviour = behaviour_name();
      s.state = to_string(v.state);
      s.previous_state = previous_state_;
      s.reason = reason_;
      s.reason_code = reason_code_;
      s.time_in_state = tactile_common::to_seconds(now_ns - state_since_ns_);
      s.transitions = nav_.transitions() + safety_transitions_;
      out.state = s;
      last_state_pub_ns_ = now_ns;
    }
    return out;
  }
  if (!odom_fresh) return out;  // not guarded yet (no wall estimate so far): nothing to steer by
  if (v.resumed) {
    ++safety_transitions_;
    previous_state_ = "FAILSAFE_HOVER";
    reason_ = v.text;
    reason_code_ = static_cast<uint8_t>(v.reason);
    state_since_ns_ = now_ns;
  }
  NavInput in;
  in.t = t;
  in.wall_valid = have_wall_;
  in.wall_distance = wall_distance_;
  in.wall_direction = wall_direction_;
  in.position = position_;
  in.yaw = yaw_;
  const NavSetpoint sp = nav_.step(in);
  nav_msgs::msg::Odometry m;
  tactile_common::to_stamp(now_ns, m.header.stamp);
  m.header.frame_id = odom_frame_;  // positions from the odometry's (was map)
  m.child_frame_id = odom_frame_;   // the twist is a world velocity, not a body one
  m.pose.pose.position.x = sp.position_valid ? sp.position.x() : nan;
  m.pose.pose.position.y = sp.position_valid ? sp.position.y() : nan;
  m.pose.pose.position.z = sp.height;
  m.pose.pose.orientation.z = std::sin(0.5 * sp.yaw);
  m.pose.pose.orientation.w = std::cos(0.5 * sp.yaw);
  m.twist.twist.linear.x = sp.velocity.x();
  m.twist.twist.linear.y = sp.velocity.y();
  out.setpoint = m;
  const bool changed = nav_.state() != last_state_;
  if (changed) {
    previous_state_ = to_string(last_state_);
    reason_ = nav_.state() == NavState::kWallFollowing ? "y_bar below d_dagger"
              : nav_.state() == NavState::kGoalReached ? "goal reached"
                                                       : "y_bar above d_dagger or goal away from the wall";
    reason_code_ = tactile_msgs::msg::FsmState::REASON_NONE;  // the navigator's transitions have no codes
    last_state_ = nav_.state();
    state_since_ns_ = now_ns;
  }
  if (changed || v.resumed || last_state_pub_ns_ < 0 || now_ns - last_state_pub_ns_ >= 500'000'000) {
    tactile_msgs::msg::FsmState s;
    tactile_common::to_stamp(now_ns, s.header.stamp);
    s.behaviour = behaviour_name();
    s.state = to_string(nav_.state());
    s.previous_state = previous_state_;
    s.reason = reason_;
    s.reason_code = reason_code_;
    s.time_in_state = tactile_common::to_seconds(now_ns - state_since_ns_);
    s.transitions = nav_.transitions() + safety_transitions_;
    out.state = s;
    last_state_pub_ns_ = now_ns;
  }
  return out;
}

}  // namespace tactile_fsm
