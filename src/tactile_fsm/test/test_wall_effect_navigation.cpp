// Wall-effect behaviours (004): moving average, eq. 12 by hand, WGS84 -> ENU,
// and closed loops on a kinematic vehicle with the true wall distance and
// direction (the estimator is tested in wall_effect_ekf): wall following
// holds d* at v*, a 95 deg corner, a convex obstacle bypassed to the goal, the
// vector field through three round obstacles.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "tactile_fsm/geo_goal.hpp"
#include "tactile_fsm/wall_effect_nav_logic.hpp"
#include "tactile_fsm/wall_effect_navigation.hpp"

using namespace tactile_fsm;

TEST(MovingAverage, AveragesOverTheWindow) {
  MovingAverage a(1.5);
  EXPECT_TRUE(std::isnan(a.value()));
  for (int k = 0; k <= 100; ++k) a.add(0.01 * k, k < 50 ? 1.0 : 3.0);  // 0..1 s
  EXPECT_NEAR(a.value(), (50 * 1.0 + 51 * 3.0) / 101.0, 1e-12);
  for (int k = 101; k <= 300; ++k) a.add(0.01 * k, 3.0);  // the 1.0s leave the 1.5 s window
  EXPECT_NEAR(a.value(), 3.0, 1e-12);
}

TEST(VectorField, Eq12ByHand) {
  WallEffectNavParams p;
  p.repulse_max = 1e9;
  // 9e5 * (1.8e-35)^0.2 = 9e5 * exp(0.2 ln 1.8e-35)
  EXPECT_NEAR(repulsive_speed(0.2, p), 9e5 * std::exp(0.2 * std::log(1.8e-35)), 1e-12);
  EXPECT_NEAR(repulsive_speed(0.0, p), 9e5, 1e-6);
  p.repulse_max = 0.5;
  EXPECT_EQ(repulsive_speed(0.0, p), 0.5);
  // Equal to v_plus = 0.1 m/s at y_hat = ln(0.1 / 9e5) / ln(1.8e-35) = 0.200 m
  // (004 quotes 17.1 cm for this crossing; the formula as printed gives 20.0 cm).
  const double y_eq = std::log(0.1 / 9e5) / std::log(1.8e-35);
  EXPECT_NEAR(y_eq, 0.2001, 1e-3);
  EXPECT_NEAR(repulsive_speed(y_eq, p), 0.1, 1e-9);
}

TEST(GeoGoal, Wgs84ToEnuByHandAtTheEquator) {
  // 0.001 deg of longitude at the equator: a * pi / 180 * 0.001 (a = 6378137 m).
  auto e = wgs84_to_enu({0.0, 0.0, 0.0}, {0.0, 0.001, 0.0});
  EXPECT_NEAR(e[0], 6378137.0 * M_PI / 180.0 * 0.001, 0.01);
  EXPECT_NEAR(e[1], 0.0, 1e-6);
  // 0.001 deg of latitude: meridian radius a (1 - e^2) at the equator.
  const double e2 = 0.00669437999014;
  e = wgs84_to_enu({0.0, 0.0, 0.0}, {0.001, 0.0, 0.0});
  EXPECT_NEAR(e[1], 6378137.0 * (1 - e2) * M_PI / 180.0 * 0.001, 0.01);
  EXPECT_THROW(wgs84_to_enu({91.0, 0.0, 0.0}, {0.0, 0.0, 0.0}), std::invalid_argument);
}

namespace {

/// Straight walls (segments) and circles; distance and direction to the nearest.
struct World {
  struct Seg { Vec2 a, b; };
  struct Circle { Vec2 c; double r; };
  std::vector<Seg> segs;
  std::vector<Circle> circles;
  /// Nearest surface point from p: distance and world direction.
  double nearest(const Vec2& p, Vec2& dir) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& s : segs) {
      const Vec2 ab = s.b - s.a;
      const double t = std::clamp((p - s.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const Vec2 q = s.a + t * ab;
      if ((q - p).norm() < best) {
        best = (q - p).norm();
        dir = (q - p).normalized();
      }
    }
    for (const auto& c : circles) {
      const double d = (c.c - p).norm() - c.r;
      if (d < best) {
        best = d;
        dir = (c.c - p).normalized();
      }
    }
    return best;
  }
};

struct FlightResult {
  bool reached = false;
  double min_distance = std::numeric_limits<double>::infinity();
  double rms_follow_error = 0.0;
  double follow_time = 0.0;
  double mean_follow_speed = 0.0;
};

/// Kinematic vehicle: velocity follows p_dot_d + K_p (p_d - p) with a 0.3 s lag;
/// the wall estimate is the truth within 0.6 m (the EKF's range), noise-free.
FlightResult fly(const WallEffectNavParams& p, const World& w, Vec2 pos, const NavGoal& goal, double duration) {
  WallEffectNavigator nav(p);
  nav.set_goal(goal);
  Vec2 v = Vec2::Zero();
  FlightResult r;
  double sum_e2 = 0.0, sum_speed = 0.0;
  int n_follow = 0;
  const double dt = 0.01;
  const double yaw = 0.3;  // a constant heading, not aligned with anything
  for (double t = 0.0; t < duration; t += dt) {
    Vec2 dir;
    const double d = w.nearest(pos, dir);
    r.min_distance = std::min(r.min_distance, d);
    NavInput in;
    in.t = t;
    in.position = pos;
    in.yaw = yaw;
    in.wall_valid = true;
    in.wall_distance = std::min(d, 0.6);
    const Vec2 db(std::cos(-yaw) * dir.x() - std::sin(-yaw) * dir.y(), std::sin(-yaw) * dir.x() + std::cos(-yaw) * dir.y());
    in.wall_direction = std::atan2(db.y(), db.x());
    const NavSetpoint sp = nav.step(in);
    Vec2 v_cmd = sp.velocity + (sp.position_valid ? Vec2(2.0 * (sp.position - pos)) : Vec2::Zero());
    v += (v_cmd - v) * (dt / 0.3);
    pos += v * dt;
    if (nav.state() == NavState::kWallFollowing && t > 1.0) {
      sum_e2 += (d - p.follow_distance) * (d - p.follow_distance);
      sum_speed += std::abs(v.dot(Vec2(-dir.y(), dir.x())));
      ++n_follow;
    }
    if (nav.state() == NavState::kGoalReached) {
      r.reached = true;
      break;
    }
  }
  if (n_follow > 0) {
    r.rms_follow_error = std::sqrt(sum_e2 / n_follow);
    r.mean_follow_speed = sum_speed / n_follow;
    r.follow_time = n_follow * dt;
  }
  return r;
}

}  // namespace

TEST(WallFollowing, EntersBelowDDaggerHoldsDStarAtVStar) {
  WallEffectNavParams p;  // 1.5 s, 20 cm, 17 cm, 10 cm/s
  World w;
  w.segs.push_back({Vec2(-5, 0), Vec2(5, 0)});
  NavGoal g;  // goal straight behind the wall, to the right: the wall must be followed
  g.position = Vec2(10.0, -5.0);
  const FlightResult r = fly(p, w, Vec2(0.0, 0.5), g, 40.0);
  EXPECT_GT(r.follow_time, 10.0);
  EXPECT_LT(r.rms_follow_error, 0.01);
  EXPECT_NEAR(r.mean_follow_speed, 0.10, 0.01);
  EXPECT_GT(r.min_distance, 0.15);
  EXPECT_FALSE(r.reached);  // the goal is behind the wall
}

TEST(WallFollowing, NegotiatesA95DegreeCornerAndReachesTheGoal) {
  WallEffectNavParams p;
  p.follow_speed = 0.25;
  World w;  // wall along x (y = 0) up to x = 1, then a 95 deg corner away from the vehicle
  const double a = (180.0 - 95.0) * M_PI / 180.0;
  w.segs.push_back({Vec2(-3, 0), Vec2(1, 0)});
  w.segs.push_back({Vec2(1, 0), Vec2(1 + 3 * std::cos(-a), 3 * std::sin(-a))});
  NavGoal g;
  g.position = Vec2(3.0, -2.0);  // around the corner
  const FlightResult r = fly(p, w, Vec2(-1.0, 0.45), g, 120.0);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.min_distance, 0.10);  // no collision: the ducts reach 0.13 m from the centre at most
}

TEST(WallFollowing, BypassesAConvexObstacleToTheGoal) {
  WallEffectNavParams p;
  World w;
  w.circles.push_back({Vec2(1.5, 0.0), 0.5});
  NavGoal g;
  g.position = Vec2(3.5, 0.0);
  const FlightResult r = fly(p, w, Vec2(0.0, 0.05), g, 150.0);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.min_distance, 0.12);
}

TEST(VectorField, ThreeRoundObstaclesNoCollisionGoalReached) {
  WallEffectNavParams p;
  p.behaviour = "vector_field";
  World w;  // 004 Fig. 8 style: three round obstacles of radius 0.8 m
  w.circles.push_back({Vec2(1.5, 0.3), 0.8});
  w.circles.push_back({Vec2(3.0, -1.6), 0.8});
  w.circles.push_back({Vec2(4.5, 0.9), 0.8});
  NavGoal g;
  g.position = Vec2(6.5, 0.0);
  const FlightResult r = fly(p, w, Vec2(-1.0, 0.0), g, 200.0);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.min_distance, 0.13);
}

TEST(WallFollowing, PilotDirectionIsVelocityOnly) {
  WallEffectNavParams p;
  WallEffectNavigator nav(p);
  NavGoal g;
  g.is_position = false;
  g.direction = M_PI / 2;
  nav.set_goal(g);
  NavInput in;
  in.wall_valid = true;
  in.wall_distance = 0.6;
  const NavSetpoint sp = nav.step(in);
  EXPECT_FALSE(sp.position_valid);
  EXPECT_NEAR(sp.velocity.x(), 0.0, 1e-12);
  EXPECT_NEAR(sp.velocity.y(), 0.10, 1e-12);
}

TEST(WallEffectNavLogic, ParametersAndGpsGoal) {
  auto m = WallEffectNavLogic::default_parameters();
  m.set("goal_mode", std::string("gps"));
  m.set("gps_origin", std::vector<double>{52.0, 4.37, 0.0});
  m.set("gps_goal", std::vector<double>{52.0, 4.37 + 0.0001, 0.0});
  const auto p = WallEffectNavLogic::params_from(m);
  const NavGoal g = p.goal();
  EXPECT_GT(g.position.x(), 6.0);  // ~6.87 m east at 52 deg N
  EXPECT_LT(g.position.x(), 7.5);
  EXPECT_NEAR(g.position.y(), 0.0, 0.01);
  m.set("gps_goal", std::vector<double>{95.0, 0.0, 0.0});
  try {
    WallEffectNavLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("gps_goal"), std::string::npos) << e.what();
  }
  m = WallEffectNavLogic::default_parameters();
  m.set("follow_distance", 0.25);  // >= d_dagger
  EXPECT_THROW(WallEffectNavLogic::params_from(m), tactile_common::ParamError);
}

TEST(WallEffectNavLogic, PublishesSetpointsAndStates) {
  WallEffectNavLogic logic(WallEffectNavLogic::params_from(WallEffectNavLogic::default_parameters()));
  EXPECT_FALSE(logic.on_timer(0).setpoint.has_value());  // no odometry yet
  nav_msgs::msg::Odometry o;
  o.pose.pose.orientation.w = 1.0;
  o.pose.pose.position.x = NAN;
  logic.on_odometry(o);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 1u);
  o.pose.pose.position.x = -1.0;
  o.header.frame_id = "cf1/odom";
  o.child_frame_id = "cf1/base_link";
  logic.on_odometry(o);
  const auto out = logic.on_timer(10'000'000);
  ASSERT_TRUE(out.setpoint.has_value());
  ASSERT_TRUE(out.state.has_value());
  EXPECT_EQ(out.state->state, "FREE_FLIGHT");
  EXPECT_NEAR(out.setpoint->twist.twist.linear.x, 0.10, 1e-12);  // towards the goal at the origin
  // Positions and velocity in the odometry's frame (it was labelled map).
  EXPECT_EQ(out.setpoint->header.frame_id, "cf1/odom");
  EXPECT_EQ(out.setpoint->child_frame_id, "cf1/odom");
}

TEST(WallEffectNavLogic, RepoConfigEqualsDefaults) {
  const auto d = WallEffectNavLogic::default_parameters();
  const std::string file = "../../config/wall_effect_nav.yaml";
  const auto f = tactile_common::load_node_parameters(file, "/wall_effect_nav", d);
  for (const auto& [key, value] : d.values()) {
    EXPECT_EQ(f.origin(key), file) << key << " not set in " << file;
    EXPECT_TRUE(value == f.values().at(key)) << key;
  }
}

// Every key carries a description, a unit and the range params_from()/validate() accept
// for it alone (never wider: a value just outside each end is refused); all read at start.
TEST(WallEffectNavLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const tactile_common::ParamMap d = WallEffectNavLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak : tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) {
         WallEffectNavLogic::params_from(m);
       })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  // An unbounded range means every finite value: infinity itself is refused.
  for (const auto& leak : tactile_common::infinities_accepted(d, [](const tactile_common::ParamMap& m) {
         WallEffectNavLogic::params_from(m);
       })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is accepted";
  }
  ASSERT_NE(d.info("repulse_base"), nullptr);
  EXPECT_EQ(d.info("repulse_base")->range->text(), "(0, 1)");  // 004 eq. 12: a base below 1
  ASSERT_NE(d.info("follow_distance"), nullptr);
  EXPECT_EQ(d.info("follow_distance")->unit, "m");
  EXPECT_EQ(d.info("follow_distance")->range->text(), "(0, inf)");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

// Issue 33 (stale inputs): the wall estimate stops (the EKF's thrust / IMU
// went stale, or the node died) while odometry keeps coming. The navigator
// steered by the last distance forever; now the logic hovers at the current
// position (zero velocity) from the first tick the estimate is older than
// max_input_age_s, says FAILSAFE_HOVER / "wall estimate stale", and resumes
// when estimates come again.
TEST(WallEffectNavLogic, StaleWallEstimateHoversAndResumes) {
  WallEffectNavLogic logic(WallEffectNavLogic::params_from(WallEffectNavLogic::default_parameters()));
  const double age = logic.params().safety.max_input_age_s;
  const int64_t last_wall_ns = 500'000'000, resume_ns = 1'000'000'000;
  bool moved_when_stale = false, normal_before = true, saw_failsafe = false, resumed = false;
  std::string failsafe_reason;
  double x = -1.0;
  for (int64_t ns = 0; ns <= 1'200'000'000; ns += WallEffectNavLogic::kTimerPeriodNs) {
    nav_msgs::msg::Odometry o;
    tactile_common::to_stamp(ns, o.header.stamp);
    o.pose.pose.orientation.w = 1.0;
    o.pose.pose.position.x = x;
    logic.on_odometry(o);
    if (ns <= last_wall_ns || ns >= resume_ns) {
      tactile_msgs::msg::WallEstimate w;
      tactile_common::to_stamp(ns, w.header.stamp);
      w.distance = 0.6;  // a wall 0.6 m ahead: free flight toward the goal at the origin
      w.direction = 0.0;
      logic.on_wall(w);
    }
    const auto out = logic.on_timer(ns);
    ASSERT_TRUE(out.setpoint.has_value());
    const double v = std::hypot(out.setpoint->twist.twist.linear.x, out.setpoint->twist.twist.linear.y);
    const bool stale = ns > last_wall_ns + tactile_common::from_seconds(age) && ns < resume_ns;
    if (stale) {
      moved_when_stale = moved_when_stale || v != 0.0 || out.setpoint->pose.pose.position.x != x;
    } else if (ns <= last_wall_ns + tactile_common::from_seconds(age)) {
      normal_before = normal_before && v > 0.0;
    }
    if (out.state && out.state->state == "FAILSAFE_HOVER" && !saw_failsafe) {
      saw_failsafe = true;
      failsafe_reason = out.state->reason;
      EXPECT_EQ(out.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_WALL_ESTIMATE_STALE);
      EXPECT_EQ(out.state->previous_state, "FREE_FLIGHT");
      EXPECT_EQ(ns, last_wall_ns + tactile_common::from_seconds(age) + WallEffectNavLogic::kTimerPeriodNs);
    }
    if (ns == resume_ns) {  // the shared fail-safe's resume, published on the tick
      ASSERT_TRUE(out.state.has_value());
      EXPECT_EQ(out.state->state, "FREE_FLIGHT");
      EXPECT_EQ(out.state->previous_state, "FAILSAFE_HOVER");
      EXPECT_EQ(out.state->reason, "inputs fresh again");
      EXPECT_EQ(out.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_INPUTS_FRESH);
      resumed = true;
    }
    EXPECT_FALSE(out.state && out.state->state == "FAILSAFE_LAND") << "0.5 s of stale input is no landing";
    if (ns >= resume_ns) {
      EXPECT_GT(v, 0.0);
    }
    x += 0.01 * out.setpoint->twist.twist.linear.x;
  }
  EXPECT_TRUE(normal_before);
  EXPECT_FALSE(moved_when_stale) << "steered by a wall estimate older than max_input_age_s";
  EXPECT_TRUE(saw_failsafe);
  EXPECT_EQ(failsafe_reason, "wall estimate stale");
  EXPECT_TRUE(resumed);
  EXPECT_GT(logic.stats().ticks_wall_stale, 0u);
}

namespace {
constexpr int64_t kNavTick = WallEffectNavLogic::kTimerPeriodNs;

nav_msgs::msg::Odometry nav_odom(int64_t ns, double x, double y) {
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ns, o.header.stamp);
  o.header.frame_id = "odom";
  o.pose.pose.orientation.w = 1.0;
  o.pose.pose.position.x = x;
  o.pose.pose.position.y = y;
  return o;
}
tactile_msgs::msg::WallEstimate nav_wall(int64_t ns) {
  tactile_msgs::msg::WallEstimate w;
  tactile_common::to_stamp(ns, w.header.stamp);
  w.distance = 0.6;  // a wall 0.6 m ahead: free flight toward the goal at the origin
  w.direction = 0.0;
  return w;
}

/// One input stops at `stop_ns` for good (odometry if `odometry`, else the wall estimate);
/// returns every tick's setpoint and state message from the start to `end_ns`, the
/// drone at x = -1 + the integrated setpoint velocity while the odometry comes.
struct NavTick {
  int64_t ns;
  nav_msgs::msg::Odometry sp;
  std::optional<tactile_msgs::msg::FsmState> state;
};
std::vector<NavTick> fly_until_stale(WallEffectNavLogic& logic, bool odometry, int64_t stop_ns, int64_t end_ns,
                                     int64_t resume_ns = -1) {
  std::vector<NavTick> ticks;
  double x = -1.0;
  for (int64_t ns = 0; ns <= end_ns; ns += kNavTick) {
    const bool on = ns <= stop_ns || (resume_ns >= 0 && ns >= resume_ns);
    if (on || !odometry) logic.on_odometry(nav_odom(ns, x, 0.0));
    if (on || odometry) logic.on_wall(nav_wall(ns));
    const auto out = logic.on_timer(ns);
    if (!out.setpoint) {
      ADD_FAILURE() << "no setpoint at " << ns << " ns";
      return ticks;
    }
    ticks.push_back({ns, *out.setpoint, out.state});
    if (std::isfinite(out.setpoint->pose.pose.position.x)) x += 0.01 * out.setpoint->twist.twist.linear.x;
  }
  return ticks;
}
}  // namespace

// Issue 33, the shared fail-safe (SafetyRunner). Odometry stopped: the node published
// nothing, so the INDI controller kept flying the last setpoint (its velocity too) for as
// long as its own odometry came. Now: FAILSAFE_HOVER (REASON_FAILSAFE_ODOMETRY_STALE) at
// the last known position, zero velocity; after failsafe_land_after_s FAILSAFE_LAND
// (REASON_FAILSAFE_STALE_TOO_LONG): that x, y held, z velocity-only (NaN) descending at
// failsafe_land_speed, no height needed.
TEST(WallEffectNavLogic, StaleOdometryHoversWhereLastKnownThenLands) {
  WallEffectNavLogic logic(WallEffectNavLogic::params_from(WallEffectNavLogic::default_parameters()));
  const auto& p = logic.params();
  const int64_t stop = 500'000'000;
  const int64_t hover_ns = stop + tactile_common::from_seconds(p.safety.max_input_age_s) + kNavTick;
  const int64_t land_ns = hover_ns + tactile_common::from_seconds(p.safety.failsafe_land_after_s);
  const auto ticks = fly_until_stale(logic, true, stop, land_ns + 1'000'000'000);
  ASSERT_EQ(ticks.back().ns, land_ns + 1'000'000'000);
  double last_known = 0.0;
  int hovers = 0, landings = 0;
  for (const auto& k : ticks) {
    const auto& pos = k.sp.pose.pose.position;
    const auto& vel = k.sp.twist.twist.linear;
    if (k.ns <= stop) last_known = -1.0 + 0.01 * 0.10 * static_cast<double>(k.ns / kNavTick);
    if (k.ns < hover_ns) {
      EXPECT_FALSE(k.state && k.state->state.rfind("FAILSAFE", 0) == 0) << k.ns;
      continue;
    }
    EXPECT_NEAR(pos.x, last_known, 1e-9) << k.ns;  // where the drone was last known
    EXPECT_DOUBLE_EQ(pos.y, 0.0);
    EXPECT_EQ(vel.x, 0.0);
    EXPECT_EQ(vel.y, 0.0);
    if (k.ns < land_ns) {
      EXPECT_DOUBLE_EQ(pos.z, p.nav.height) << k.ns;
      EXPECT_EQ(vel.z, 0.0);
    } else {
      EXPECT_TRUE(std::isnan(pos.z)) << k.ns << ": the landing flies no height";
      EXPECT_DOUBLE_EQ(vel.z, -p.failsafe_land_speed);
    }
    if (!k.state) continue;
    if (k.ns < land_ns) {
      ++hovers;
      EXPECT_EQ(k.state->state, "FAILSAFE_HOVER");
      EXPECT_EQ(k.state->reason, "odometry stale");
      EXPECT_EQ(k.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_ODOMETRY_STALE);
      EXPECT_EQ(k.state->previous_state, "FREE_FLIGHT");
      if (hovers == 1) { EXPECT_EQ(k.ns, hover_ns); }
    } else {
      ++landings;
      EXPECT_EQ(k.state->state, "FAILSAFE_LAND");
      EXPECT_EQ(k.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
      EXPECT_EQ(k.state->previous_state, "FAILSAFE_HOVER");
      if (landings == 1) { EXPECT_EQ(k.ns, land_ns); }
    }
  }
  EXPECT_EQ(hovers, 4);  // on entry and at 2 Hz for 2 s
  EXPECT_EQ(landings, 3);
  EXPECT_EQ(logic.stats().failsafe_hovers, 1u);
  EXPECT_EQ(logic.stats().failsafe_landings, 1u);
}

// The wall estimate stops for good (the odometry goes on): FAILSAFE_HOVER
// (REASON_FAILSAFE_WALL_ESTIMATE_STALE) at the position on entry, then FAILSAFE_LAND after
// failsafe_land_after_s, terminal: estimates coming again do not resume the navigator.
TEST(WallEffectNavLogic, StaleWallEstimateLandsAfterFailsafeLandAfterS) {
  auto m = WallEffectNavLogic::default_parameters();
  m.set("failsafe_land_after_s", 1.0);
  WallEffectNavLogic logic(WallEffectNavLogic::params_from(m));
  const int64_t stop = 500'000'000, resume = 2'500'000'000;
  const auto ticks = fly_until_stale(logic, false, stop, 3'000'000'000, resume);
  std::vector<std::pair<int64_t, std::string>> states;
  for (const auto& k : ticks) {
    if (k.state && (states.empty() || states.back().second != k.state->state))
      states.emplace_back(k.ns, k.state->state);
  }
  ASSERT_EQ(states.size(), 3u);
  EXPECT_EQ(states[0].second, "FREE_FLIGHT");
  EXPECT_EQ(states[1], std::make_pair(int64_t{710'000'000}, std::string("FAILSAFE_HOVER")));
  EXPECT_EQ(states[2], std::make_pair(int64_t{1'710'000'000}, std::string("FAILSAFE_LAND")));
  const auto& last = ticks.back().sp;  // 0.5 s after the estimates came back
  EXPECT_TRUE(std::isnan(last.pose.pose.position.z));
  EXPECT_DOUBLE_EQ(last.twist.twist.linear.z, -logic.params().failsafe_land_speed);
  EXPECT_EQ(logic.safety().state(), SafetyState::kFailsafeLand);
  EXPECT_EQ(logic.navigator().state(), NavState::kFreeFlight);
}

// Odometry stale for 0.5 s, then fresh: FAILSAFE_HOVER (odometry), then the navigator
// resumes with REASON_FAILSAFE_INPUTS_FRESH; nothing lands.
TEST(WallEffectNavLogic, StaleOdometryResumesWhenFresh) {
  WallEffectNavLogic logic(WallEffectNavLogic::params_from(WallEffectNavLogic::default_parameters()));
  const int64_t stop = 500'000'000, resume = 1'000'000'000;
  const auto ticks = fly_until_stale(logic, true, stop, 1'500'000'000, resume);
  bool hovered = false, resumed = false;
  for (const auto& k : ticks) {
    if (!k.state) continue;
    EXPECT_NE(k.state->state, "FAILSAFE_LAND");
    if (k.state->state == "FAILSAFE_HOVER") {
      hovered = true;
      EXPECT_EQ(k.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_ODOMETRY_STALE);
    }
    if (k.ns == resume) {
      EXPECT_EQ(k.state->state, "FREE_FLIGHT");
      EXPECT_EQ(k.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_INPUTS_FRESH);
      resumed = true;
    }
  }
  EXPECT_TRUE(hovered);
  EXPECT_TRUE(resumed);
  EXPECT_GT(std::hypot(ticks.back().sp.twist.twist.linear.x, ticks.back().sp.twist.twist.linear.y), 0.0);
  EXPECT_EQ(logic.stats().failsafe_landings, 0u);
}

TEST(WallEffectNavLogic, FailsafeParametersAreValidated) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"failsafe_land_after_s", -1.0}, {"failsafe_land_speed", 0.0}, {"max_input_age_s", 0.0}}) {
    auto m = WallEffectNavLogic::default_parameters();
    m.set(key, value);
    try {
      WallEffectNavLogic::params_from(m);
      ADD_FAILURE() << key << " = " << value << " accepted";
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}
