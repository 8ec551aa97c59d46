// Core tests of the whisker wall-following FSM (000 Methods, Fig. S4e):
// state sequence, the sub-state rule on hand-picked depths, saturation,
// stale-input fail-safe, and a closed loop with a kinematic point drone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "tactile_fsm/whisker_wall_follower.hpp"
#include "wall_follower_input.hpp"

using tactile_fsm::FsmState;
using tactile_fsm::Setpoint;
using tactile_fsm::Side;
using tactile_fsm::wall_sub_state;
using tactile_fsm::WallFollowerInput;
using tactile_fsm::WallFollowerOutput;
using tactile_fsm::WallFollowerParams;
using tactile_fsm::WallSubState;
using tactile_fsm::WhiskerWallFollower;

namespace {

/// The rules of issue 17 that the whisker FSM ships (and WallFollowerParams'
/// defaults since issue 33) off: the FSM these tests were written against
/// (000 Fig. S4e with the heading limit, the same-obstacle rule and the
/// realignment). A test of one rule turns that rule on.
WallFollowerParams rules_off() {
  WallFollowerParams p;
  p.turn_anchor_tolerance = 0.0;
  p.turn_anchor_rate = 0.0;
  p.press_sum_pa = 0.0;
  p.press_hold_s = 0.2;
  p.phantom_quiet_rms = 0.0;
  p.phantom_travel = 0.05;
  p.phantom_resume_max = 0.0;
  p.phantom_latch = false;
  p.whisk_rate_max = 2.0;
  p.whisk_pause_rms = 0.0;
  p.clear_yaw_offset = 0.0;
  p.clear_yaw_release_rms = 0.0;
  p.first_whisk_amplitude = 0.0;
  p.end_contact_lateral = 0.0;
  p.hold_heading_trailing_lost = false;
  p.wall_end_depth = 0.0;
  return p;
}

constexpr double kDt = 0.02;  // 50 Hz
constexpr double kDeg = M_PI / 180.0;

using tactile_fsm::test::input;

void set_depths(WallFollowerInput& in, double dl, double dr) {
  in.left_valid = in.right_valid = true;
  in.depth_left = dl;
  in.depth_right = dr;
}

/// Ten ticks at (1, 0) with the left whisker lost and the right one at
/// `right`: the sub-state after them.
WallSubState sub_with_left_lost(WhiskerWallFollower& fsm, double& t, double right) {
  WallSubState sub = WallSubState::kNone;
  for (int k = 0; k < 10; ++k, t += kDt) {
    WallFollowerInput in = input(t, 1.0, 0.0);
    set_depths(in, NAN, right);
    in.left_valid = false;
    sub = fsm.step(in).sub_state;
  }
  return sub;
}

WallSubState rule(double dl, double dr, WallSubState current = WallSubState::kFlySideways) {
  return wall_sub_state(dl, true, dr, true, Side::kRight, true, current, rules_off());
}

/// validate() rejects p with an error naming WallFollowerParams.<field>.
void expect_rejected(const WallFollowerParams& p, const std::string& field) {
  try {
    p.validate();
    ADD_FAILURE() << field << " accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("WallFollowerParams." + field), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(WallFollowerParams, DefaultsArePaperValuesAndValidate) {
  const WallFollowerParams p;
  EXPECT_DOUBLE_EQ(p.v_max, 0.2);                   // 000 Results, 20 cm/s
  EXPECT_NEAR(p.omega_max, 0.4363323, 1e-6);        // 25 deg/s
  EXPECT_DOUBLE_EQ(p.t_min, 0.06);                  // 000 Fig. 4c band 60-100 mm
  EXPECT_DOUBLE_EQ(p.t_max, 0.10);
  EXPECT_DOUBLE_EQ(p.hover_init_s, 2.0);
  EXPECT_DOUBLE_EQ(p.flight_height, 0.4);
  EXPECT_EQ(p.follow_side, Side::kRight);
  EXPECT_NO_THROW(p.validate());
}

// One default per key (issue 33): the core struct's defaults are the rules the
// whisker FSM node ships (config/tactile_fsm.yaml); gpis_explorer turns two of
// them off for its wall follows (gpis_wall_params()).
TEST(WallFollowerParams, DefaultsAreTheShippedRules) {
  const WallFollowerParams p;
  EXPECT_DOUBLE_EQ(p.turn_anchor_tolerance, 10.0 * kDeg);  // round 13
  EXPECT_DOUBLE_EQ(p.turn_anchor_rate, 2.0 * kDeg);
  EXPECT_DOUBLE_EQ(p.press_sum_pa, 900.0);                 // round 3
  EXPECT_DOUBLE_EQ(p.press_hold_s, 0.0);
  EXPECT_DOUBLE_EQ(p.phantom_quiet_rms, 6.5);              // rounds 4, 4b
  EXPECT_DOUBLE_EQ(p.phantom_travel, 0.03);
  EXPECT_DOUBLE_EQ(p.phantom_resume_max, 2.0);
  EXPECT_TRUE(p.phantom_latch);
  EXPECT_DOUBLE_EQ(p.clear_yaw_offset, 0.2443);            // round 9
  EXPECT_DOUBLE_EQ(p.clear_yaw_release_rms, 13.0);
  EXPECT_DOUBLE_EQ(p.first_whisk_amplitude, 0.44);         // round 12
  EXPECT_DOUBLE_EQ(p.first_scan_step, 0.08);
  EXPECT_DOUBLE_EQ(p.whisk_rate_max, 3.0);
  EXPECT_DOUBLE_EQ(p.whisk_pause_rms, 13.0);
  EXPECT_DOUBLE_EQ(p.end_contact_lateral, 0.045);          // round 10
  EXPECT_TRUE(p.hold_heading_trailing_lost);               // rule 1
  EXPECT_DOUBLE_EQ(p.wall_end_depth, 0.105);               // round 7
}

TEST(WallFollowerParams, ValidateNamesFieldAndReason) {
  auto message = [](WallFollowerParams p) -> std::string {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  WallFollowerParams p = rules_off();
  p.t_max = 0.05;  // below t_min
  EXPECT_NE(message(p).find("WallFollowerParams.t_max: must be finite and > t_min"), std::string::npos) << message(p);
  p = rules_off();
  p.v_max = -1.0;
  EXPECT_NE(message(p).find("WallFollowerParams.v_max"), std::string::npos);
  p = rules_off();
  p.align_exit = 5.0 * kDeg;  // above align_enter (3 deg)
  EXPECT_NE(message(p).find("WallFollowerParams.align_exit"), std::string::npos);
  p = rules_off();
  p.max_input_age_s = std::nan("");
  EXPECT_NE(message(p).find("WallFollowerParams.max_input_age_s"), std::string::npos);
  EXPECT_THROW(WhiskerWallFollower{p}, std::invalid_argument);
  EXPECT_EQ(tactile_fsm::side_from_string("left"), Side::kLeft);
  EXPECT_THROW(tactile_fsm::side_from_string("up"), std::invalid_argument);
}

// --- Sub-state rule (000 Fig. S4e) on hand-picked (d_l, d_r) pairs, band 60-100 mm, s = 50 mm.

TEST(WallSubStateRule, InsideBandAlignedFliesSideways) {
  EXPECT_EQ(rule(0.080, 0.080), WallSubState::kFlySideways);
  EXPECT_EQ(rule(0.061, 0.0615), WallSubState::kFlySideways);  // 0.6 deg, near T_min
}

TEST(WallSubStateRule, BothTooCloseFliesBackwardBothTooFarFliesForward) {
  EXPECT_EQ(rule(0.050, 0.055), WallSubState::kFlyBackward);
  EXPECT_EQ(rule(0.120, 0.110), WallSubState::kFlyForward);
}

TEST(WallSubStateRule, TiltTurnsTowardPerpendicular) {
  // d_l < d_r: the wall is nearer on the left; theta = atan(-0.02/0.05) = -21.8 deg,
  // the perpendicular heading is counter-clockwise -> turn left.
  EXPECT_EQ(rule(0.070, 0.090), WallSubState::kTurnLeft);
  EXPECT_EQ(rule(0.090, 0.070), WallSubState::kTurnRight);
  // Different intervals (one out of the band) with a clear tilt.
  EXPECT_EQ(rule(0.050, 0.080), WallSubState::kTurnLeft);
  EXPECT_EQ(rule(0.110, 0.090), WallSubState::kTurnRight);
  EXPECT_EQ(rule(0.050, 0.110), WallSubState::kTurnLeft);
}

TEST(WallSubStateRule, AlignmentHysteresis) {
  // 2 deg tilt: d_l - d_r = 0.05 * tan(2 deg) = 1.746 mm; between exit (1) and enter (3 deg).
  const double half = 0.5 * 0.05 * std::tan(2.0 * kDeg);
  EXPECT_EQ(rule(0.080 + half, 0.080 - half, WallSubState::kFlySideways), WallSubState::kFlySideways);
  EXPECT_EQ(rule(0.080 + half, 0.080 - half, WallSubState::kTurnRight), WallSubState::kTurnRight);
  // 4 deg starts a turn from sideways.
  const double h4 = 0.5 * 0.05 * std::tan(4.0 * kDeg);
  EXPECT_EQ(rule(0.080 + h4, 0.080 - h4, WallSubState::kFlySideways), WallSubState::kTurnRight);
}

TEST(WallSubStateRule, AlignedButStraddlingBandEdgeTranslates) {
  // theta = atan(0.0004 / 0.05) = 0.46 deg < align_exit: move, do not turn.
  EXPECT_EQ(rule(0.1002, 0.0998), WallSubState::kFlyForward);
  EXPECT_EQ(rule(0.0598, 0.0602), WallSubState::kFlyBackward);
}

TEST(WallSubStateRule, MissingDepth) {
  const WallFollowerParams p = rules_off();
  // Approach: left not touching yet counts as beyond T_max -> turn right (toward the wall on the right).
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, false, WallSubState::kNone, p),
            WallSubState::kTurnRight);
  // Following right, the leading (right) whisker ran off the end: keep passing the edge.
  EXPECT_EQ(wall_sub_state(0.08, true, NAN, false, Side::kRight, true, WallSubState::kFlySideways, p),
            WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(0.05, true, NAN, false, Side::kRight, true, WallSubState::kFlySideways, p),
            WallSubState::kFlyBackward);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kLeft, true, WallSubState::kFlySideways, p),
            WallSubState::kFlySideways);
  // Following right, the trailing (left) whisker lost: with
  // hold_heading_trailing_lost off (rules_off(); gpis_explorer's) as approach ->
  // turn right; with it on (the default) hold the heading and translate.
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, true, WallSubState::kFlySideways, p),
            WallSubState::kTurnRight);
  WallFollowerParams hold = p;
  hold.hold_heading_trailing_lost = true;
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, true, WallSubState::kFlySideways, hold),
            WallSubState::kFlySideways);
  // Invalid flag wins over a finite value; NaN with a valid flag is invalid.
  EXPECT_EQ(wall_sub_state(0.08, true, NAN, true, Side::kRight, false, WallSubState::kNone, p),
            WallSubState::kTurnLeft);
}

// Issue 17 (docs/tuning/tactile_fsm.md "Random baffle courses"): the trailing whisker lost after
// both touched, hand cases. Following right the trailing whisker is the left
// one; following left, the right one. The remaining depth decides the
// translation (band 60-100 mm); the drone never turns toward the lost whisker.
TEST(WallSubStateRule, TrailingWhiskerLostHoldsHeading) {
  WallFollowerParams p = rules_off();
  p.hold_heading_trailing_lost = true;  // the whisker FSM node's default
  const auto ws = WallSubState::kFlySideways;
  // Right side, left lost: remaining right depth in band / too close / too far.
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, true, ws, p), WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.045, true, Side::kRight, true, ws, p), WallSubState::kFlyBackward);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.12, true, Side::kRight, true, ws, p), WallSubState::kFlyForward);
  // Left side, right lost.
  EXPECT_EQ(wall_sub_state(0.07, true, NAN, false, Side::kLeft, true, ws, p), WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(0.05, true, NAN, false, Side::kLeft, true, ws, p), WallSubState::kFlyBackward);
  EXPECT_EQ(wall_sub_state(0.11, true, NAN, false, Side::kLeft, true, WallSubState::kTurnLeft, p),
            WallSubState::kFlyForward);
  // Before both touched (approach) the missing depth still counts as beyond
  // T_max: turn toward the touching whisker to align.
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, false, ws, p), WallSubState::kTurnRight);
  EXPECT_EQ(wall_sub_state(0.08, true, NAN, false, Side::kLeft, false, ws, p), WallSubState::kTurnLeft);
}

// Issue 17, docs/tuning/tactile_fsm.md "Round 7": after both touched, one whisker lost and the
// other beyond T_max. Following right, the leading (right) whisker ran off a
// baffle's end and is still held at 115 mm (truly free), the trailing (left)
// one is released at the end: without the rule the remaining depth asks for
// FLY_FORWARD at V_max / 2 (mocap 3019 flew 1.0 s forward into the end);
// with wall_end_depth the wall ends: FLY_SIDEWAYS. A remaining depth in the
// band or below, and the approach (before both touched), are unchanged.
TEST(WallSubStateRule, OneDepthBeyondWallEndDepthAfterBothTouchedPassesTheEdge) {
  WallFollowerParams p = rules_off();
  p.hold_heading_trailing_lost = true;  // the whisker FSM node's default
  const auto ws = WallSubState::kFlySideways;
  EXPECT_EQ(wall_sub_state(NAN, false, 0.115, true, Side::kRight, true, ws, p), WallSubState::kFlyForward);
  p.wall_end_depth = 0.10;
  EXPECT_EQ(wall_sub_state(NAN, false, 0.115, true, Side::kRight, true, ws, p), WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(0.115, true, NAN, false, Side::kLeft, true, ws, p), WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, true, ws, p), WallSubState::kFlySideways);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.05, true, Side::kRight, true, ws, p), WallSubState::kFlyBackward);
  EXPECT_EQ(wall_sub_state(NAN, false, 0.115, true, Side::kRight, false, ws, p), WallSubState::kFlyForward);  // approach
  EXPECT_EQ(wall_sub_state(NAN, false, 0.08, true, Side::kRight, false, ws, p), WallSubState::kTurnRight);
  // Above the remaining depth: unchanged (FLY_FORWARD); also without the hold rule.
  p.wall_end_depth = 0.12;
  EXPECT_EQ(wall_sub_state(NAN, false, 0.115, true, Side::kRight, true, ws, p), WallSubState::kFlyForward);
  p.hold_heading_trailing_lost = false;
  p.wall_end_depth = 0.10;
  EXPECT_EQ(wall_sub_state(NAN, false, 0.115, true, Side::kRight, true, ws, p), WallSubState::kFlySideways);
  // Through step(): both whiskers on the wall, then the left released with the
  // right still read at 115 mm.
  auto sub_after_release = [](WallFollowerParams q) {
    WhiskerWallFollower fsm(q);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t, 1.0, 0.0));
    for (int k = 0; k < 10; ++k, t += kDt) {
      WallFollowerInput in = input(t, 1.0, 0.0);
      set_depths(in, 0.08, 0.08);
      fsm.step(in);
    }
    return sub_with_left_lost(fsm, t, 0.115);
  };
  WallFollowerParams q = rules_off();
  q.hold_heading_trailing_lost = true;
  EXPECT_EQ(q.wall_end_depth, 0.0);
  EXPECT_EQ(sub_after_release(q), WallSubState::kFlyForward);  // wall_end_depth off
  q.wall_end_depth = 0.10;
  EXPECT_EQ(sub_after_release(q), WallSubState::kFlySideways);
  // 0 (off) or >= t_max, finite.
  q.wall_end_depth = 0.08;
  EXPECT_THROW(q.validate(), std::invalid_argument);
  q.wall_end_depth = -0.1;
  EXPECT_THROW(q.validate(), std::invalid_argument);
  q.wall_end_depth = NAN;
  EXPECT_THROW(q.validate(), std::invalid_argument);
  q.wall_end_depth = 0.0;
  EXPECT_NO_THROW(q.validate());
}

// Issue 17: a contact right after a clearing (less than same_obstacle_distance
// along the course from where the side-step ended) keeps the side although the
// target is now clearly on the other side; further on, the side is re-chosen.
TEST(WhiskerWallFollower, ContactJustAfterClearingKeepsTheSide) {
  auto run = [](double forward_after_resume) {
    WhiskerWallFollower fsm{rules_off()};
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t));
    // Contact at x = 1, target (2, 0) straight ahead -> default side right.
    WallFollowerInput in = input(t, 1.0, 0.0);
    set_depths(in, 0.08, 0.08);
    fsm.step(in);
    EXPECT_EQ(fsm.active_side(), Side::kRight);
    // Sideways to y = -0.6, then both whiskers off for clear_confirm_s.
    double y = 0.0;
    for (int k = 0; k < 150; ++k) {
      t += kDt;
      y -= 0.004;
      in = input(t, 1.0, y);
      set_depths(in, 0.08, 0.08);
      fsm.step(in);
    }
    for (int k = 0; k < 15; ++k) fsm.step(input(t += kDt, 1.0, y));
    EXPECT_EQ(fsm.state(), FsmState::kResumeForward);
    // Side-step the clear margin (0.30 m): now y = -0.9, target 0.9 m to the left.
    for (int k = 0; k < 80 && fsm.state() == FsmState::kResumeForward; ++k) {
      y -= 0.004;
      fsm.step(input(t += kDt, 1.0, y));
    }
    EXPECT_EQ(fsm.state(), FsmState::kFlyForward);
    in = input(t += kDt, 1.0 + forward_after_resume, y);
    set_depths(in, 0.08, 0.08);
    fsm.step(in);
    EXPECT_EQ(fsm.state(), FsmState::kWallFollowing);
    return fsm.active_side();
  };
  EXPECT_EQ(run(0.08), Side::kRight);  // same obstacle (0.08 m < 0.15 m): kept
  EXPECT_EQ(run(0.50), Side::kLeft);   // a new obstacle: toward the target
}

// Issue 17: wall following does not turn beyond max_heading_offset (45 deg)
// from the course heading (0 here, heading at the end of the hover). Depths
// d_l = 100 mm, d_r = 70 mm (theta = atan(0.03/0.05) = 31 deg, wall nearer on
// the right) ask for TURN_RIGHT; at yaw -30 deg it turns, at -46 deg (past the
// limit) it flies sideways instead (both in band), at +46 deg a turn right
// (back toward the course) is still allowed. Below T_min it backs off.
TEST(WhiskerWallFollower, HeadingLimitAboutTheCourse) {
  auto sub_at = [](double yaw_deg, double dl, double dr) {
    WhiskerWallFollower fsm{rules_off()};
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t));
    WallFollowerInput in = input(t, 1.0, 0.0, yaw_deg * kDeg);
    set_depths(in, dl, dr);
    return fsm.step(in).sub_state;
  };
  EXPECT_EQ(sub_at(-30.0, 0.10, 0.07), WallSubState::kTurnRight);
  EXPECT_EQ(sub_at(-46.0, 0.10, 0.07), WallSubState::kFlySideways);
  EXPECT_EQ(sub_at(46.0, 0.10, 0.07), WallSubState::kTurnRight);
  EXPECT_EQ(sub_at(-46.0, 0.10, 0.05), WallSubState::kFlyBackward);
  EXPECT_EQ(sub_at(-46.0, 0.13, 0.09), WallSubState::kFlyForward);
  // Mirror: a turn left is blocked past +45 deg.
  EXPECT_EQ(sub_at(46.0, 0.07, 0.10), WallSubState::kFlySideways);
  EXPECT_EQ(sub_at(30.0, 0.07, 0.10), WallSubState::kTurnLeft);
  // Off (0): the turn is kept.
  WallFollowerParams p = rules_off();
  p.max_heading_offset = 0.0;
  WhiskerWallFollower fsm(p);
  double t = 0.0;
  for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t));
  WallFollowerInput in = input(t, 1.0, 0.0, -46.0 * kDeg);
  set_depths(in, 0.10, 0.07);
  EXPECT_EQ(fsm.step(in).sub_state, WallSubState::kTurnRight);
}

// Issue 17, docs/tuning/tactile_fsm.md "Round 13": the turn anchor. The first tick both whiskers
// touch reads the wall heading (yaw 0, d_l = d_r = 80 mm: heading 0). Depths
// then biased as on textile (d_l 86 mm, d_r 80 mm: theta = atan(0.006/0.05) =
// 6.8 deg < turn_anchor_theta 10 deg) turn the drone right at yaw -5 deg
// (within the 10 deg tolerance) but not at yaw -11 deg (beyond it): there it
// flies sideways. A clear angle (d_l 100, d_r 70 mm: 31 deg) still turns. A
// clear angle read while not turning (here on the tick the left whisker
// touches again) moves the anchor to the wall heading it reads (-42 deg),
// after which the small bias turns at -40 deg; one read in a turn does not
// (the tips drag with the yaw). While not turning the anchor follows the
// heading read at turn_anchor_rate (1 deg/s here): the bias held at -11 deg
// turns again after 2 s, not with the anchor fixed (rate 0). Off: it turns.
TEST(WhiskerWallFollower, TurnAnchorHoldsTheFirstWallHeading) {
  WallFollowerParams p = rules_off();
  p.turn_anchor_tolerance = 10.0 * kDeg;
  p.turn_anchor_theta = 10.0 * kDeg;
  p.turn_anchor_rate = 0.0;
  p.hold_heading_trailing_lost = true;  // as in the node: the trailing whisker lost holds the heading
  struct Phase {
    double yaw_deg, dl, dr, seconds;  // NaN depth: that whisker off the wall
  };
  // Hover, a first touch square at yaw 0 for 0.5 s, then the phases.
  auto run = [](const WallFollowerParams& params, std::vector<Phase> phases) {
    WhiskerWallFollower fsm(params);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t));
    phases.insert(phases.begin(), Phase{0.0, 0.08, 0.08, 0.5});
    WallSubState sub = WallSubState::kNone;
    for (const auto& ph : phases) {
      const int ticks = static_cast<int>(std::lround(ph.seconds / kDt));
      for (int k = 0; k < ticks; ++k, t += kDt) {
        WallFollowerInput in = input(t, 1.0, 0.0, ph.yaw_deg * kDeg);
        set_depths(in, ph.dl, ph.dr);
        in.left_valid = std::isfinite(ph.dl);
        in.right_valid = std::isfinite(ph.dr);
        sub = fsm.step(in).sub_state;
        EXPECT_EQ(fsm.state(), FsmState::kWallFollowing);
      }
    }
    return sub;
  };
  EXPECT_EQ(run(p, {{-5.0, 0.086, 0.080, 0.5}}), WallSubState::kTurnRight);
  EXPECT_EQ(run(p, {{-11.0, 0.086, 0.080, 0.5}}), WallSubState::kFlySideways);
  EXPECT_EQ(run(p, {{-11.0, 0.10, 0.07, 0.5}}), WallSubState::kTurnRight);
  // A clear angle read while not turning moves the anchor (the left whisker
  // touching again: the heading filter restarts on the raw -42 deg)...
  EXPECT_EQ(run(p, {{-11.0, NAN, 0.08, 0.1}, {-11.0, 0.10, 0.07, 0.5}, {-40.0, 0.086, 0.080, 0.5}}),
            WallSubState::kTurnRight);
  // ... one read in a turn does not: at -5 deg the bias turns right on every
  // tick (within the tolerance), the clear angle then arrives during that turn
  // (it would move the anchor to -36 deg), and the bias at -40 deg is refused.
  EXPECT_EQ(run(p, {{-5.0, 0.086, 0.080, 0.5}, {-5.0, 0.10, 0.07, 0.5}, {-40.0, 0.086, 0.080, 0.5}}),
            WallSubState::kFlySideways);
  // Mirror: a left bias at +11 deg is held too; a turn back toward the anchor is not.
  EXPECT_EQ(run(p, {{11.0, 0.080, 0.086, 0.5}}), WallSubState::kFlySideways);
  EXPECT_EQ(run(p, {{11.0, 0.086, 0.080, 0.5}}), WallSubState::kTurnRight);
  // Below T_min the refused turn backs off (the translation the depths ask for).
  EXPECT_EQ(run(p, {{-11.0, 0.061, 0.055, 0.5}}), WallSubState::kFlyBackward);
  // turn_anchor_rate: the anchor creeps toward the heading read (-17.8 deg) while not turning.
  EXPECT_EQ(run(p, {{-11.0, 0.086, 0.080, 2.0}}), WallSubState::kFlySideways);
  WallFollowerParams creep = p;
  creep.turn_anchor_rate = 1.0 * kDeg;
  EXPECT_EQ(run(creep, {{-11.0, 0.086, 0.080, 0.5}}), WallSubState::kFlySideways);
  EXPECT_EQ(run(creep, {{-11.0, 0.086, 0.080, 2.0}}), WallSubState::kTurnRight);  // anchor past -1 deg after ~1 s
  WallFollowerParams off = p;
  off.turn_anchor_tolerance = 0.0;
  EXPECT_EQ(run(off, {{-11.0, 0.086, 0.080, 0.5}}), WallSubState::kTurnRight);
}

TEST(WhiskerWallFollower, TurnAnchorParametersAreValidated) {
  auto bad = [](double tol, double th) {
    WallFollowerParams p = rules_off();
    p.turn_anchor_tolerance = tol;
    p.turn_anchor_theta = th;
    return p;
  };
  EXPECT_NO_THROW(bad(0.0, 0.1).validate());
  EXPECT_NO_THROW(bad(0.2, 0.2).validate());
  EXPECT_THROW(bad(-0.1, 0.2).validate(), std::invalid_argument);
  EXPECT_THROW(bad(M_PI + 0.1, 0.2).validate(), std::invalid_argument);
  EXPECT_THROW(bad(NAN, 0.2).validate(), std::invalid_argument);
  EXPECT_THROW(bad(0.2, 0.0).validate(), std::invalid_argument);
  EXPECT_THROW(bad(0.2, M_PI / 2).validate(), std::invalid_argument);
  EXPECT_THROW(bad(0.2, NAN).validate(), std::invalid_argument);
  WallFollowerParams p = bad(0.2, 0.2);
  p.turn_anchor_rate = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.turn_anchor_rate = INFINITY;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// Issue 17, docs/whisker_fsm.md "Pressed whisker": both depths read 70 mm (in the 60-100 mm
// band, aligned: FLY_SIDEWAYS), but the left whisker's S_c sum is 1200 Pa, over
// press_sum_pa (900 Pa): its depth counts as press_depth (50 mm) < T_min, the
// two whiskers are in different intervals and aligned, so the drone backs off.
// Both pressed: FLY_BACKWARD. Sums below the threshold, unknown sums (NaN), the
// rule off (0 Pa) or a band whose T_min is below press_depth (darkness, 40 mm):
// FLY_SIDEWAYS as before. press_hold_s keeps a pressed whisker pressed for that
// long after its sum fell.
TEST(WhiskerWallFollower, PressedWhiskerCountsAsAtPressDepth) {
  auto sub_at = [](WallFollowerParams p, double sum_l, double sum_r, double sum_l_later = NAN) {
    WhiskerWallFollower fsm(p);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t));
    WallFollowerInput in = input(t, 1.0, 0.0);
    set_depths(in, 0.07, 0.07);
    in.input_sum_left = sum_l;
    in.input_sum_right = sum_r;
    WallSubState s = fsm.step(in).sub_state;
    if (std::isfinite(sum_l_later)) {
      in = input(t += 0.1, 1.0, 0.0);
      set_depths(in, 0.07, 0.07);
      in.input_sum_left = sum_l_later;
      in.input_sum_right = sum_r;
      s = fsm.step(in).sub_state;
    }
    return s;
  };
  WallFollowerParams p = rules_off();
  p.press_sum_pa = 900.0;
  p.press_hold_s = 0.0;
  EXPECT_EQ(sub_at(p, 1200.0, 300.0), WallSubState::kFlyBackward);
  EXPECT_EQ(sub_at(p, 1200.0, 1000.0), WallSubState::kFlyBackward);
  EXPECT_EQ(sub_at(p, 850.0, 300.0), WallSubState::kFlySideways);
  EXPECT_EQ(sub_at(p, NAN, NAN), WallSubState::kFlySideways);
  // Held: 0.1 s after the sum fell to 300 Pa, pressed with a 0.2 s hold, not with none.
  EXPECT_EQ(sub_at(p, 1200.0, 300.0, 300.0), WallSubState::kFlySideways);
  p.press_hold_s = 0.2;
  EXPECT_EQ(sub_at(p, 1200.0, 300.0, 300.0), WallSubState::kFlyBackward);
  // Darkness band 40-100 mm: 50 mm is inside, nothing changes.
  WallFollowerParams dark = p;
  dark.t_min = 0.04;
  EXPECT_EQ(sub_at(dark, 1200.0, 1200.0), WallSubState::kFlySideways);
  // Off (the paper, the core default).
  EXPECT_EQ(sub_at(rules_off(), 1200.0, 1200.0), WallSubState::kFlySideways);
  // Bad values name the field.
  p.press_sum_pa = -1.0;
  expect_rejected(p, "press_sum_pa");
  p.press_sum_pa = 900.0;
  p.press_depth = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// Issue 17, round 4: a held contact whose S_c sum stays quiet while the drone
// travels is a phantom (gel hysteresis, 000 eq. 1). Hand case: both whiskers
// in contact at 70 / 70 mm (in band, aligned: FLY_SIDEWAYS to the right, the
// drone moved 4 mm per tick by hand along -y from where it hovered). With a
// quiet sum (RMS 3 Pa < 8 Pa) the whiskers count as off the wall once the
// drone is more than 0.05 m from where the contact began: tick 13 (52 mm),
// and the obstacle is cleared clear_confirm_s (0.2 s = 10 ticks) after the
// last tick in contact (12): tick 22; without the rule, with a moving
// sum (20 Pa), with an unknown RMS or with the drone hovering in place the
// wall following goes on.
TEST(WhiskerWallFollower, QuietHeldContactWhileTravellingIsPhantom) {
  struct Run {
    int first_phantom_tick = -1;
    int cleared_tick = -1;
  };
  auto fly = [](WallFollowerParams p, double rms, double step_m) {
    WhiskerWallFollower fsm(p);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t, 1.0, 0.0));
    Run r;
    for (int k = 0; k < 40; ++k, t += kDt) {
      WallFollowerInput in = input(t, 1.0, -step_m * k);
      set_depths(in, 0.07, 0.07);
      in.tdorc_contact_left = in.tdorc_contact_right = true;
      in.input_sum_left = in.input_sum_right = 400.0;
      in.input_change_rms_left = in.input_change_rms_right = rms;
      const WallFollowerOutput o = fsm.step(in);
      if (r.first_phantom_tick < 0 && fsm.phantom_left() && fsm.phantom_right()) r.first_phantom_tick = k;
      if (r.cleared_tick < 0 && o.state == FsmState::kResumeForward) r.cleared_tick = k;
    }
    return r;
  };
  WallFollowerParams p = rules_off();
  p.phantom_quiet_rms = 8.0;
  p.phantom_travel = 0.05;
  const Run quiet = fly(p, 3.0, 0.004);
  EXPECT_EQ(quiet.first_phantom_tick, 13);
  EXPECT_EQ(quiet.cleared_tick, 22);
  EXPECT_EQ(fly(p, 20.0, 0.004).cleared_tick, -1);  // the sum moves: a wall
  EXPECT_EQ(fly(p, NAN, 0.004).cleared_tick, -1);   // unknown: kept
  EXPECT_EQ(fly(p, 3.0, 0.0).cleared_tick, -1);     // quiet but hovering: kept
  // Off (the paper, the core default).
  EXPECT_EQ(fly(rules_off(), 3.0, 0.004).cleared_tick, -1);
  // Bad values name the field.
  p.phantom_travel = -0.1;
  expect_rejected(p, "phantom_travel");
  p.phantom_travel = 0.05;
  p.phantom_quiet_rms = NAN;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// Issue 17, round 4: after a phantom clearing, RESUME_FORWARD keeps
// side-stepping while the whisker is still held (TDORC has not released it),
// up to phantom_resume_max from the clearing. Same hand case as above (4 mm
// per tick along -y, cleared at tick 22, y = -0.088 m): with
// phantom_resume_max 0 FLY_FORWARD begins once 0.30 m (clear_margin) from the
// clearing, tick 97 (75 ticks of 4 mm); with 0.6 m not before tick 172 (150
// ticks), or at the first tick past the margin without a held contact (the
// hold ends at tick 120).
TEST(WhiskerWallFollower, ResumeKeepsSideSteppingWhilePhantomHeld) {
  auto fly = [](double resume_max, int release_tick) {
    WallFollowerParams p = rules_off();
    p.phantom_quiet_rms = 8.0;
    p.phantom_travel = 0.05;
    p.phantom_resume_max = resume_max;
    WhiskerWallFollower fsm(p);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t, 1.0, 0.0));
    for (int k = 0; k < 250; ++k, t += kDt) {
      WallFollowerInput in = input(t, 1.0, -0.004 * k);
      in.target_x = 5.0;
      if (k < release_tick) {
        set_depths(in, 0.07, 0.07);
        in.tdorc_contact_left = in.tdorc_contact_right = true;
        in.input_sum_left = in.input_sum_right = 400.0;
        in.input_change_rms_left = in.input_change_rms_right = 3.0;
      }
      if (fsm.step(in).state == FsmState::kFlyForward) return k;
    }
    return -1;
  };
  EXPECT_EQ(fly(0.0, 1000), 97);
  EXPECT_EQ(fly(0.6, 1000), 172);
  EXPECT_EQ(fly(0.6, 120), 120);
  WallFollowerParams p = rules_off();
  p.phantom_resume_max = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// phantom_latch (on in the node since round 4b): the hand case of the gate, then from tick 30
// the quiet sum's RMS reads 9 Pa (noise crossing the 8 Pa quiet level):
// without the latch the phantom is let back in (wall following again at tick
// 30); with it the whisker stays a phantom (still RESUME_FORWARD at tick 39),
// and an RMS of 20 Pa (>= 2 * 8 Pa, a new touch) brings it back.
TEST(WhiskerWallFollower, PhantomLatch) {
  auto state_at_39 = [](bool latch, double later_rms) {
    WallFollowerParams p = rules_off();
    p.phantom_quiet_rms = 8.0;
    p.phantom_travel = 0.05;
    p.phantom_latch = latch;
    WhiskerWallFollower fsm(p);
    double t = 0.0;
    for (; t <= 2.0 + 1e-9; t += kDt) fsm.step(input(t, 1.0, 0.0));
    FsmState s = FsmState::kHoverInit;
    for (int k = 0; k < 40; ++k, t += kDt) {
      WallFollowerInput in = input(t, 1.0, -0.004 * k);
      in.target_x = 5.0;
      set_depths(in, 0.07, 0.07);
      in.tdorc_contact_left = in.tdorc_contact_right = true;
      in.input_sum_left = in.input_sum_right = 400.0;
      in.input_change_rms_left = in.input_change_rms_right = k < 30 ? 3.0 : later_rms;
      s = fsm.step(in).state;
      if (k == 29) {
        EXPECT_EQ(s, FsmState::kResumeForward);
      }
    }
    return s;
  };
  EXPECT_EQ(state_at_39(false, 9.0), FsmState::kWallFollowing);
  EXPECT_EQ(state_at_39(true, 9.0), FsmState::kResumeForward);
  EXPECT_EQ(state_at_39(true, 20.0), FsmState::kWallFollowing);
}

TEST(Saturation, ScalesSpeedAndClampsYawRate) {
  const WallFollowerParams p = rules_off();
  Setpoint s;
  s.vx = 0.3;
  s.vy = 0.4;  // |v| = 0.5 -> scaled by 0.4 to 0.2
  s.yaw_rate = -2.0;
  s.height = 0.4;
  const Setpoint o = tactile_fsm::saturate(s, p);
  EXPECT_NEAR(o.vx, 0.12, 1e-12);
  EXPECT_NEAR(o.vy, 0.16, 1e-12);
  EXPECT_NEAR(o.yaw_rate, -25.0 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(o.height, 0.4);
  s.vx = NAN;
  s.vy = 0.1;
  s.yaw_rate = INFINITY;
  const Setpoint n = tactile_fsm::saturate(s, p);
  EXPECT_EQ(n.vx, 0.0);
  EXPECT_DOUBLE_EQ(n.vy, 0.1);
  EXPECT_EQ(n.yaw_rate, 0.0);
  // A smaller V_max in the params scales the FSM's own commands too.
  WallFollowerParams slow = rules_off();
  slow.v_max = 0.1;
  slow.omega_max = 0.2;
  WhiskerWallFollower fsm(slow);
  for (int k = 0; k <= 150; ++k) fsm.step(input(k * kDt));
  ASSERT_EQ(fsm.state(), FsmState::kFlyForward);
  EXPECT_DOUBLE_EQ(fsm.step(input(151 * kDt)).setpoint.vx, 0.1);
}

// --- Scripted sequence: hover 2 s -> forward -> contact -> wall following ->
// cleared -> resume -> forward -> target -> landing -> landed.
TEST(WhiskerWallFollower, ScriptedStateSequence) {
  const WallFollowerParams p = rules_off();
  WhiskerWallFollower fsm(p);
  double t = 0.0;
  WallFollowerOutput o;
  // Hover for 2 s at the flight height.
  for (; t < 1.99; t += kDt) {
    o = fsm.step(input(t));
    ASSERT_EQ(o.state, FsmState::kHoverInit) << t;
    EXPECT_EQ(o.setpoint.vx, 0.0);
    EXPECT_DOUBLE_EQ(o.setpoint.height, 0.4);
    EXPECT_FALSE(o.setpoint.land);
  }
  o = fsm.step(input(2.0));
  ASSERT_EQ(o.state, FsmState::kFlyForward);
  EXPECT_TRUE(o.transitioned);
  EXPECT_STREQ(fsm.reason(), "hover initialisation done");
  EXPECT_DOUBLE_EQ(o.setpoint.vx, 0.2);  // V_max
  EXPECT_EQ(o.setpoint.vy, 0.0);
  // Contact: TDORC flag on the left whisker, depths still beyond T_max.
  WallFollowerInput in = input(2.5, 0.4);
  in.tdorc_contact_left = true;
  set_depths(in, 0.13, 0.13);
  o = fsm.step(in);
  ASSERT_EQ(o.state, FsmState::kWallFollowing);
  EXPECT_STREQ(fsm.reason(), "whisker contact");
  EXPECT_EQ(fsm.active_side(), Side::kRight);  // target straight ahead -> default side
  EXPECT_EQ(o.sub_state, WallSubState::kFlyForward);
  EXPECT_DOUBLE_EQ(o.setpoint.vx, 0.1);  // V_max / 2
  // In the band: fly sideways to the right at V_max (filter settles within a few ticks).
  t = 2.5;
  for (int k = 0; k < 30; ++k) {
    t += kDt;
    in = input(t, 0.45);
    set_depths(in, 0.08, 0.08);
    o = fsm.step(in);
  }
  EXPECT_EQ(o.state, FsmState::kWallFollowing);
  EXPECT_EQ(o.sub_state, WallSubState::kFlySideways);
  EXPECT_DOUBLE_EQ(o.setpoint.vy, -0.2);
  EXPECT_EQ(o.setpoint.vx, 0.0);
  // Both whiskers leave the wall: cleared clear_confirm_s = 0.2 s after the
  // last tick in contact (t).
  const double off = t + kDt;
  for (int k = 0; k < 9; ++k) {
    o = fsm.step(input(off + k * kDt, 0.45, -0.3));
    ASSERT_EQ(o.state, FsmState::kWallFollowing) << k;
  }
  o = fsm.step(input(t + 0.2, 0.45, -0.3));
  ASSERT_EQ(o.state, FsmState::kResumeForward);
  EXPECT_DOUBLE_EQ(o.setpoint.vy, -0.2);  // side-step the clearance margin
  o = fsm.step(input(off + 0.3, 0.45, -0.59));  // 0.29 m < clear_margin (0.30 m)
  EXPECT_EQ(o.state, FsmState::kResumeForward);
  o = fsm.step(input(off + 0.4, 0.45, -0.61));  // 0.31 m
  ASSERT_EQ(o.state, FsmState::kFlyForward);
  EXPECT_DOUBLE_EQ(o.setpoint.vx, 0.2);
  // Heading realignment to the course heading (0 at the end of the hover):
  // yaw 0.1 rad -> yaw_rate = -realign_gain * 0.1 = -0.15 rad/s; 0.5 rad ->
  // -0.75 saturated at -omega_max.
  {
    WallFollowerInput r = input(off + 0.45, 0.5, -0.61);
    r.yaw = 0.1;
    EXPECT_NEAR(fsm.step(r).setpoint.yaw_rate, -0.15, 1e-12);
    r.t += kDt;
    r.yaw = 0.5;
    EXPECT_NEAR(fsm.step(r).setpoint.yaw_rate, -25.0 * kDeg, 1e-12);
  }
  // Not yet at the target (2, 0): 1.0 m before it.
  o = fsm.step(input(off + 0.5, 1.0, -0.61));
  EXPECT_EQ(o.state, FsmState::kFlyForward);
  EXPECT_EQ(o.setpoint.yaw_rate, 0.0);  // on the course heading
  // Past the target along the course (+x from the start at the origin), 0.61 m to its side.
  o = fsm.step(input(off + 0.6, 2.01, -0.61));
  ASSERT_EQ(o.state, FsmState::kLanding);
  EXPECT_STREQ(fsm.reason(), "target reached");
  EXPECT_TRUE(o.setpoint.land);
  EXPECT_EQ(o.setpoint.height, 0.0);
  o = fsm.step(input(off + 2.5, 2.01, -0.46));
  EXPECT_EQ(o.state, FsmState::kLanding);
  o = fsm.step(input(off + 2.6, 2.01, -0.46));
  EXPECT_EQ(o.state, FsmState::kLanded);
  EXPECT_TRUE(o.setpoint.land);
  EXPECT_EQ(fsm.transitions(), 6u);  // hover->fwd->wall->resume->fwd->landing->landed
}

TEST(WhiskerWallFollower, LandsWithinTargetRadius) {
  WallFollowerParams p = rules_off();
  p.land_past_target = false;
  WhiskerWallFollower fsm(p);
  for (int k = 0; k <= 100; ++k) fsm.step(input(k * kDt));
  ASSERT_EQ(fsm.state(), FsmState::kFlyForward);
  // Past the target but 0.5 m to the side: no landing without land_past_target.
  EXPECT_EQ(fsm.step(input(2.1, 2.2, 0.5)).state, FsmState::kFlyForward);
  EXPECT_EQ(fsm.step(input(2.12, 1.9, 0.1)).state, FsmState::kLanding);  // 0.141 m < 0.15 m
}

TEST(WhiskerWallFollower, SideTowardTargetLateralOffset) {
  // Target (2, 0.5) from the origin heading +x: 0.5 m to the left -> follow left.
  WhiskerWallFollower fsm{rules_off()};
  for (int k = 0; k <= 100; ++k) fsm.step(input(k * kDt));
  WallFollowerInput in = input(2.1);
  in.target_y = 0.5;
  set_depths(in, 0.08, 0.08);
  fsm.step(in);
  ASSERT_EQ(fsm.state(), FsmState::kWallFollowing);
  EXPECT_EQ(fsm.active_side(), Side::kLeft);
  // Heading +y (yaw 90 deg): the same target is 2 m to the right.
  WhiskerWallFollower fsm2{rules_off()};
  for (int k = 0; k <= 100; ++k) fsm2.step(input(k * kDt, 0.0, 0.0, M_PI / 2));
  in = input(2.1, 0.0, 0.0, M_PI / 2);
  in.target_y = 0.5;
  set_depths(in, 0.08, 0.08);
  const WallFollowerOutput o = fsm2.step(in);
  EXPECT_EQ(fsm2.active_side(), Side::kRight);
  EXPECT_DOUBLE_EQ(o.setpoint.vy, -0.2);
  // With side_toward_target off the configured side is used.
  WallFollowerParams p = rules_off();
  p.side_toward_target = false;
  p.follow_side = Side::kLeft;
  WhiskerWallFollower fsm3(p);
  for (int k = 0; k <= 100; ++k) fsm3.step(input(k * kDt));
  in = input(2.1);
  in.target_y = -1.0;
  set_depths(in, 0.08, 0.08);
  fsm3.step(in);
  EXPECT_EQ(fsm3.active_side(), Side::kLeft);
}

TEST(WhiskerWallFollower, StaleDepthFailsafeHoverThenLand) {
  WhiskerWallFollower fsm{rules_off()};
  for (int k = 0; k <= 125; ++k) fsm.step(input(k * kDt));
  ASSERT_EQ(fsm.state(), FsmState::kFlyForward);
  // Depth stops at t = 2.5 s; odometry continues. Stale after 0.2 s.
  WallFollowerOutput o;
  for (int k = 126; k <= 135; ++k) {
    WallFollowerInput in = input(k * kDt);
    in.depth_stamp = 2.5;
    o = fsm.step(in);
    ASSERT_EQ(o.state, FsmState::kFlyForward) << k;
  }
  WallFollowerInput in = input(2.72);
  in.depth_stamp = 2.5;
  o = fsm.step(in);
  ASSERT_EQ(o.state, FsmState::kFailsafeHover);
  EXPECT_STREQ(fsm.reason(), "tactile depth stale");
  EXPECT_EQ(o.setpoint.vx, 0.0);
  EXPECT_EQ(o.setpoint.vy, 0.0);
  EXPECT_DOUBLE_EQ(o.setpoint.height, 0.4);
  EXPECT_FALSE(o.setpoint.land);
  in.t = 4.70;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  in.t = 4.72;  // 2 s after entering the fail-safe hover
  o = fsm.step(in);
  ASSERT_EQ(o.state, FsmState::kFailsafeLand);
  EXPECT_TRUE(o.setpoint.land);
  // Terminal: fresh input does not restart the flight.
  EXPECT_EQ(fsm.step(input(5.0)).state, FsmState::kFailsafeLand);
}

TEST(WhiskerWallFollower, StaleOdometryFailsafeAndRecovery) {
  WhiskerWallFollower fsm{rules_off()};
  for (int k = 0; k <= 125; ++k) fsm.step(input(k * kDt));
  WallFollowerInput in = input(3.0);
  in.odom_stamp = 2.5;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  EXPECT_STREQ(fsm.reason(), "odometry stale");
  // Fresh again before failsafe_land_after_s: resume forward flight.
  EXPECT_EQ(fsm.step(input(3.5)).state, FsmState::kFlyForward);
  EXPECT_STREQ(fsm.reason(), "inputs fresh again");
}

TEST(WhiskerWallFollower, NoInputAtEndOfHoverIsFailsafe) {
  WhiskerWallFollower fsm{rules_off()};
  WallFollowerInput in;  // never received anything
  for (int k = 0; k < 100; ++k) {
    in.t = k * kDt;
    ASSERT_EQ(fsm.step(in).state, FsmState::kHoverInit);
  }
  in.t = 2.0;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  EXPECT_STREQ(fsm.reason(), "tactile depth stale at end of hover");
}

// --- Closed loop: a point drone with yaw integrating the setpoints through a
// first-order velocity lag, a straight wall at a known angle, two whiskers 5 cm
// apart 5 cm ahead of the centre, geometric depths along body x with 2 mm noise.
namespace {

struct ClosedLoopResult {
  bool reached_wall = false;
  double in_band_fraction = 0.0;  ///< both true depths in [T_min, T_max], fraction of the first 10 s of wall following
  double max_heading_error_last5 = 0.0;  ///< [deg], last 5 s of the 10 s
  double min_depth = 1.0;         ///< closest true depth during wall following [m]
  int sideways_ticks = 0;
};

ClosedLoopResult fly_to_wall(double wall_deg, unsigned seed) {
  const WallFollowerParams p = rules_off();
  WhiskerWallFollower fsm(p);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double a = wall_deg * kDeg;
  // Wall: points q with n.q = c, n = (cos a, sin a) pointing into the wall;
  // the perpendicular heading is a. It crosses the x axis at x = 0.6 m.
  const double nx = std::cos(a), ny = std::sin(a), c = 0.6 * nx;
  const double reach = 0.14, base_x = 0.05, half_s = 0.025, tau = 0.1;
  double x = 0.0, y = 0.0, psi = 0.0, vxb = 0.0, vyb = 0.0, r = 0.0;
  auto depth = [&](double side_y) -> double {
    const double bx = x + base_x * std::cos(psi) - side_y * std::sin(psi);
    const double by = y + base_x * std::sin(psi) + side_y * std::cos(psi);
    const double nh = nx * std::cos(psi) + ny * std::sin(psi);
    if (nh <= 1e-3) return NAN;
    const double d = (c - nx * bx - ny * by) / nh;
    return (d >= 0.0 && d <= reach) ? d : NAN;
  };
  ClosedLoopResult res;
  double band_start = -1.0;
  int band_ticks = 0, total_ticks = 0;
  Setpoint sp;
  for (int k = 0; k < 50 * 30; ++k) {
    const double t = k * kDt;
    const double dl = depth(+half_s), dr = depth(-half_s);
    WallFollowerInput in;
    in.t = t;
    in.depth_stamp = in.odom_stamp = t;
    in.left_valid = std::isfinite(dl);
    in.right_valid = std::isfinite(dr);
    in.depth_left = in.left_valid ? dl + noise(rng) : NAN;
    in.depth_right = in.right_valid ? dr + noise(rng) : NAN;
    in.tdorc_contact_left = in.left_valid;
    in.tdorc_contact_right = in.right_valid;
    in.x = x;
    in.y = y;
    in.yaw = psi;
    const WallFollowerOutput o = fsm.step(in);
    sp = o.setpoint;
    if (std::getenv("TACTILE_FSM_TRACE") != nullptr) {  // debugging aid: one line per tick
      std::printf("%.2f %s %s dl=%.4f dr=%.4f err=%.2f\n", t, tactile_fsm::to_string(o.state),
                  tactile_fsm::to_string(o.sub_state), dl, dr, std::remainder(psi - a, 2.0 * M_PI) / kDeg);
    }
    EXPECT_LE(std::hypot(sp.vx, sp.vy), p.v_max + 1e-12);
    EXPECT_LE(std::fabs(sp.yaw_rate), p.omega_max + 1e-12);
    if (o.state == FsmState::kWallFollowing) {
      res.reached_wall = true;
      if (std::isfinite(dl)) res.min_depth = std::min(res.min_depth, dl);
      if (std::isfinite(dr)) res.min_depth = std::min(res.min_depth, dr);
      if (o.sub_state == WallSubState::kFlySideways) ++res.sideways_ticks;
    } else if (res.reached_wall) {
      ADD_FAILURE() << "left wall following at t=" << t << " to " << tactile_fsm::to_string(o.state) << ": "
                    << fsm.reason();
      break;
    }
    const bool in_band = std::isfinite(dl) && std::isfinite(dr) && dl >= p.t_min && dl <= p.t_max &&
                         dr >= p.t_min && dr <= p.t_max;
    if (band_start < 0.0 && res.reached_wall) band_start = t;  // 10 s from the wall-following entry
    if (band_start >= 0.0) {
      if (t >= band_start + 10.0) break;
      ++total_ticks;
      if (in_band) ++band_ticks;
      if (t >= band_start + 5.0) {
        const double err = std::remainder(psi - a, 2.0 * M_PI) / kDeg;
        res.max_heading_error_last5 = std::max(res.max_heading_error_last5, std::fabs(err));
      }
    }
    // Integrate 20 ms in 1 ms steps (velocity lag tau, world-frame motion).
    for (int i = 0; i < 20; ++i) {
      const double h = 0.001;
      vxb += (sp.vx - vxb) * h / tau;
      vyb += (sp.vy - vyb) * h / tau;
      r += (sp.yaw_rate - r) * h / tau;
      x += (vxb * std::cos(psi) - vyb * std::sin(psi)) * h;
      y += (vxb * std::sin(psi) + vyb * std::cos(psi)) * h;
      psi += r * h;
    }
  }
  res.in_band_fraction = total_ticks > 0 ? static_cast<double>(band_ticks) / total_ticks : 0.0;
  if (total_ticks < 499) ADD_FAILURE() << "wall following shorter than 10 s: " << total_ticks << " ticks";
  return res;
}

}  // namespace

class ClosedLoop : public ::testing::TestWithParam<double> {};

TEST_P(ClosedLoop, KeepsBandAndPerpendicularHeading) {
  const double wall_deg = GetParam();
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    const ClosedLoopResult r = fly_to_wall(wall_deg, seed);
    ASSERT_TRUE(r.reached_wall) << wall_deg;
    EXPECT_GE(r.in_band_fraction, 0.90) << "wall " << wall_deg << " deg, seed " << seed;
    EXPECT_LE(r.max_heading_error_last5, 5.0) << "wall " << wall_deg << " deg, seed " << seed;
    EXPECT_GT(r.min_depth, 0.03) << "wall " << wall_deg << " deg, seed " << seed;
    // It actually follows the wall (sideways most of the time), not just hovers.
    EXPECT_GT(r.sideways_ticks, 250) << "wall " << wall_deg << " deg, seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(WallAngles, ClosedLoop, ::testing::Values(0.0, 20.0, -20.0, 30.0, -30.0));

// --- Baffle course (000 Fig. 4a/4e geometry as in the repository's
// three_baffles / tilted_baffles arenas): finite walls, the drone must pass
// each baffle at an end and land past the last one without touching a baffle
// with its frame.
namespace {

struct Segment {
  double ax, ay, bx, by;
};

double point_segment_distance(double px, double py, const Segment& s) {
  const double vx = s.bx - s.ax, vy = s.by - s.ay;
  const double u = std::clamp(((px - s.ax) * vx + (py - s.ay) * vy) / (vx * vx + vy * vy), 0.0, 1.0);
  return std::hypot(px - (s.ax + u * vx), py - (s.ay + u * vy));
}

/// The two segments cross (proper intersection).
bool segments_cross(const Segment& p, const Segment& q) {
  auto side = [](const Segment& s, double x, double y) { return (s.bx - s.ax) * (y - s.ay) - (s.by - s.ay) * (x - s.ax); };
  return side(q, p.ax, p.ay) * side(q, p.bx, p.by) < 0.0 && side(p, q.ax, q.ay) * side(p, q.bx, q.by) < 0.0;
}

struct CourseResult {
  FsmState final_state = FsmState::kHoverInit;
  int wall_episodes = 0;
  double min_frame_clearance = 1.0;  ///< centre-to-baffle distance [m]
  double final_x = 0.0;
};

CourseResult fly_course(const std::vector<Segment>& walls, double t_max) {
  WallFollowerParams p = rules_off();
  p.t_max = t_max;
  WhiskerWallFollower fsm(p);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double reach = 0.14, base_x = 0.05, half_s = 0.025, tau = 0.1;
  double x = 0.0, y = 0.0, psi = 0.0, vxb = 0.0, vyb = 0.0, r = 0.0;
  auto depth = [&](double side_y) -> double {
    const double bx = x + base_x * std::cos(psi) - side_y * std::sin(psi);
    const double by = y + base_x * std::sin(psi) + side_y * std::cos(psi);
    const double hx = std::cos(psi), hy = std::sin(psi);
    double best = NAN;
    for (const Segment& s : walls) {  // ray b + d h against segment a + u (b - a)
      const double ex = s.bx - s.ax, ey = s.by - s.ay;
      const double den = hx * ey - hy * ex;
      if (std::fabs(den) < 1e-9) continue;
      const double wx = s.ax - bx, wy = s.ay - by;
      const double d = (wx * ey - wy * ex) / den;
      const double u = (wx * hy - wy * hx) / den;
      if (d >= 0.0 && d <= reach && u >= 0.0 && u <= 1.0 && !(best <= d)) best = d;
    }
    return best;
  };
  CourseResult res;
  FsmState last = FsmState::kHoverInit;
  for (int k = 0; k < 50 * 120 && fsm.state() != FsmState::kLanded; ++k) {
    const double t = k * kDt;
    const double dl = depth(+half_s), dr = depth(-half_s);
    WallFollowerInput in;
    in.t = t;
    in.depth_stamp = in.odom_stamp = t;
    in.left_valid = std::isfinite(dl);
    in.right_valid = std::isfinite(dr);
    in.depth_left = in.left_valid ? dl + noise(rng) : NAN;
    in.depth_right = in.right_valid ? dr + noise(rng) : NAN;
    in.tdorc_contact_left = in.left_valid;
    in.tdorc_contact_right = in.right_valid;
    in.x = x;
    in.y = y;
    in.yaw = psi;
    in.has_target = true;
    in.target_x = 3.6;
    in.target_y = 0.0;
    const Setpoint sp = fsm.step(in).setpoint;
    if (fsm.state() == FsmState::kWallFollowing && last != FsmState::kWallFollowing) ++res.wall_episodes;
    last = fsm.state();
    for (const Segment& s : walls) res.min_frame_clearance = std::min(res.min_frame_clearance, point_segment_distance(x, y, s));
    for (int i = 0; i < 20; ++i) {
      const double h = 0.001;
      vxb += (sp.vx - vxb) * h / tau;
      vyb += (sp.vy - vyb) * h / tau;
      r += (sp.yaw_rate - r) * h / tau;
      x += (vxb * std::cos(psi) - vyb * std::sin(psi)) * h;
      y += (vxb * std::sin(psi) + vyb * std::cos(psi)) * h;
      psi += r * h;
    }
  }
  res.final_state = fsm.state();
  res.final_x = x;
  return res;
}

}  // namespace

TEST(BaffleCourse, ThreeParallelBafflesReachTarget) {
  // arenas/three_baffles.yaml: -90.76, -91.34, -90.77 deg; gaps right, left, right.
  const std::vector<Segment> walls = {{1.0080, 0.8999, 0.9920, -0.2999},
                                      {2.0140, 0.2998, 1.9860, -0.8998},
                                      {3.0081, 0.8999, 2.9919, -0.2999}};
  const CourseResult r = fly_course(walls, 0.100);  // 000 Fig. 4c band 60-100 mm
  EXPECT_EQ(r.final_state, FsmState::kLanded);
  EXPECT_EQ(r.wall_episodes, 3);
  EXPECT_GT(r.final_x, 3.0);
  EXPECT_GT(r.min_frame_clearance, 0.08);  // whisker base 50 mm ahead + T_min 60 mm, minus tilt
}

TEST(BaffleCourse, TiltedBafflesReachTarget) {
  // arenas/tilted_baffles.yaml: -90.90, -65.71, -91.15 deg; band 60-105 mm (000 Fig. 4g).
  const std::vector<Segment> walls = {{1.0094, 0.8999, 0.9906, -0.2999},
                                      {1.7532, 0.2469, 2.2468, -0.8469},
                                      {3.0120, 0.8999, 2.9880, -0.2999}};
  const CourseResult r = fly_course(walls, 0.105);
  EXPECT_EQ(r.final_state, FsmState::kLanded);
  // After following the middle baffle the heading is its normal (24.3 deg,
  // 000 Fig. 4h) and forward flight keeps it (body-frame forward, 000
  // Methods), so the drone may pass beside the third baffle's end instead of
  // touching it: at least the first two are followed.
  EXPECT_GE(r.wall_episodes, 2);
  EXPECT_GT(r.final_x, 3.0);
  EXPECT_GT(r.min_frame_clearance, 0.06);
}

// Issue 17, docs/tuning/tactile_fsm.md "Round 9": after a clearing the body yaw is held
// clear_yaw_offset away from the side-step side (left here: the target is
// ahead, follow_side right, the drone side-steps right), in the FLY_FORWARD
// after it (not during the side-step), while the
// track is the one flown without the offset (side-step along -y, then +x at
// V_max). Kinematic drone: the left whisker's tip (base (0.05, 0.025), reach
// 0.141 m) reaches beyond the guard's 80 mm on the left, where the next
// baffle's outer end lies; off, it stays at 25 mm.
TEST(WhiskerWallFollower, YawOffsetAfterClearingTurnsWhiskersNotTrack) {
  auto fly = [](double offset) {
    WallFollowerParams p = rules_off();
    p.clear_yaw_offset = offset;
    WhiskerWallFollower fsm(p);
    double t = 0.0, x = 0.0, y = 0.0, yaw = 0.0;
    for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t, x, y, yaw));
    // Touch: both whiskers in the band for 1 s (square wall, FLY_SIDEWAYS right).
    for (int k = 0; k < 50; ++k, t += kDt) {
      WallFollowerInput in = input(t, x, y, yaw);
      set_depths(in, 0.08, 0.08);
      fsm.step(in);
    }
    EXPECT_EQ(fsm.state(), FsmState::kWallFollowing);
    double tip_left = 0.0, max_track_x = 0.0, min_fwd_y = 1.0, max_fwd_y = -1.0, resume_y0 = NAN;
    double max_resume_yaw = 0.0;
    bool resumed = false, forward = false;
    for (int k = 0; k < 300; ++k, t += kDt) {
      const WallFollowerOutput o = fsm.step(input(t, x, y, yaw));
      EXPECT_LE(std::fabs(o.setpoint.yaw_rate), p.omega_max + 1e-12);
      const double vx = std::cos(yaw) * o.setpoint.vx - std::sin(yaw) * o.setpoint.vy;
      const double vy = std::sin(yaw) * o.setpoint.vx + std::cos(yaw) * o.setpoint.vy;
      if (o.state == FsmState::kResumeForward) {
        if (!resumed) resume_y0 = y;
        resumed = true;
        max_track_x = std::max(max_track_x, std::fabs(vx));  // side-step stays along -y
        max_resume_yaw = std::max(max_resume_yaw, std::fabs(yaw));
      }
      if (o.state == FsmState::kFlyForward) {
        forward = true;
        EXPECT_NEAR(vx, p.v_max, 1e-9);  // full V_max along the course
        min_fwd_y = std::min(min_fwd_y, y);
        max_fwd_y = std::max(max_fwd_y, y);
        // Lateral reach of the left whisker's tip to the left of the axis.
        tip_left = std::max(tip_left, 0.191 * std::sin(yaw) + 0.025 * std::cos(yaw));
      }
      x += vx * kDt;
      y += vy * kDt;
      yaw += o.setpoint.yaw_rate * kDt;
    }
    EXPECT_TRUE(resumed);
    EXPECT_TRUE(forward);
    EXPECT_LT(max_track_x, 1e-9);
    EXPECT_NEAR(max_fwd_y - min_fwd_y, 0.0, 1e-9);  // straight along the course
    EXPECT_LT(y, resume_y0 - p.clear_margin + 1e-6);
    return std::vector<double>{tip_left, yaw, max_resume_yaw};
  };
  const std::vector<double> off = fly(0.0);
  EXPECT_NEAR(off[0], 0.025, 1e-9);
  EXPECT_NEAR(off[1], 0.0, 1e-9);
  const std::vector<double> on = fly(20.0 * kDeg);
  EXPECT_GT(on[0], 0.085);                       // beyond the guard's 80 mm
  EXPECT_NEAR(on[1], 20.0 * kDeg, 0.5 * kDeg);   // held to the left, away from the side-step
  EXPECT_NEAR(on[2], 0.0, 1e-9);                 // not during the side-step
  WallFollowerParams bad = rules_off();
  bad.clear_yaw_offset = -0.1;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad.clear_yaw_offset = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// clear_yaw_release_rms (docs/tuning/tactile_fsm.md "Round 9"): once a whisker's S_c sum moves
// (a touch TDORC has not flagged yet) the offset is dropped until the next
// clearing: the yaw goes back to the track's heading.
TEST(WhiskerWallFollower, YawOffsetReleasedOnMovingSum) {
  auto final_yaw = [](double release_rms, double rms) {
    WallFollowerParams p = rules_off();
    p.clear_yaw_offset = 20.0 * kDeg;
    p.clear_yaw_release_rms = release_rms;
    WhiskerWallFollower fsm(p);
    double t = 0.0, x = 0.0, y = 0.0, yaw = 0.0;
    for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t, x, y, yaw));
    for (int k = 0; k < 50; ++k, t += kDt) {
      WallFollowerInput in = input(t, x, y, yaw);
      set_depths(in, 0.08, 0.08);
      fsm.step(in);
    }
    double forward_s = 0.0;
    for (int k = 0; k < 400; ++k, t += kDt) {
      WallFollowerInput in = input(t, x, y, yaw);
      // The sum starts moving 2 s into FLY_FORWARD (no contact flagged).
      in.input_change_rms_left = forward_s > 2.0 ? rms : 3.0;
      in.input_change_rms_right = 3.0;
      const WallFollowerOutput o = fsm.step(in);
      if (o.state == FsmState::kFlyForward) forward_s += kDt;
      const double vx = std::cos(yaw) * o.setpoint.vx - std::sin(yaw) * o.setpoint.vy;
      const double vy = std::sin(yaw) * o.setpoint.vx + std::cos(yaw) * o.setpoint.vy;
      x += vx * kDt;
      y += vy * kDt;
      yaw += o.setpoint.yaw_rate * kDt;
    }
    EXPECT_GT(forward_s, 4.0);
    return yaw;
  };
  EXPECT_NEAR(final_yaw(0.0, 20.0), 20.0 * kDeg, 0.5 * kDeg);   // off: offset kept
  EXPECT_NEAR(final_yaw(13.0, 5.0), 20.0 * kDeg, 0.5 * kDeg);   // quiet sum: kept
  EXPECT_NEAR(final_yaw(13.0, 20.0), 0.0, 0.5 * kDeg);          // moving sum: back to the track
  WallFollowerParams bad = rules_off();
  bad.clear_yaw_release_rms = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

namespace {

/// A point drone that flies the setpoints exactly (velocity in the body-yaw frame).
struct PointDrone {
  double x = 0.0, y = 0.0, yaw = 0.0;
  void move(const WallFollowerOutput& o) {
    x += (std::cos(yaw) * o.setpoint.vx - std::sin(yaw) * o.setpoint.vy) * kDt;
    y += (std::sin(yaw) * o.setpoint.vx + std::cos(yaw) * o.setpoint.vy) * kDt;
    yaw += o.setpoint.yaw_rate * kDt;
  }
};

/// The FLY_FORWARD after a first contact (both whiskers at 80 mm for 1 s) and
/// its clearing (8 s of free whiskers): its ticks, largest |yaw rate| and
/// smallest forward speed.
struct AfterClearing {
  int forward = 0;
  double max_rate = 0.0;
  double min_vx = INFINITY;
};

AfterClearing contact_then_clear(WhiskerWallFollower& fsm, PointDrone& d, double& t) {
  for (int k = 0; k < 50; ++k, t += kDt) {
    WallFollowerInput in = input(t, d.x, d.y, d.yaw);
    set_depths(in, 0.08, 0.08);
    d.move(fsm.step(in));
  }
  EXPECT_EQ(fsm.state(), FsmState::kWallFollowing);
  AfterClearing a;
  for (int k = 0; k < 400; ++k, t += kDt) {
    const WallFollowerOutput o = fsm.step(input(t, d.x, d.y, d.yaw));
    if (o.state == FsmState::kFlyForward) {
      ++a.forward;
      a.max_rate = std::max(a.max_rate, std::fabs(o.setpoint.yaw_rate));
      a.min_vx = std::min(a.min_vx, o.setpoint.vx);
    }
    d.move(o);
  }
  return a;
}

// Into the first scan of the step and scan (|yaw| >= 0.3 rad), then the
// depth stale for 0.3 s: a fail-safe hover cuts the scan. Returns the time.
double scan_cut_by_failsafe(WhiskerWallFollower& fsm, const WallFollowerParams& p, PointDrone& d) {
  double t = 0.0;
  for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t));
  while (std::fabs(d.yaw) < 0.3 && t < 10.0) {
    d.move(fsm.step(input(t, d.x, d.y, d.yaw)));
    t += kDt;
  }
  EXPECT_GE(std::fabs(d.yaw), 0.3);
  for (int k = 0; k < 15; ++k, t += kDt) {
    WallFollowerInput in = input(t, d.x, d.y, d.yaw);
    in.depth_stamp = p.hover_init_s;
    d.move(fsm.step(in));
  }
  EXPECT_EQ(fsm.state(), FsmState::kFailsafeHover);
  return t;
}

}  // namespace

// end_contact_lateral (docs/tuning/tactile_fsm.md "Round 10"): a first touch by the right whisker
// alone, depth 100 mm, at a yaw 20 deg right of the course puts the contact
// point 0.15 sin 20 + 0.025 cos 20 = 75 mm right of the axis: a baffle's end
// on the right; with the rule the drone passes it on the left, side-stepping
// (as at an edge) instead of approaching it. At yaw 0 (25 mm) or with the rule
// off the contact is an approach on the default side (right).
TEST(WhiskerWallFollower, EndContactBesideTheAxisIsPassedOnTheOtherSide) {
  auto first_touch = [](double lateral, double yaw) {
    WallFollowerParams p = rules_off();
    p.end_contact_lateral = lateral;
    p.side_toward_target = false;  // the default side (right) unless the rule picks
    WhiskerWallFollower fsm(p);
    double t = 0.0;
    for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t));
    fsm.step(input(t, 0.1, 0.0, yaw));
    t += kDt;
    WallFollowerInput in = input(t, 0.1, 0.0, yaw);
    in.right_valid = true;
    in.depth_right = 0.10;
    in.tdorc_contact_right = true;
    const WallFollowerOutput o = fsm.step(in);
    EXPECT_EQ(o.state, FsmState::kWallFollowing);
    return std::make_pair(fsm.active_side(), o.sub_state);
  };
  const auto on = first_touch(0.045, -20.0 * kDeg);
  EXPECT_EQ(on.first, Side::kLeft);
  EXPECT_EQ(on.second, WallSubState::kFlySideways);
  const auto square = first_touch(0.045, 0.0);
  EXPECT_EQ(square.first, Side::kRight);
  EXPECT_NE(square.second, WallSubState::kFlySideways);
  const auto off = first_touch(0.0, -20.0 * kDeg);
  EXPECT_EQ(off.first, Side::kRight);
  EXPECT_NE(off.second, WallSubState::kFlySideways);
  WallFollowerParams bad = rules_off();
  bad.end_contact_lateral = -0.01;
  expect_rejected(bad, "end_contact_lateral");
}

namespace {

/// What meets the segment (ax, ay)-(bx, by) first on the first approach of a
/// point drone with a first-order velocity lag (`lag` s, the vehicle's ~0.23 s)
/// and the paper's whisker geometry (segments (0.05..0.191, +-0.025) of the
/// body frame, guard circle 0.08 m), and the yaw off the course at that moment.
struct FirstMeet {
  std::string who = "none";  ///< "whisker", "guard" or "none"
  double yaw = NAN;          ///< [rad]
  double t = NAN;            ///< [s]
};

FirstMeet first_meet(const WallFollowerParams& p, double ax, double ay, double bx, double by, double lag = 0.23) {
  const Segment obstacle{ax, ay, bx, by};
  WhiskerWallFollower fsm(p);
  double x = 0.0, y = 0.0, yaw = 0.0, wx = 0.0, wy = 0.0, wr = 0.0;  // world velocity, yaw rate
  for (double t = 0.0; t < 60.0; t += kDt) {
    WallFollowerInput in = input(t, x, y, yaw);
    in.target_x = 4.0;
    const WallFollowerOutput o = fsm.step(in);
    const double cx = std::cos(yaw) * o.setpoint.vx - std::sin(yaw) * o.setpoint.vy;
    const double cy = std::sin(yaw) * o.setpoint.vx + std::cos(yaw) * o.setpoint.vy;
    for (int k = 0; k < 10; ++k) {  // 2 ms sub-steps of the 20 ms tick
      const double h = 0.1 * kDt;
      wx += (cx - wx) * h / lag;
      wy += (cy - wy) * h / lag;
      wr += (o.setpoint.yaw_rate - wr) * h / 0.05;  // yaw-rate lag of the firmware
      x += wx * h;
      y += wy * h;
      yaw += wr * h;
      const double c = std::cos(yaw), s = std::sin(yaw);
      for (double side : {1.0, -1.0}) {
        const double b0x = x + c * 0.05 - s * side * 0.025, b0y = y + s * 0.05 + c * side * 0.025;
        const double t0x = x + c * 0.191 - s * side * 0.025, t0y = y + s * 0.191 + c * side * 0.025;
        if (segments_cross({b0x, b0y, t0x, t0y}, obstacle)) return {"whisker", yaw, t};
      }
      if (point_segment_distance(x, y, obstacle) <= 0.08) return {"guard", yaw, t};
    }
  }
  return {};
}

WallFollowerParams scan_params(double step) {
  WallFollowerParams p = rules_off();
  p.first_whisk_amplitude = 0.44;
  p.first_scan_step = step;
  p.first_scan_rate = 2.0;
  p.whisk_rate_max = 3.0;
  return p;
}

}  // namespace

// Step and scan (docs/tuning/tactile_fsm.md "Round 12"): course 1003's first baffle, whose near end
// lies 65 mm right of the axis, is met by the guard on the paper's straight
// approach and by a whisker in a scan (yawed); a wall across the course is
// mostly met in a step, at the course heading (round 10's continuous whisk
// met it at a whisked yaw, which the shipped course tests refused).
TEST(WhiskerWallFollower, StepAndScanFindsTheEndAndMeetsAWallAheadInAStep) {
  const double ax = 0.7141, ay = -0.0647, bx = 1.0361, by = -0.9199;  // baffle_1 of baffles_*_1003
  WallFollowerParams straight = rules_off();
  EXPECT_EQ(first_meet(straight, ax, ay, bx, by).who, "guard");
  const FirstMeet end = first_meet(scan_params(0.08), ax, ay, bx, by);
  EXPECT_EQ(end.who, "whisker");
  EXPECT_GT(std::fabs(end.yaw), 5.0 * kDeg);  // found in a scan
  // Walls 11 mm apart: every phase of a step. Measured: the scan meets 7 of
  // the 10 within 0.9-1.5 deg of the course; the other 3 lay just beyond the
  // tips when a scan began and are met in it (6-19 deg) as the drone creeps on
  // to the step's end.
  int scan_on_course = 0;
  for (int k = 0; k < 10; ++k) {
    const double wall_x = 0.60 + 0.011 * k;
    SCOPED_TRACE("wall at x = " + std::to_string(wall_x));
    const FirstMeet m = first_meet(scan_params(0.08), wall_x, -2.0, wall_x, 2.0);
    EXPECT_EQ(m.who, "whisker");
    if (std::fabs(m.yaw) < 2.0 * kDeg) ++scan_on_course;
  }
  EXPECT_GE(scan_on_course, 7);
}

// The scan is held while a whisker's sum moves (a touch TDORC has not flagged
// yet), from where it stopped, for at most 1 s per scan; the step's speed is
// never above V_max; parameters are validated.
TEST(WhiskerWallFollower, StepAndScanHoldsTheYawOnAMovingSumAndValidates) {
  WallFollowerParams p = scan_params(0.08);
  p.whisk_pause_rms = 13.0;
  WhiskerWallFollower fsm(p);
  double t = 0.0, x = 0.0, yaw = 0.0;
  for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t));
  for (int k = 0; k < 200 && std::fabs(yaw) <= 0.1; ++k, t += kDt) {
    const WallFollowerOutput o = fsm.step(input(t, x, 0.0, yaw));
    EXPECT_LE(o.setpoint.vx, p.v_max + 1e-12);
    EXPECT_NEAR(std::sin(yaw) * o.setpoint.vx + std::cos(yaw) * o.setpoint.vy, 0.0, 1e-12);  // on the course
    x += o.setpoint.vx * kDt;
    yaw += o.setpoint.yaw_rate * kDt;
  }
  ASSERT_GT(std::fabs(yaw), 0.1);  // scanning
  EXPECT_NEAR(x, 0.08, 0.015);     // at the step's end
  // The sum moves for 0.4 s: the yaw is held on every tick.
  for (int k = 0; k < 20; ++k, t += kDt) {
    WallFollowerInput in = input(t, x, 0.0, yaw);
    in.input_change_rms_right = 40.0;
    EXPECT_EQ(fsm.step(in).setpoint.yaw_rate, 0.0);
  }
  // Quiet again: the scan goes on from where it was held (the reference did
  // not run ahead: the yaw rate is the leg's feed-forward plus a small
  // correction, not a jump toward a reference 0.8 rad further on).
  const WallFollowerOutput go = fsm.step(input(t, x, 0.0, yaw));
  t += kDt;
  EXPECT_GT(go.setpoint.yaw_rate, 0.5 * p.first_scan_rate);
  EXPECT_LT(go.setpoint.yaw_rate, 1.5 * p.first_scan_rate);
  // A sum moving for longer than 1 s without a flag holds the scan 1 s only.
  int held = 0;
  for (int k = 0; k < 100; ++k, t += kDt) {
    WallFollowerInput in = input(t, x, 0.0, yaw);
    in.input_change_rms_right = 40.0;
    const WallFollowerOutput o = fsm.step(in);
    if (o.setpoint.yaw_rate == 0.0) ++held;
    yaw += o.setpoint.yaw_rate * kDt;
  }
  EXPECT_GE(held, 29);  // 1 s in all, 0.4 s of it above
  EXPECT_LE(held, 32);
  WallFollowerParams bad = scan_params(0.08);
  bad.first_scan_step = -0.01;
  expect_rejected(bad, "first_scan_step");
  bad.first_scan_step = 0.01;  // the step would end before it began
  expect_rejected(bad, "first_scan_step");
  bad = scan_params(0.08);
  bad.first_scan_rate = 4.0;  // > whisk_rate_max
  expect_rejected(bad, "first_scan_rate");
  bad.first_scan_rate = 0.0;
  expect_rejected(bad, "first_scan_rate");
  bad = scan_params(0.08);
  bad.first_scan_step = 0.0;  // no continuous whisk any more: the scan needs a step
  expect_rejected(bad, "first_scan_step");
}

// The scan ends at the first contact: after it and a clearing, FLY_FORWARD
// flies as without the rule; and a first approach re-entered off the course
// (after a fail-safe hover in a scan) settles before it steps.
TEST(WhiskerWallFollower, StepAndScanEndsAtTheFirstContactAndSettlesOnReentry) {
  WallFollowerParams p = scan_params(0.08);
  p.realign_gain = 1.5;
  WhiskerWallFollower fsm(p);
  PointDrone d;
  double t = scan_cut_by_failsafe(fsm, p, d);  // then fresh again
  // Back in FLY_FORWARD at ~0.3 rad off the course: no speed along the course
  // until the yaw is back within 0.05 rad.
  double along_while_off = 0.0;
  int settle_ticks = 0;
  for (; settle_ticks < 150 && std::fabs(d.yaw) >= 0.05; ++settle_ticks, t += kDt) {
    const WallFollowerOutput o = fsm.step(input(t, d.x, d.y, d.yaw));
    ASSERT_EQ(o.state, FsmState::kFlyForward);
    along_while_off = std::max(along_while_off, std::cos(d.yaw) * o.setpoint.vx - std::sin(d.yaw) * o.setpoint.vy);
    d.move(o);
  }
  EXPECT_LT(settle_ticks, 150);  // settled (1.2 s at the tracking gain)
  EXPECT_LT(along_while_off, 0.02);
  // First contact, then a clearing: no scan afterwards.
  const AfterClearing a = contact_then_clear(fsm, d, t);
  EXPECT_GT(a.forward, 100);
  EXPECT_LT(a.max_rate, p.omega_max + 1e-9);  // realignment only, no 2 rad/s scan
  EXPECT_GT(a.min_vx, 0.9 * p.v_max);         // no steps: V_max throughout
}

// A scan cut short by a fail-safe hover while the yaw is then back on the
// course (here: the pose is re-aligned during the hover) steps at the course:
// the cut scan's yaw offset is not kept while stepping.
TEST(WhiskerWallFollower, StepAndScanReentryOnTheCourseKeepsNoScanOffset) {
  WallFollowerParams p = scan_params(0.08);
  WhiskerWallFollower fsm(p);
  PointDrone d;
  const double t = scan_cut_by_failsafe(fsm, p, d);
  ASSERT_EQ(fsm.state(), FsmState::kFailsafeHover);
  d.yaw = 0.0;
  const WallFollowerOutput o = fsm.step(input(t, d.x, d.y, d.yaw));
  ASSERT_EQ(o.state, FsmState::kFlyForward);
  EXPECT_NEAR(o.setpoint.yaw_rate, 0.0, 1e-9);  // was 0.48 rad/s: the cut scan's offset tracked
  EXPECT_GT(o.setpoint.vx, 0.0);                // stepping along the course
}

// A non-finite position in the first approach (the core API; the node drops
// such odometry) gives no step-and-scan setpoint: the output stays finite.
TEST(WhiskerWallFollower, StepAndScanIgnoresANonFinitePosition) {
  WallFollowerParams p = scan_params(0.08);
  WhiskerWallFollower fsm(p);
  double t = 0.0;
  for (; t < p.hover_init_s + 1e-9; t += kDt) fsm.step(input(t));
  for (int k = 0; k < 10; ++k, t += kDt) fsm.step(input(t, 0.01 * k, 0.0, 0.0));
  const WallFollowerOutput o = fsm.step(input(t, NAN, 0.0, 0.0));
  EXPECT_TRUE(std::isfinite(o.setpoint.vx));
  EXPECT_TRUE(std::isfinite(o.setpoint.vy));
  EXPECT_TRUE(std::isfinite(o.setpoint.yaw_rate));
}

// --- Override rules (issue 33): each rule alone on a hand-made snapshot, in the
// situation that fires it and just outside it; then the follower's counts and reasons.

namespace {

using tactile_fsm::HeadingLimitRule;
using tactile_fsm::OverrideRule;
using tactile_fsm::StepAndScanRule;
using tactile_fsm::TickSnapshot;
using tactile_fsm::TurnAnchorRule;
using tactile_fsm::YawOffsetRule;

/// Wall following on the course heading 0, both depths valid (80 mm, in the
/// band), the drone at yaw `yaw`, the sub-state rule asking `asked`.
TickSnapshot wall_snapshot(double yaw, WallSubState asked) {
  TickSnapshot s;
  s.in = input(10.0, 1.0, 0.0, yaw);
  s.dt = kDt;
  s.state = FsmState::kWallFollowing;
  s.current = WallSubState::kFlySideways;
  s.l_valid = s.r_valid = true;
  s.d_left = s.d_right = 0.08;
  s.theta = 0.0;
  s.wall_heading = yaw;
  s.origin_set = true;
  s.contacted = true;
  s.sub_state = asked;
  return s;
}

/// FLY_FORWARD on the course heading 0 at (x, 0), state's setpoint V_max ahead.
TickSnapshot forward_snapshot(double x, bool after_clear, bool contacted) {
  TickSnapshot s;
  s.in = input(10.0, x, 0.0, 0.0);
  s.dt = kDt;
  s.state = FsmState::kFlyForward;
  s.origin_set = true;
  s.after_clear = after_clear;
  s.contacted = contacted;
  s.setpoint.vx = 0.2;
  s.setpoint.height = 0.4;
  return s;
}

}  // namespace

TEST(OverrideRules, NamesInRunOrder) {
  EXPECT_STREQ(tactile_fsm::to_string(OverrideRule::kHeadingLimit), "heading_limit");
  EXPECT_STREQ(tactile_fsm::to_string(OverrideRule::kTurnAnchor), "turn_anchor");
  EXPECT_STREQ(tactile_fsm::to_string(OverrideRule::kStepAndScan), "step_and_scan");
  EXPECT_STREQ(tactile_fsm::to_string(OverrideRule::kYawOffset), "yaw_offset");
}

// A left turn asked for at 50 deg left of the course (limit 45 deg) becomes
// the translation the depths ask for: sideways in the band, forward with one
// depth beyond T_max, backward with one below T_min.
TEST(OverrideRules, HeadingLimitFiresOnATurnBeyondTheLimitOnly) {
  const WallFollowerParams p;  // max_heading_offset 45 deg
  HeadingLimitRule rule(p);
  TickSnapshot s = wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft);
  ASSERT_TRUE(rule.applies(s));
  rule.apply(s);
  EXPECT_EQ(s.sub_state, WallSubState::kFlySideways);
  s = wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft);
  s.d_right = 0.12;
  rule.apply(s);
  EXPECT_EQ(s.sub_state, WallSubState::kFlyForward);
  s = wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft);
  s.d_left = 0.05;
  rule.apply(s);
  EXPECT_EQ(s.sub_state, WallSubState::kFlyBackward);
  // Outside it: within the limit, a turn back toward the course, no turn, not
  // wall following, no course yet, the rule off.
  EXPECT_FALSE(rule.applies(wall_snapshot(40.0 * kDeg, WallSubState::kTurnLeft)));
  EXPECT_FALSE(rule.applies(wall_snapshot(50.0 * kDeg, WallSubState::kTurnRight)));
  EXPECT_FALSE(rule.applies(wall_snapshot(50.0 * kDeg, WallSubState::kFlySideways)));
  s = wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft);
  s.state = FsmState::kResumeForward;
  EXPECT_FALSE(rule.applies(s));
  s = wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft);
  s.origin_set = false;
  EXPECT_FALSE(rule.applies(s));
  WallFollowerParams off = p;
  off.max_heading_offset = 0.0;
  EXPECT_FALSE(HeadingLimitRule(off).applies(wall_snapshot(50.0 * kDeg, WallSubState::kTurnLeft)));
}

// The anchor is the wall heading first read (observe); a turn asked for by a
// small angle that goes more than 10 deg beyond it is refused, one within 10
// deg or asked for by a clear angle (>= 10 deg) is not; readings in a turn do
// not move the anchor; outside wall following it is dropped.
TEST(OverrideRules, TurnAnchorFiresOnASmallAngleTurnBeyondTheAnchorOnly) {
  const WallFollowerParams p;  // 10 deg, 10 deg, 2 deg/s
  TurnAnchorRule rule(p);
  TickSnapshot first = wall_snapshot(0.0, WallSubState::kFlySideways);
  rule.observe(first);
  EXPECT_DOUBLE_EQ(rule.anchor(), 0.0);
  // 15 deg left of the anchor, theta 3 deg (the tips dragged round): refused.
  TickSnapshot s = wall_snapshot(15.0 * kDeg, WallSubState::kTurnLeft);
  s.current = WallSubState::kTurnLeft;
  s.theta = -3.0 * kDeg;
  s.wall_heading = 18.0 * kDeg;
  rule.observe(s);
  EXPECT_DOUBLE_EQ(rule.anchor(), 0.0);  // read in a turn: not moved
  ASSERT_TRUE(rule.applies(s));
  rule.apply(s);
  EXPECT_EQ(s.sub_state, WallSubState::kFlySideways);
  // Within the tolerance, or a clear angle: the turn goes on.
  TickSnapshot near = wall_snapshot(8.0 * kDeg, WallSubState::kTurnLeft);
  near.theta = -3.0 * kDeg;
  EXPECT_FALSE(rule.applies(near));
  TickSnapshot clear = wall_snapshot(15.0 * kDeg, WallSubState::kTurnLeft);
  clear.theta = -12.0 * kDeg;
  EXPECT_FALSE(rule.applies(clear));
  // One depth missing: no wall heading, the rule does not act.
  TickSnapshot one = wall_snapshot(15.0 * kDeg, WallSubState::kTurnLeft);
  one.theta = -3.0 * kDeg;
  one.r_valid = false;
  EXPECT_FALSE(rule.applies(one));
  // Out of wall following the anchor is dropped; the next one reads its own.
  TickSnapshot out = wall_snapshot(0.0, WallSubState::kNone);
  out.state = FsmState::kResumeForward;
  rule.observe(out);
  EXPECT_TRUE(std::isnan(rule.anchor()));
  EXPECT_FALSE(rule.applies(out));
  WallFollowerParams off = p;
  off.turn_anchor_tolerance = 0.0;
  TurnAnchorRule none(off);
  none.observe(first);
  EXPECT_TRUE(std::isnan(none.anchor()));
  EXPECT_FALSE(none.applies(s));
}

// Before the flight's first contact the step flies toward its end on the
// course heading, then scans; after a contact, after a clearing, out of
// FLY_FORWARD, without a position or with the amplitude 0 it does not act.
TEST(OverrideRules, StepAndScanFiresOnTheFirstApproachOnly) {
  const WallFollowerParams p;  // 0.44 rad, 0.08 m steps, 2 rad/s
  StepAndScanRule rule(p);
  TickSnapshot s = forward_snapshot(0.0, false, false);
  ASSERT_TRUE(rule.applies(s));
  rule.apply(s);
  EXPECT_NEAR(s.setpoint.vx, p.v_max, 1e-12);  // (0.08 - 0) / 0.3 s, capped at V_max
  EXPECT_NEAR(s.setpoint.vy, 0.0, 1e-12);
  EXPECT_NEAR(s.setpoint.yaw_rate, 0.0, 1e-12);  // on the course while stepping
  EXPECT_FALSE(rule.scanning());
  TickSnapshot end = forward_snapshot(0.07, false, false);  // 10 mm before the step's end
  rule.apply(end);
  EXPECT_TRUE(rule.scanning());
  EXPECT_GT(end.setpoint.yaw_rate, 1.0);  // the scan turns toward +A
  EXPECT_LE(end.setpoint.yaw_rate, p.whisk_rate_max);
  EXPECT_FALSE(rule.applies(forward_snapshot(0.0, false, true)));  // contacted
  EXPECT_FALSE(rule.applies(forward_snapshot(0.0, true, false)));  // after a clearing
  TickSnapshot resume = forward_snapshot(0.0, false, false);
  resume.state = FsmState::kResumeForward;
  EXPECT_FALSE(rule.applies(resume));
  TickSnapshot lost = forward_snapshot(0.0, false, false);
  lost.in.x = NAN;
  EXPECT_FALSE(rule.applies(lost));
  WallFollowerParams off = p;
  off.first_whisk_amplitude = 0.0;
  EXPECT_FALSE(StepAndScanRule(off).applies(forward_snapshot(0.0, false, false)));
  // A tick it does not apply ends the scan: the next first approach steps afresh.
  rule.idle();
  TickSnapshot again = forward_snapshot(0.07, false, false);
  rule.apply(again);
  EXPECT_FALSE(rule.scanning());
}

// In the FLY_FORWARD after a clearing (side-step to the right) the body yaw
// turns left toward the offset while the track stays along the course; a
// moving sum releases it; before a clearing, in the side-step or with the
// offset 0 it does not act.
TEST(OverrideRules, YawOffsetFiresAfterAClearingOnly) {
  const WallFollowerParams p;  // 0.2443 rad, released at 13 Pa
  YawOffsetRule rule(p);
  TickSnapshot s = forward_snapshot(1.0, true, true);
  s.side = Side::kRight;
  ASSERT_TRUE(rule.applies(s));
  rule.apply(s);
  EXPECT_GT(s.setpoint.yaw_rate, 0.0);             // toward the left, away from the side-step
  EXPECT_NEAR(s.setpoint.vx, 0.2, 1e-12);          // track heading = yaw here: velocity unchanged
  TickSnapshot yawed = forward_snapshot(1.0, true, true);  // body already at the offset
  yawed.in.yaw = p.clear_yaw_offset;
  rule.apply(yawed);
  EXPECT_NEAR(std::cos(p.clear_yaw_offset) * yawed.setpoint.vx - std::sin(p.clear_yaw_offset) * yawed.setpoint.vy,
              0.2, 1e-3);  // world velocity still along the course
  TickSnapshot touch = forward_snapshot(1.0, true, true);
  touch.in.yaw = p.clear_yaw_offset;
  touch.in.input_change_rms_left = 20.0;
  rule.apply(touch);
  EXPECT_TRUE(rule.released());
  EXPECT_LT(touch.setpoint.yaw_rate, 0.0);  // back toward the track's heading
  EXPECT_FALSE(rule.applies(forward_snapshot(1.0, false, true)));  // no clearing before
  TickSnapshot side_step = forward_snapshot(1.0, true, true);
  side_step.state = FsmState::kResumeForward;
  EXPECT_FALSE(rule.applies(side_step));
  WallFollowerParams off = p;
  off.clear_yaw_offset = 0.0;
  EXPECT_FALSE(YawOffsetRule(off).applies(forward_snapshot(1.0, true, true)));
  rule.idle();
  EXPECT_FALSE(rule.released());
}

// The follower counts the ticks each rule fired and names a rule in reason()
// when it begins: the step and scan from the first FLY_FORWARD tick (with the
// transition's reason), ending at the first contact; the heading limit when it
// turns the Fig. S4e rule's turn into a translation.
TEST(OverrideRules, FollowerCountsEachRuleAndNamesItInTheReason) {
  WhiskerWallFollower fsm{WallFollowerParams{}};
  double t = 0.0;
  for (; t < 2.0 - 1e-9; t += kDt) fsm.step(input(t));
  WallFollowerOutput o = fsm.step(input(t));
  t += kDt;
  EXPECT_EQ(o.state, FsmState::kFlyForward);
  EXPECT_TRUE(o.override_started);
  EXPECT_STREQ(fsm.reason(), (std::string("hover initialisation done; ") + StepAndScanRule::kReason).c_str());
  for (int k = 0; k < 9; ++k, t += kDt) EXPECT_FALSE(fsm.step(input(t)).override_started);
  EXPECT_EQ(fsm.override_count(OverrideRule::kStepAndScan), 10u);
  EXPECT_EQ(fsm.override_count(OverrideRule::kHeadingLimit), 0u);
  // A contact at 50 deg left of the course, the depths asking for a left turn.
  WallFollowerInput in = input(t, 0.0, 0.0, 50.0 * kDeg);
  set_depths(in, 0.07, 0.09);
  o = fsm.step(in);
  t += kDt;
  EXPECT_EQ(o.state, FsmState::kWallFollowing);
  EXPECT_EQ(o.sub_state, WallSubState::kFlySideways);  // not TURN_LEFT
  EXPECT_TRUE(o.override_started);
  EXPECT_STREQ(fsm.reason(), (std::string("whisker contact; ") + HeadingLimitRule::kReason).c_str());
  EXPECT_EQ(fsm.override_count(OverrideRule::kStepAndScan), 10u);  // ended at the contact
  EXPECT_EQ(fsm.override_count(OverrideRule::kHeadingLimit), 1u);
  in = input(t, 0.0, 0.0, 50.0 * kDeg);
  set_depths(in, 0.07, 0.09);
  o = fsm.step(in);
  EXPECT_FALSE(o.override_started);  // still firing, not begun
  EXPECT_EQ(fsm.override_count(OverrideRule::kHeadingLimit), 2u);
  fsm.reset();
  EXPECT_EQ(fsm.override_count(OverrideRule::kHeadingLimit), 0u);
}
