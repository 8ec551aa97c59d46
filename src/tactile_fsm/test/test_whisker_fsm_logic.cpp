// Node logic tests: parameters (defaults, repository config, errors), message
// mapping, the 5 Hz / on-transition FsmState, bad input dropped and counted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <variant>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/time.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"

using tactile_common::ParamError;
using tactile_common::ParamMap;
using tactile_fsm::WhiskerFsmLogic;
using FsmState = tactile_msgs::msg::FsmState;

namespace {

constexpr int64_t kStepNs = 20000000;  // 50 Hz

tactile_msgs::msg::TactileDepth depth(int64_t ns, bool cl, double dl, bool cr, double dr) {
  tactile_msgs::msg::TactileDepth m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.contact_left = cl;
  m.contact_right = cr;
  m.depth_left = dl;
  m.depth_right = dr;
  return m;
}

nav_msgs::msg::Odometry odom(int64_t ns, double x, double y, double yaw) {
  nav_msgs::msg::Odometry m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.pose.pose.position.x = x;
  m.pose.pose.position.y = y;
  m.pose.pose.orientation.w = std::cos(yaw / 2);
  m.pose.pose.orientation.z = std::sin(yaw / 2);
  return m;
}

tactile_msgs::msg::WhiskerSignal signal(int64_t ns, uint8_t id, bool contact) {
  tactile_msgs::msg::WhiskerSignal m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.whisker_id = id;
  m.contact = contact;
  m.compensated = {{contact ? 30.0 : 1.0, 0.0, 0.0}};
  return m;
}

std::string param_error(const ParamMap& m) {
  try {
    WhiskerFsmLogic::params_from(m);
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

// Feeds fresh no-contact depth and odometry at (x, y, yaw) and ticks.
WhiskerFsmLogic::Outputs tick(WhiskerFsmLogic& l, int64_t ns, double x = 0.0, double y = 0.0, double yaw = 0.0) {
  l.on_depth(depth(ns, false, NAN, false, NAN));
  l.on_odometry(odom(ns, x, y, yaw));
  return l.on_timer(ns);
}

}  // namespace

TEST(WhiskerFsmLogic, DefaultsAndTopics) {
  const auto p = WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters());
  EXPECT_DOUBLE_EQ(p.fsm.v_max, 0.2);
  EXPECT_DOUBLE_EQ(p.fsm.t_min, 0.06);
  EXPECT_DOUBLE_EQ(p.fsm.t_max, 0.10);
  EXPECT_NEAR(p.fsm.omega_max, 25.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(p.fsm.follow_side, tactile_fsm::Side::kRight);
  EXPECT_DOUBLE_EQ(p.target_x, 3.6);
  EXPECT_STREQ(WhiskerFsmLogic::kNodeName, "whisker_fsm");
  EXPECT_STREQ(WhiskerFsmLogic::kDepthTopic, "whisker/depth");
  EXPECT_STREQ(WhiskerFsmLogic::kLeftSignalTopic, "whisker/left/signal");
  EXPECT_STREQ(WhiskerFsmLogic::kRightSignalTopic, "whisker/right/signal");
  EXPECT_STREQ(WhiskerFsmLogic::kOdomTopic, "odom");
  EXPECT_STREQ(WhiskerFsmLogic::kSetpointTopic, "cmd_hover");
  EXPECT_STREQ(WhiskerFsmLogic::kStateTopic, "fsm_state");
  EXPECT_EQ(WhiskerFsmLogic::kTimerPeriodNs, 20000000);
}

TEST(WhiskerFsmLogic, RepositoryConfigMatchesDefaults) {
  // The test runs in the package source directory. Every key of the defaults is
  // compared (a key added to default_parameters() is covered without touching
  // this test), and the file names no key the node does not have.
  const ParamMap d = WhiskerFsmLogic::default_parameters();
  const ParamMap m = tactile_common::load_node_parameters("../../config/tactile_fsm.yaml", "/whisker_fsm", d);
  ASSERT_EQ(m.values().size(), d.values().size());
  for (const auto& [key, value] : d.values()) {
    const auto& in_file = m.values().at(key);
    if (std::holds_alternative<double>(value) && std::holds_alternative<double>(in_file)) {
      // Angles are written in radians with 16 digits (align_enter = 3 deg).
      EXPECT_NEAR(std::get<double>(in_file), std::get<double>(value), 1e-15 * std::max(1.0, std::abs(std::get<double>(value))))
          << key << " in config/tactile_fsm.yaml differs from default_parameters()";
    } else {
      EXPECT_TRUE(in_file == value) << key << " in config/tactile_fsm.yaml differs from default_parameters()";
    }
  }
  const auto p = WhiskerFsmLogic::params_from(m);
  EXPECT_NEAR(p.fsm.omega_max, 25.0 * M_PI / 180.0, 1e-15);  // 000 Fig. S4e, 25 deg/s
  EXPECT_TRUE(p.fsm.phantom_latch);                          // round 4b
  EXPECT_DOUBLE_EQ(p.fsm.wall_end_depth, 0.105);             // round 7
}

// The parameter spec: every key described, no described range wider than what
// params_from()/validate() accept, and no key live (the FSM's rules are read at start).
TEST(WhiskerFsmLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const tactile_common::ParamMap d = WhiskerFsmLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { WhiskerFsmLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
  EXPECT_EQ(d.info("t_min")->unit, "m");
}

TEST(WhiskerFsmLogic, ParameterErrorsNameTheKey) {
  ParamMap m = WhiskerFsmLogic::default_parameters();
  m.set("follow_side", std::string("up"));
  EXPECT_NE(param_error(m).find("follow_side"), std::string::npos);
  EXPECT_NE(param_error(m).find("\"up\""), std::string::npos);
  m = WhiskerFsmLogic::default_parameters();
  m.set("t_max", 0.05);
  EXPECT_NE(param_error(m).find("t_max"), std::string::npos) << param_error(m);
  EXPECT_NE(param_error(m).find("> t_min"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("target_x", std::nan(""));
  EXPECT_NE(param_error(m).find("target_x"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("press_sum_pa", -5.0);
  EXPECT_NE(param_error(m).find("press_sum_pa"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("press_depth", 0.0);
  EXPECT_NE(param_error(m).find("press_depth"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("phantom_quiet_rms", -1.0);
  EXPECT_NE(param_error(m).find("phantom_quiet_rms"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("phantom_quiet_samples", int64_t{1});
  EXPECT_NE(param_error(m).find("phantom_quiet_samples"), std::string::npos) << param_error(m);
  m = WhiskerFsmLogic::default_parameters();
  m.set("v_max", std::string("fast"));  // wrong type
  EXPECT_THROW(WhiskerFsmLogic::params_from(m), ParamError);
}

// The setpoint's velocities are body-frame: its frame is the odometry's child frame,
// with the vehicle's frame_prefix (REP 105, several vehicles).
TEST(WhiskerFsmLogic, SetpointIsInTheOdometryBodyFrame) {
  WhiskerFsmLogic l(WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters()));
  auto o = odom(0, 0.0, 0.0, 0.0);
  o.header.frame_id = "cf1/odom";
  o.child_frame_id = "cf1/base_link";
  l.on_depth(depth(0, false, NAN, false, NAN));
  l.on_odometry(o);
  EXPECT_EQ(l.on_timer(0).setpoint.header.frame_id, "cf1/base_link");
}

TEST(WhiskerFsmLogic, FlightThroughMessages) {
  auto p = WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters());
  p.target_x = 2.0;
  WhiskerFsmLogic l(p);
  int64_t ns = 0;
  auto o = tick(l, ns);
  ASSERT_TRUE(o.state.has_value());  // first tick publishes the state
  EXPECT_EQ(o.state->behaviour, "whisker_wall_following");
  EXPECT_EQ(o.state->state, "HOVER_INIT");
  EXPECT_EQ(o.state->previous_state, "");
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_NONE);
  EXPECT_DOUBLE_EQ(o.setpoint.height, 0.4);
  EXPECT_EQ(o.setpoint.header.frame_id, "base_link");
  // 5 Hz state messages while hovering: ticks 10, 20, ..., none in between.
  int states = 0;
  for (int k = 1; k < 100; ++k) {
    o = tick(l, k * kStepNs);
    if (o.state) {
      ++states;
      EXPECT_EQ(k % 10, 0) << k;
      EXPECT_NEAR(o.state->time_in_state, k * 0.02, 1e-9);
    }
  }
  EXPECT_EQ(states, 9);
  o = tick(l, 100 * kStepNs);  // 2 s: forward
  ASSERT_TRUE(o.state.has_value());
  EXPECT_EQ(o.state->state, "FLY_FORWARD");
  EXPECT_EQ(o.state->previous_state, "HOVER_INIT");
  // The step and scan (an override rule) begins on the same tick: both reasons.
  EXPECT_EQ(o.state->reason,
            "hover initialisation done; step and scan on the first approach (first_whisk_amplitude, first_scan_step)");
  EXPECT_EQ(o.state->transitions, 1u);
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_WHISKER_HOVER_DONE);  // the transition's code
  EXPECT_EQ(l.stats().rule_step_and_scan, 1u);
  EXPECT_DOUBLE_EQ(o.setpoint.vx, 0.2);
  tactile_common::to_stamp(100 * kStepNs, o.setpoint.header.stamp);
  // A TDORC contact on the right whisker alone triggers wall following.
  ns = 101 * kStepNs;
  l.on_depth(depth(ns, false, NAN, false, NAN));
  l.on_odometry(odom(ns, 0.5, 0.0, 0.0));
  l.on_right_signal(signal(ns, 1, true));
  o = l.on_timer(ns);
  ASSERT_TRUE(o.state.has_value());
  EXPECT_EQ(o.state->state, "WALL_FOLLOWING/FLY_SIDEWAYS");  // no depth yet
  EXPECT_EQ(o.state->reason, "whisker contact");
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_WHISKER_CONTACT);
  EXPECT_DOUBLE_EQ(o.setpoint.vy, -0.2);
  // Depths in the band, tilted: d_l = 90 mm, d_r = 70 mm -> turn right at omega_max.
  ns = 102 * kStepNs;
  l.on_depth(depth(ns, true, 0.09, true, 0.07));
  l.on_odometry(odom(ns, 0.5, 0.0, 0.0));
  o = l.on_timer(ns);
  ASSERT_TRUE(o.state.has_value());
  EXPECT_EQ(o.state->state, "WALL_FOLLOWING/TURN_RIGHT");
  EXPECT_EQ(o.state->previous_state, "WALL_FOLLOWING/FLY_SIDEWAYS");
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_WHISKER_SUB_STATE_RULE);
  EXPECT_NEAR(o.setpoint.yaw_rate, -25.0 * M_PI / 180.0, 1e-12);
  // Odometry past the target (2, 0) -> landing.
  ns = 103 * kStepNs;
  l.on_depth(depth(ns, true, 0.08, true, 0.08));
  l.on_odometry(odom(ns, 2.05, 0.0, 0.0));
  o = l.on_timer(ns);
  ASSERT_TRUE(o.state.has_value());
  EXPECT_EQ(o.state->state, "LANDING");
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_WHISKER_TARGET_REACHED);
  EXPECT_TRUE(o.setpoint.land);
  EXPECT_EQ(o.setpoint.height, 0.0);
}

// Issue 17, pressed whisker: the sum of the three S_c of each WhiskerSignal
// reaches the rule. Wall following with both depths at 70 mm (in band,
// aligned): FLY_SIDEWAYS while the sums are 300 Pa; the left sum at
// 400 + 400 + 400 = 1200 Pa (>= press_sum_pa, 900 Pa by default in this node)
// makes it FLY_BACKWARD (vx = -V_max/2); with press_sum_pa 0 it stays sideways.
TEST(WhiskerFsmLogic, PressedWhiskerFromSignalSums) {
  auto run = [](double press_sum_pa) {
    ParamMap m = WhiskerFsmLogic::default_parameters();
    m.set("press_sum_pa", press_sum_pa);
    auto p = WhiskerFsmLogic::params_from(m);
    p.target_x = 5.0;
    WhiskerFsmLogic l(p);
    for (int k = 0; k <= 100; ++k) tick(l, k * kStepNs);
    std::vector<std::string> states;
    for (int k = 101; k <= 103; ++k) {
      const int64_t ns = k * kStepNs;
      l.on_depth(depth(ns, true, 0.07, true, 0.07));
      l.on_odometry(odom(ns, 0.5, 0.0, 0.0));
      auto left = signal(ns, 0, true);
      auto right = signal(ns, 1, true);
      const double each = k == 103 ? 400.0 : 100.0;
      left.calibrated = {{each, each, each}};
      right.calibrated = {{100.0, 100.0, 100.0}};
      l.on_left_signal(left);
      l.on_right_signal(right);
      const auto o = l.on_timer(ns);
      states.push_back(o.state ? o.state->state : "");
      if (k == 103) {
        EXPECT_NEAR(o.setpoint.vx, press_sum_pa > 0.0 ? -0.1 : 0.0, 1e-12);
      }
    }
    return states;
  };
  EXPECT_DOUBLE_EQ(WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters()).fsm.press_sum_pa, 900.0);
  const auto on = run(900.0);
  EXPECT_EQ(on[0], "WALL_FOLLOWING/FLY_SIDEWAYS");
  EXPECT_EQ(on[2], "WALL_FOLLOWING/FLY_BACKWARD");
  const auto off = run(0.0);
  EXPECT_EQ(off[2], "");  // no transition: still FLY_SIDEWAYS
}

// Issue 17, round 4: the RMS of the sample-to-sample changes of each
// whisker's S_c sum reaches the phantom gate. Both whiskers in contact at
// 70 / 70 mm, the drone moved 4 mm per tick along -y (odometry by hand), each
// channel at 100 +- 1 Pa (sum 300 +- 3, changes of 6 Pa: RMS 6 < 8, quiet) or
// 100 +- 10 Pa (changes of 60 Pa, moving). The window fills with the 25th
// signal (tick 125), so the contact counts as live up to tick 124; the drone
// is 52 mm further at tick 137, the whiskers count as off and the obstacle is
// cleared 0.2 s after the last tick in contact (136): tick 146; a moving
// sum, or the gate off, keeps the wall following.
TEST(WhiskerFsmLogic, QuietSignalSumsReachThePhantomGate) {
  auto run = [](double quiet_rms, double swing) {
    ParamMap m = WhiskerFsmLogic::default_parameters();
    m.set("phantom_quiet_rms", quiet_rms);
    m.set("phantom_travel", 0.05);
    auto p = WhiskerFsmLogic::params_from(m);
    p.target_x = 5.0;
    WhiskerFsmLogic l(p);
    for (int k = 0; k <= 100; ++k) tick(l, k * kStepNs);
    int cleared = -1;
    for (int k = 101; k <= 160; ++k) {
      const int64_t ns = k * kStepNs;
      l.on_depth(depth(ns, true, 0.07, true, 0.07));
      l.on_odometry(odom(ns, 0.5, -0.004 * (k - 101), 0.0));
      auto left = signal(ns, 0, true);
      auto right = signal(ns, 1, true);
      const double each = 100.0 + (k % 2 ? swing : -swing);
      left.calibrated = {{each, each, each}};
      right.calibrated = {{each, each, each}};
      l.on_left_signal(left);
      l.on_right_signal(right);
      l.on_timer(ns);
      if (cleared < 0 && l.fsm().state() == tactile_fsm::FsmState::kResumeForward) cleared = k;
    }
    return cleared;
  };
  EXPECT_EQ(run(8.0, 1.0), 146);
  EXPECT_EQ(run(8.0, 10.0), -1);
  EXPECT_EQ(run(0.0, 1.0), -1);
}

TEST(WhiskerFsmLogic, BadInputDroppedAndCounted) {
  // The paper's straight approach (V_max in FLY_FORWARD), not the first-approach
  // scan, whose step (0.08 m) the odometry's 0.1 m below lies past: it would fly
  // back to the step's end.
  auto m = WhiskerFsmLogic::default_parameters();
  m.set("first_whisk_amplitude", 0.0);
  WhiskerFsmLogic l(WhiskerFsmLogic::params_from(m));
  for (int k = 0; k <= 100; ++k) tick(l, k * kStepNs);
  ASSERT_EQ(l.fsm().state(), tactile_fsm::FsmState::kFlyForward);
  const int64_t ns = 101 * kStepNs;
  // NaN depth of a whisker in contact: dropped (would otherwise start wall following).
  l.on_depth(depth(ns, true, NAN, false, NAN));
  // NaN depth of a whisker not in contact is not used: accepted.
  l.on_depth(depth(ns, false, NAN, false, 0.5));
  // NaN pose and a zero quaternion.
  auto bad = odom(ns, NAN, 0.0, 0.0);
  l.on_odometry(bad);
  bad = odom(ns, 0.1, 0.0, 0.0);
  bad.pose.pose.orientation.w = 0.0;
  l.on_odometry(bad);
  // NaN S_p, wrong whisker id on the left topic, and an out-of-order signal.
  auto s = signal(ns, 0, true);
  s.compensated[1] = NAN;
  l.on_left_signal(s);
  l.on_left_signal(signal(ns, 1, true));
  l.on_right_signal(signal(ns, 1, false));
  l.on_right_signal(signal(ns - kStepNs, 1, true));
  // Out-of-order depth.
  l.on_depth(depth(ns - 5 * kStepNs, true, 0.08, true, 0.08));
  l.on_odometry(odom(ns, 0.1, 0.0, 0.0));
  const auto o = l.on_timer(ns);
  EXPECT_EQ(l.fsm().state(), tactile_fsm::FsmState::kFlyForward);  // nothing bad got through
  EXPECT_DOUBLE_EQ(o.setpoint.vx, 0.2);
  EXPECT_EQ(l.stats().dropped_nonfinite, 4u);  // depth NaN, pose NaN, zero quaternion, S_p NaN
  EXPECT_EQ(l.stats().dropped_wrong_whisker, 1u);
  EXPECT_EQ(l.stats().dropped_out_of_order, 2u);
  EXPECT_EQ(l.stats().received_signal_left, 2u);
  EXPECT_EQ(l.stats().received_signal_right, 2u);
}

TEST(WhiskerFsmLogic, StaleInputsFailsafe) {
  WhiskerFsmLogic l(WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters()));
  for (int k = 0; k <= 100; ++k) tick(l, k * kStepNs);
  // Odometry keeps coming, depth stops at tick 100 (2.0 s); stale after 0.2 s.
  WhiskerFsmLogic::Outputs o;
  int k = 101;
  for (; k <= 110; ++k) {
    l.on_odometry(odom(k * kStepNs, 0.0, 0.0, 0.0));
    o = l.on_timer(k * kStepNs);
    ASSERT_EQ(l.fsm().state(), tactile_fsm::FsmState::kFlyForward) << k;
  }
  l.on_odometry(odom(k * kStepNs, 0.0, 0.0, 0.0));
  o = l.on_timer(k * kStepNs);
  ASSERT_TRUE(o.state.has_value());
  EXPECT_EQ(o.state->state, "FAILSAFE_HOVER");
  EXPECT_EQ(o.state->reason, "tactile depth stale");
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_FAILSAFE_DEPTH_STALE);  // the SafetyRunner's code
  EXPECT_EQ(o.setpoint.vx, 0.0);
  for (++k; k <= 211; ++k) {
    o = l.on_timer(k * kStepNs);
    if (l.fsm().state() == tactile_fsm::FsmState::kFailsafeLand) break;
  }
  ASSERT_TRUE(o.state.has_value());  // published on the transition
  EXPECT_EQ(o.state->reason_code, FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
  EXPECT_EQ(l.fsm().state(), tactile_fsm::FsmState::kFailsafeLand);
  EXPECT_TRUE(o.setpoint.land);
}

TEST(WhiskerFsmLogic, StaleSignalContactIsIgnored) {
  WhiskerFsmLogic l(WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters()));
  l.on_left_signal(signal(0, 0, true));  // contact at t = 0, never updated
  for (int k = 0; k <= 120; ++k) tick(l, k * kStepNs);
  EXPECT_EQ(l.fsm().state(), tactile_fsm::FsmState::kFlyForward);
}

// One default per key (issue 33): params_from(default_parameters()) is the core
// struct's defaults, the two issue-17 rules gpis_explorer turns off included.
TEST(WhiskerFsmLogic, NodeDefaultsAreTheCoreDefaults) {
  const WhiskerFsmLogic::Params n = WhiskerFsmLogic::params_from(WhiskerFsmLogic::default_parameters());
  const tactile_fsm::WallFollowerParams c;
  const tactile_fsm::WallFollowerParams& f = n.fsm;
  EXPECT_TRUE(f.hold_heading_trailing_lost);
  EXPECT_EQ(f.hold_heading_trailing_lost, c.hold_heading_trailing_lost);
  EXPECT_DOUBLE_EQ(f.wall_end_depth, 0.105);
  EXPECT_EQ(f.wall_end_depth, c.wall_end_depth);
  EXPECT_EQ(f.turn_anchor_tolerance, c.turn_anchor_tolerance);
  EXPECT_EQ(f.turn_anchor_rate, c.turn_anchor_rate);
  EXPECT_EQ(f.press_sum_pa, c.press_sum_pa);
  EXPECT_EQ(f.press_hold_s, c.press_hold_s);
  EXPECT_EQ(f.phantom_quiet_rms, c.phantom_quiet_rms);
  EXPECT_EQ(f.phantom_travel, c.phantom_travel);
  EXPECT_EQ(f.phantom_resume_max, c.phantom_resume_max);
  EXPECT_EQ(f.phantom_latch, c.phantom_latch);
  EXPECT_EQ(f.whisk_rate_max, c.whisk_rate_max);
  EXPECT_EQ(f.whisk_pause_rms, c.whisk_pause_rms);
  EXPECT_EQ(f.clear_yaw_offset, c.clear_yaw_offset);
  EXPECT_EQ(f.clear_yaw_release_rms, c.clear_yaw_release_rms);
  EXPECT_EQ(f.first_whisk_amplitude, c.first_whisk_amplitude);
  EXPECT_EQ(f.first_scan_step, c.first_scan_step);
  EXPECT_EQ(f.first_scan_rate, c.first_scan_rate);
  EXPECT_EQ(f.end_contact_lateral, c.end_contact_lateral);
}
