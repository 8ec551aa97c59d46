// The whisker wall follower's parts one by one (issue 33): the per-side
// Whisker, the named guards on hand-made snapshots (true at the edge, false
// just outside), the transition tables, each transition from a state the
// follower is put in directly, the reason codes, and the shared fail-safe.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_fsm/whisker_wall_follower.hpp"
#include "wall_follower_input.hpp"

using tactile_fsm::FsmState;
using tactile_fsm::SafetyReason;
using tactile_fsm::Side;
using tactile_fsm::TickSnapshot;
using tactile_fsm::transition_table;
using tactile_fsm::WallFollowerInput;
using tactile_fsm::WallFollowerParams;
using tactile_fsm::WallSubState;
using tactile_fsm::Whisker;
using tactile_fsm::WhiskerReading;
using tactile_fsm::WhiskerReason;
using tactile_fsm::WhiskerSample;
using tactile_fsm::WhiskerWallFollower;
namespace guards = tactile_fsm::guards;

namespace {

constexpr double kDt = 0.02;   // 50 Hz
constexpr double kEdge = 1e-6;  // "just outside" an edge [s] or [m]

uint8_t code(WhiskerReason r) { return static_cast<uint8_t>(r); }
uint8_t code(SafetyReason r) { return static_cast<uint8_t>(r); }

WhiskerSample touching(double depth, double sum = 100.0, double rms = 20.0) {
  WhiskerSample s;
  s.depth_fresh = true;
  s.valid = true;
  s.depth = depth;
  s.tdorc_contact = true;
  s.input_sum = sum;
  s.input_change_rms = rms;
  return s;
}

WhiskerSample free_whisker() {
  WhiskerSample s;
  s.depth_fresh = true;
  s.input_sum = 0.0;
  s.input_change_rms = 1.0;
  return s;
}

using tactile_fsm::test::input;

WhiskerReading contact_reading(double depth) {
  WhiskerReading r;
  r.held_raw = r.valid = r.contact = true;
  r.depth = r.filtered = r.rule_depth = depth;
  return r;
}

}  // namespace

// --- Whisker ------------------------------------------------------------------

TEST(Whisker, ValidNeedsAFreshFlaggedFiniteDepth) {
  WallFollowerParams p;
  Whisker w(p);
  EXPECT_TRUE(w.update(touching(0.08), 0.0, kDt, true, 0.0, 0.0).valid);
  WhiskerSample stale = touching(0.08);
  stale.depth_fresh = false;
  const WhiskerReading r = w.update(stale, kDt, kDt, true, 0.0, 0.0);
  EXPECT_FALSE(r.valid);
  EXPECT_TRUE(r.contact);  // the TDORC flag alone still counts
  EXPECT_TRUE(r.held_raw);
  EXPECT_TRUE(std::isnan(r.depth));
  WhiskerSample nan_depth = touching(NAN);
  EXPECT_FALSE(w.update(nan_depth, 2 * kDt, kDt, true, 0.0, 0.0).valid);
}

// A held contact whose sum stays quiet while the drone moves more than
// phantom_travel is a phantom; latched until the sum moves at twice the quiet level.
TEST(Whisker, PhantomGateLatchesUntilTheSumMovesClearly) {
  WallFollowerParams p;  // phantom_quiet_rms 6.5 Pa, phantom_travel 0.03 m, latch on
  Whisker w(p);
  double t = 0.0;
  // Moving sum: live wherever the drone is.
  EXPECT_FALSE(w.update(touching(0.08, 100.0, 20.0), t, kDt, true, 0.0, 0.0).phantom);
  // Quiet from here on: 0.03 m of travel is not yet a phantom, just beyond is.
  t += kDt;
  EXPECT_FALSE(w.update(touching(0.08, 100.0, 1.0), t, kDt, true, p.phantom_travel, 0.0).phantom);
  t += kDt;
  WhiskerReading r = w.update(touching(0.08, 100.0, 1.0), t, kDt, true, p.phantom_travel + 0.001, 0.0);
  EXPECT_TRUE(r.phantom);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.contact);
  EXPECT_TRUE(r.held_raw);
  EXPECT_TRUE(std::isnan(r.filtered));
  // Latched: an RMS above the quiet level but below twice it keeps it a phantom.
  t += kDt;
  EXPECT_TRUE(w.update(touching(0.08, 100.0, 1.5 * p.phantom_quiet_rms), t, kDt, true, 0.1, 0.0).phantom);
  t += kDt;
  r = w.update(touching(0.08, 100.0, 2.0 * p.phantom_quiet_rms), t, kDt, true, 0.1, 0.0);
  EXPECT_FALSE(r.phantom);
  EXPECT_TRUE(r.valid);
  // The latch off: the same RMS frees it at once.
  WallFollowerParams q = p;
  q.phantom_latch = false;
  Whisker u(q);
  u.update(touching(0.08, 100.0, 20.0), 0.0, kDt, true, 0.0, 0.0);
  EXPECT_TRUE(u.update(touching(0.08, 100.0, 1.0), kDt, kDt, true, 0.05, 0.0).phantom);
  EXPECT_FALSE(u.update(touching(0.08, 100.0, 1.5 * q.phantom_quiet_rms), 2 * kDt, kDt, true, 0.1, 0.0).phantom);
  // No fresh pose: no phantom.
  EXPECT_FALSE(w.update(touching(0.08, 100.0, 1.0), 1.0, kDt, false, 5.0, 0.0).phantom);
}

TEST(Whisker, FilterRestartsWhenTheWhiskerLosesTheWall) {
  WallFollowerParams p;  // depth_filter_tau_s 0.08 s
  Whisker w(p);
  EXPECT_DOUBLE_EQ(w.update(touching(0.08), 0.0, 0.0, true, 0.0, 0.0).filtered, 0.08);
  const double a = kDt / (p.depth_filter_tau_s + kDt);
  EXPECT_DOUBLE_EQ(w.update(touching(0.10), kDt, kDt, true, 0.0, 0.0).filtered, 0.08 + a * 0.02);
  EXPECT_TRUE(std::isnan(w.update(free_whisker(), 2 * kDt, kDt, true, 0.0, 0.0).filtered));
  // Back on the wall: starts at the reading, not from the old value.
  EXPECT_DOUBLE_EQ(w.update(touching(0.06), 3 * kDt, kDt, true, 0.0, 0.0).filtered, 0.06);
}

TEST(Whisker, PressedDepthCappedAtPressDepth) {
  WallFollowerParams p;  // press_sum_pa 900 Pa, press_depth 0.05 m, no hold
  Whisker w(p);
  WhiskerReading r = w.update(touching(0.07, p.press_sum_pa), 0.0, 0.0, true, 0.0, 0.0);
  EXPECT_TRUE(r.pressed);
  EXPECT_DOUBLE_EQ(r.filtered, 0.07);
  EXPECT_DOUBLE_EQ(r.rule_depth, p.press_depth);
  r = w.update(touching(0.07, p.press_sum_pa - 1.0), kDt, kDt, true, 0.0, 0.0);
  EXPECT_FALSE(r.pressed);
  EXPECT_DOUBLE_EQ(r.rule_depth, r.filtered);
  // A depth already below press_depth stays.
  Whisker near(p);
  r = near.update(touching(0.03, 2000.0), 0.0, 0.0, true, 0.0, 0.0);
  EXPECT_TRUE(r.pressed);
  EXPECT_DOUBLE_EQ(r.rule_depth, 0.03);
  // Off: never pressed.
  WallFollowerParams off = p;
  off.press_sum_pa = 0.0;
  Whisker u(off);
  EXPECT_FALSE(u.update(touching(0.07, 5000.0), 0.0, 0.0, true, 0.0, 0.0).pressed);
}

// --- Guards ---------------------------------------------------------------------

// The wall following both behaviours run (whisker FSM WALL_FOLLOWING, GPIS
// FOLLOW_WALL): an episode's side and both-touched memory, the rule on them, and
// the sub-state's motion (000 Fig. S4e: sideways V_max, forward / backward
// V_max / 2, turns omega_max).
TEST(WallFollowing, EpisodeMemoryRuleAndMotion) {
  const WallFollowerParams p;
  tactile_fsm::WallFollowing w;
  w.begin(Side::kLeft);
  EXPECT_EQ(w.side(), Side::kLeft);
  EXPECT_FALSE(w.both_touched());
  EXPECT_EQ(w.sub_state(), WallSubState::kNone);
  // Right whisker only, at 0.08 m, before both touched: the approach rule (the
  // missing left depth beyond T_max) turns toward the wall.
  EXPECT_EQ(w.rule(NAN, false, 0.08, true, p), WallSubState::kTurnRight);
  w.touched(true, false);
  EXPECT_FALSE(w.both_touched());
  w.touched(true, true);
  EXPECT_TRUE(w.both_touched());
  // After both touched the leading (left, sliding left) whisker lost: passing the
  // edge, sideways -- the memory changed the rule's answer.
  EXPECT_EQ(w.rule(NAN, false, 0.08, true, p), WallSubState::kFlySideways);
  // The rule does not change the episode; set_sub_state() does.
  EXPECT_EQ(w.sub_state(), WallSubState::kNone);
  w.set_sub_state(WallSubState::kTurnLeft);
  EXPECT_EQ(w.sub_state(), WallSubState::kTurnLeft);
  // A new episode forgets both; begin(side, true) starts as an edge being passed.
  w.begin(Side::kRight);
  EXPECT_FALSE(w.both_touched());
  EXPECT_EQ(w.sub_state(), WallSubState::kNone);
  w.begin(Side::kRight, true);
  EXPECT_TRUE(w.both_touched());

  const struct {
    Side side;
    WallSubState sub;
    double vx, vy, yaw_rate;
  } motions[] = {
      {Side::kLeft, WallSubState::kFlySideways, 0.0, p.v_max, 0.0},
      {Side::kRight, WallSubState::kFlySideways, 0.0, -p.v_max, 0.0},
      {Side::kRight, WallSubState::kFlyForward, 0.5 * p.v_max, 0.0, 0.0},
      {Side::kRight, WallSubState::kFlyBackward, -0.5 * p.v_max, 0.0, 0.0},
      {Side::kRight, WallSubState::kTurnLeft, 0.0, 0.0, p.omega_max},
      {Side::kLeft, WallSubState::kTurnRight, 0.0, 0.0, -p.omega_max},
      {Side::kLeft, WallSubState::kNone, 0.0, 0.0, 0.0},
  };
  for (const auto& m : motions) {
    SCOPED_TRACE(tactile_fsm::to_string(m.sub));
    w.begin(m.side);
    w.set_sub_state(m.sub);
    tactile_fsm::Setpoint sp;
    sp.height = 0.4;
    w.motion(p, &sp);
    EXPECT_DOUBLE_EQ(sp.vx, m.vx);
    EXPECT_DOUBLE_EQ(sp.vy, m.vy);
    EXPECT_DOUBLE_EQ(sp.yaw_rate, m.yaw_rate);
    EXPECT_DOUBLE_EQ(sp.height, 0.4);  // only the motion's field is set
  }
}

TEST(Guards, HoverDoneAndLandingDoneAtTheirDuration) {
  WallFollowerParams p;
  TickSnapshot s;
  s.entered = 1.0;
  s.in.t = 1.0 + p.hover_init_s;
  EXPECT_TRUE(guards::hover_done(s, p));
  s.in.t = 1.0 + p.hover_init_s - kEdge;
  EXPECT_FALSE(guards::hover_done(s, p));
  s.in.t = 1.0 + p.landing_duration_s;
  EXPECT_TRUE(guards::landing_done(s, p));
  s.in.t = 1.0 + p.landing_duration_s - kEdge;
  EXPECT_FALSE(guards::landing_done(s, p));
}

TEST(Guards, ContactIsEitherWhiskerAfterThePhantomGate) {
  WallFollowerParams p;
  TickSnapshot s;
  EXPECT_FALSE(guards::contact(s, p));
  EXPECT_FALSE(guards::contact_while_clearing(s, p));
  s.right.contact = true;
  EXPECT_TRUE(guards::contact(s, p));
  EXPECT_TRUE(guards::contact_while_clearing(s, p));
  s.right = WhiskerReading{};
  s.left.held_raw = s.left.phantom = true;  // held, but a phantom
  EXPECT_FALSE(guards::contact(s, p));
}

TEST(Guards, ContactSameObstacleWithinTheDistanceAlongTheCourse) {
  WallFollowerParams p;  // same_obstacle_distance 0.15 m
  TickSnapshot s;
  s.left.contact = true;
  s.after_clear = true;
  s.resume_x = 0.0;
  s.in.x = p.same_obstacle_distance - kEdge;
  s.in.y = 0.3;  // sideways does not count
  EXPECT_TRUE(guards::contact_same_obstacle(s, p));
  s.in.x = p.same_obstacle_distance;
  EXPECT_FALSE(guards::contact_same_obstacle(s, p));
  s.in.x = 0.0;
  s.after_clear = false;
  EXPECT_FALSE(guards::contact_same_obstacle(s, p));
  s.after_clear = true;
  s.left.contact = false;
  EXPECT_FALSE(guards::contact_same_obstacle(s, p));
}

TEST(Guards, ContactAtBaffleEndBeyondTheLateralLimit) {
  WallFollowerParams p;  // end_contact_lateral 45 mm, whisker_base_x 0.05 m, spacing 0.05 m
  TickSnapshot s;
  s.origin_set = true;
  s.course_yaw = 0.0;
  s.left = contact_reading(0.10);
  // Yawed left by `a`: the left tip lies sin(a) (base_x + d) + cos(a) s/2 beside the axis.
  const auto lateral = [&](double a) {
    return std::sin(a) * (p.whisker_base_x + 0.10) + std::cos(a) * 0.5 * p.whisker_spacing;
  };
  // Bisect the yaw at which the offset is end_contact_lateral.
  double lo = 0.0, hi = 0.5;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (lateral(mid) > p.end_contact_lateral ? hi : lo) = mid;
  }
  s.in.yaw = hi + 1e-9;
  EXPECT_NEAR(guards::end_contact_offset(s, p), lateral(s.in.yaw), 1e-12);
  EXPECT_TRUE(guards::contact_at_baffle_end(s, p));
  s.in.yaw = lo - 1e-6;
  EXPECT_FALSE(guards::contact_at_baffle_end(s, p));
  // Both whiskers, or the depth not valid (a TDORC flag alone): no end.
  s.in.yaw = 0.4;
  EXPECT_TRUE(guards::contact_at_baffle_end(s, p));
  s.right = contact_reading(0.10);
  EXPECT_FALSE(guards::contact_at_baffle_end(s, p));
  s.right = WhiskerReading{};
  s.left.valid = false;
  EXPECT_FALSE(guards::contact_at_baffle_end(s, p));
  // Off.
  s.left = contact_reading(0.10);
  WallFollowerParams off = p;
  off.end_contact_lateral = 0.0;
  EXPECT_FALSE(guards::contact_at_baffle_end(s, off));
}

TEST(Guards, ClearedByMarginWaitsForAHeldPhantomUpToTheResumeMax) {
  WallFollowerParams p;  // clear_margin 0.30 m, phantom_resume_max 2 m
  TickSnapshot s;
  s.clear_x = 0.0;
  s.in.y = p.clear_margin;
  EXPECT_TRUE(guards::cleared_by_margin(s, p));
  s.in.y = p.clear_margin - kEdge;
  EXPECT_FALSE(guards::cleared_by_margin(s, p));
  // A whisker still held as a phantom: on until phantom_resume_max.
  s.left.held_raw = true;
  s.in.y = p.phantom_resume_max - kEdge;
  EXPECT_FALSE(guards::cleared_by_margin(s, p));
  s.in.y = p.phantom_resume_max;
  EXPECT_TRUE(guards::cleared_by_margin(s, p));
}

TEST(Guards, ObstacleClearedAfterClearConfirm) {
  WallFollowerParams p;  // clear_confirm_s 0.2 s
  TickSnapshot s;
  s.last_contact_t = 3.0;
  s.in.t = 3.0 + p.clear_confirm_s;
  EXPECT_TRUE(guards::obstacle_cleared(s, p));
  s.in.t = 3.0 + p.clear_confirm_s - kEdge;
  EXPECT_FALSE(guards::obstacle_cleared(s, p));
  s.in.t = 10.0;
  s.right.contact = true;
  EXPECT_FALSE(guards::obstacle_cleared(s, p));
}

TEST(Guards, TargetReachedWithinTheRadiusOrPastIt) {
  WallFollowerParams p;  // target_radius 0.15 m, land_past_target
  TickSnapshot s;
  s.in.has_target = true;
  s.in.target_x = 2.0;
  s.in.target_y = 0.0;
  s.in.x = 2.0 - p.target_radius;
  s.in.y = 0.0;
  EXPECT_TRUE(guards::target_reached(s, p));
  s.in.x = 2.0 - p.target_radius - kEdge;
  EXPECT_FALSE(guards::target_reached(s, p));
  // Past it along the course (origin -> target), far beside it.
  s.in.x = 2.0;
  s.in.y = 1.0;
  EXPECT_TRUE(guards::target_reached(s, p));
  s.in.x = 2.0 - kEdge;
  EXPECT_FALSE(guards::target_reached(s, p));
  WallFollowerParams strict = p;
  strict.land_past_target = false;
  s.in.x = 2.5;
  EXPECT_FALSE(guards::target_reached(s, strict));
  s.in.has_target = false;
  s.in.x = 2.0;
  s.in.y = 0.0;
  EXPECT_FALSE(guards::target_reached(s, p));
}

// --- Tables -------------------------------------------------------------------------

TEST(TransitionTables, RowsInTheirOrder) {
  auto names = [](FsmState st) {
    std::vector<std::string> v;
    for (const auto& row : transition_table(st)) v.push_back(row.guard_name);
    return v;
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(names(FsmState::kHoverInit), V({"hover_done"}));
  EXPECT_EQ(names(FsmState::kFlyForward),
            V({"target_reached", "contact_same_obstacle", "contact_at_baffle_end", "contact"}));
  EXPECT_EQ(names(FsmState::kWallFollowing), V({"target_reached", "obstacle_cleared"}));
  EXPECT_EQ(names(FsmState::kResumeForward), V({"target_reached", "contact_while_clearing", "cleared_by_margin"}));
  EXPECT_EQ(names(FsmState::kLanding), V({"landing_done"}));
  EXPECT_EQ(transition_table(FsmState::kLanded).size, 0u);
  EXPECT_EQ(transition_table(FsmState::kFailsafeHover).size, 0u);  // the SafetyRunner's
  EXPECT_EQ(transition_table(FsmState::kFailsafeLand).size, 0u);
  // Each code is the guard's, named as it (to_string), and unique per (state, row).
  for (FsmState st : {FsmState::kHoverInit, FsmState::kFlyForward, FsmState::kWallFollowing,
                      FsmState::kResumeForward, FsmState::kLanding}) {
    std::set<uint8_t> codes;
    for (const auto& row : transition_table(st)) {
      EXPECT_STREQ(tactile_fsm::to_string(row.code), row.guard_name);
      EXPECT_TRUE(codes.insert(code(row.code)).second);
      EXPECT_GE(code(row.code), 30);
      EXPECT_LE(code(row.code), 49);
    }
  }
}

// --- Transitions from a state the follower is put in --------------------------------

namespace {

WallFollowerParams quiet_params() {
  WallFollowerParams p;
  p.first_whisk_amplitude = 0.0;  // no step and scan: the plain setpoints
  p.clear_yaw_offset = 0.0;
  return p;
}

}  // namespace

TEST(Transitions, HoverInitToFlyForwardSetsTheCourse) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.step(input(0.0));
  fsm.step(input(2.0 - kDt, 0.1, 0.2, 0.3));
  EXPECT_EQ(fsm.state(), FsmState::kHoverInit);
  EXPECT_EQ(fsm.step(input(2.0, 0.1, 0.2, 0.3)).state, FsmState::kFlyForward);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kHoverDone));
  // The course heading is the yaw there: the realignment holds it.
  EXPECT_NEAR(fsm.step(input(2.0 + kDt, 0.1, 0.2, 0.3)).setpoint.yaw_rate, 0.0, 1e-12);
}

TEST(Transitions, FlyForwardContactChoosesTheSideTowardTheTarget) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kFlyForward, input(5.0));
  WallFollowerInput in = input(5.0 + kDt);
  in.target_y = 1.0;  // to the left
  in.tdorc_contact_right = true;
  EXPECT_EQ(fsm.step(in).state, FsmState::kWallFollowing);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kContact));
  EXPECT_EQ(fsm.active_side(), Side::kLeft);
}

TEST(Transitions, FlyForwardContactAtABaffleEndPassesItOnTheOtherSide) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kFlyForward, input(5.0));
  // The left whisker alone, yawed 0.4 rad left: its tip ~85 mm left of the axis.
  WallFollowerInput in = input(5.0 + kDt, 0.0, 0.0, 0.4);
  in.left_valid = true;
  in.depth_left = 0.10;
  in.target_y = 1.0;  // the target's side (left) would be chosen otherwise
  EXPECT_EQ(fsm.step(in).state, FsmState::kWallFollowing);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kContactBaffleEnd));
  EXPECT_EQ(fsm.active_side(), Side::kRight);
}

TEST(Transitions, ResumeForwardThenFlyForwardThenSameObstacleKeepsTheSide) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kResumeForward, input(5.0, 1.0, 0.0));
  // Side-stepping: not yet clear_margin from the clearing.
  WallFollowerInput in = input(5.0 + kDt, 1.0, -0.29);
  EXPECT_EQ(fsm.step(in).state, FsmState::kResumeForward);
  in = input(5.0 + 2 * kDt, 1.0, -0.30);
  EXPECT_EQ(fsm.step(in).state, FsmState::kFlyForward);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kClearedByMargin));
  // A contact 0.1 m on, the target now to the left: the same obstacle, side kept (right).
  in = input(5.0 + 3 * kDt, 1.1, -0.30);
  in.target_y = 1.0;
  in.tdorc_contact_left = true;
  EXPECT_EQ(fsm.step(in).state, FsmState::kWallFollowing);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kContactSameObstacle));
  EXPECT_EQ(fsm.active_side(), Side::kRight);
}

TEST(Transitions, ResumeForwardContactIsTheSameObstaclesEnd) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kResumeForward, input(5.0, 1.0, 0.0));
  WallFollowerInput in = input(5.0 + kDt, 1.0, -0.1);
  in.tdorc_contact_right = true;
  EXPECT_EQ(fsm.step(in).state, FsmState::kWallFollowing);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kContactWhileClearing));
}

TEST(Transitions, WallFollowingClearedAfterClearConfirm) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kWallFollowing, input(5.0, 1.0, 0.0));
  double t = 5.0;
  // 0.2 s without contact (the entry counts as the last contact).
  for (int k = 0; k < 9; ++k) {
    t += kDt;
    ASSERT_EQ(fsm.step(input(t, 1.0, 0.0)).state, FsmState::kWallFollowing) << k;
  }
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kSubStateRule));  // NONE -> FLY_SIDEWAYS
  t += kDt;
  EXPECT_EQ(fsm.step(input(t, 1.0, 0.0)).state, FsmState::kResumeForward);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kObstacleCleared));
}

TEST(Transitions, TargetReachedFromEachFlyingStateThenLanded) {
  for (FsmState st : {FsmState::kFlyForward, FsmState::kWallFollowing, FsmState::kResumeForward}) {
    WhiskerWallFollower fsm{quiet_params()};
    fsm.for_test_enter(st, input(5.0));
    EXPECT_EQ(fsm.step(input(5.0 + kDt, 1.9, 0.0)).state, FsmState::kLanding) << tactile_fsm::to_string(st);
    EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kTargetReached));
    const double landed = 5.0 + kDt + fsm.params().landing_duration_s;
    EXPECT_EQ(fsm.step(input(landed - kDt)).state, FsmState::kLanding);
    EXPECT_EQ(fsm.step(input(landed)).state, FsmState::kLanded);
    EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kLandingDone));
  }
}

TEST(Transitions, FailsafeStatesAreTheSafetyRunners) {
  WhiskerWallFollower fsm{quiet_params()};
  EXPECT_THROW(fsm.for_test_enter(FsmState::kFailsafeHover, input(0.0)), std::invalid_argument);
  EXPECT_THROW(fsm.for_test_enter(FsmState::kFailsafeLand, input(0.0)), std::invalid_argument);
}

// --- The shared fail-safe -------------------------------------------------------------

// The stale-input transitions carry the SafetyRunner's codes; the runner's
// state follows the follower's.
TEST(Failsafe, StaleInputsCarryTheSafetyRunnersCodes) {
  WhiskerWallFollower fsm{quiet_params()};
  fsm.for_test_enter(FsmState::kWallFollowing, input(5.0));
  WallFollowerInput in = input(5.0 + kDt);
  in.depth_stamp = 5.0 + kDt - fsm.params().max_input_age_s;  // at the limit: fresh
  in.tdorc_contact_left = true;
  EXPECT_EQ(fsm.step(in).state, FsmState::kWallFollowing);
  in.t += kDt;
  in.odom_stamp = in.t;
  in.depth_stamp = in.t - fsm.params().max_input_age_s - kEdge;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  EXPECT_EQ(fsm.reason_code(), code(SafetyReason::kDepthStale));
  EXPECT_EQ(fsm.safety().state(), tactile_fsm::SafetyState::kFailsafeHover);
  EXPECT_EQ(fsm.step(input(in.t + kDt)).state, FsmState::kFlyForward);
  EXPECT_EQ(fsm.reason_code(), code(SafetyReason::kInputsFresh));
  // Odometry stale; then stale for failsafe_land_after_s: FAILSAFE_LAND.
  in = input(6.0);
  in.odom_stamp = 5.0;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  EXPECT_EQ(fsm.reason_code(), code(SafetyReason::kOdometryStale));
  in.t = 6.0 + fsm.params().failsafe_land_after_s - kDt;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeHover);
  in.t = 6.0 + fsm.params().failsafe_land_after_s;
  EXPECT_EQ(fsm.step(in).state, FsmState::kFailsafeLand);
  EXPECT_EQ(fsm.reason_code(), code(SafetyReason::kStaleTooLong));
  EXPECT_EQ(fsm.step(input(9.0)).state, FsmState::kFailsafeLand);  // terminal
}

TEST(Failsafe, NotGuardedWhileHoveringOrLanding) {
  WhiskerWallFollower fsm{quiet_params()};
  WallFollowerInput never;  // nothing received
  for (int k = 0; k < 99; ++k) {
    never.t = k * kDt;
    ASSERT_EQ(fsm.step(never).state, FsmState::kHoverInit);
  }
  WhiskerWallFollower landing{quiet_params()};
  landing.for_test_enter(FsmState::kLanding, input(5.0));
  never.t = 5.0 + kDt;
  EXPECT_EQ(landing.step(never).state, FsmState::kLanding);
  never.t = 7.0;
  EXPECT_EQ(landing.step(never).state, FsmState::kLanded);
}

// --- Reason codes of the rules ----------------------------------------------------------

TEST(ReasonCodes, OverrideRuleOnsetAndSubStateChanges) {
  WallFollowerParams p;  // the shipped rules
  WhiskerWallFollower fsm{p};
  double t = 0.0;
  for (; t < 2.0 - 1e-9; t += kDt) fsm.step(input(t));
  // The step and scan begins on the transition's tick: the transition's code stays.
  fsm.step(input(t));
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kHoverDone));
  // Wall following at 50 deg off the course, the depths asking for a left turn:
  // the heading limit's code once the contact is behind.
  t += kDt;
  WallFollowerInput in = input(t, 0.0, 0.0, 50.0 * M_PI / 180.0);
  in.left_valid = in.right_valid = true;
  in.depth_left = 0.07;
  in.depth_right = 0.09;
  fsm.step(in);
  EXPECT_EQ(fsm.reason_code(), code(WhiskerReason::kContact));
  WhiskerWallFollower fresh{p};
  fresh.for_test_enter(FsmState::kWallFollowing, input(5.0));
  in = input(5.0 + kDt, 0.0, 0.0, 50.0 * M_PI / 180.0);
  in.left_valid = in.right_valid = true;
  in.depth_left = 0.07;
  in.depth_right = 0.09;
  fresh.step(in);
  EXPECT_EQ(fresh.sub_state(), WallSubState::kFlySideways);
  EXPECT_EQ(fresh.reason_code(), code(WhiskerReason::kHeadingLimit));
}
