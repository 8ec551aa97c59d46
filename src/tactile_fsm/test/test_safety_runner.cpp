// SafetyRunner: each guard alone, then each transition from a state the test
// puts the runner into, at the tick it must fire and the tick before.
#include "tactile_fsm/safety_runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

using tactile_fsm::SafetyInput;
using tactile_fsm::SafetyParams;
using tactile_fsm::SafetyReason;
using tactile_fsm::SafetyRunner;
using tactile_fsm::SafetyState;

namespace {

SafetyParams params(double age = 0.2, double land_after = 2.0) {
  SafetyParams p;
  p.max_input_age_s = age;
  p.failsafe_land_after_s = land_after;
  return p;
}

// Depth and odometry, both fresh at t (stamped 10 ms before).
SafetyRunner depth_and_odometry(const SafetyParams& p = params()) {
  return SafetyRunner(p, {SafetyInput::kDepth, SafetyInput::kOdometry});
}

// Into FAILSAFE_HOVER at t with the depth stale (stamped at `depth_stamp`).
SafetyRunner held_at(double t, double depth_stamp = 0.0, const SafetyParams& p = params()) {
  SafetyRunner r = depth_and_odometry(p);
  EXPECT_TRUE(r.step(t - 0.02, {t - 0.02, t - 0.02}, true).nominal());
  const auto v = r.step(t, {depth_stamp, t}, true);
  EXPECT_EQ(v.state, SafetyState::kFailsafeHover);
  return r;
}

}  // namespace

TEST(SafetyGuards, FirstStaleNamesTheFirstStaleInputInTheGivenOrder) {
  SafetyRunner r = depth_and_odometry();
  const double both_fresh[] = {0.95, 0.95};
  const double odom_stale[] = {0.95, 0.5};
  const double both_stale[] = {0.5, 0.5};
  EXPECT_EQ(r.first_stale(1.0, both_fresh), -1);
  EXPECT_EQ(r.first_stale(1.0, odom_stale), 1);
  EXPECT_EQ(r.first_stale(1.0, both_stale), 0);  // depth first
}

TEST(SafetyTransitions, StaleInputInAGuardedStateHoversAndNamesIt) {
  SafetyRunner r = depth_and_odometry();
  auto v = r.step(0.0, {0.0, 0.0}, true);
  EXPECT_TRUE(v.nominal());
  EXPECT_FALSE(v.entered);
  // Odometry 0.21 s old, depth fresh: odometry stale.
  v = r.step(0.21, {0.2, 0.0}, true);
  EXPECT_EQ(v.state, SafetyState::kFailsafeHover);
  EXPECT_TRUE(v.entered);
  EXPECT_EQ(v.reason, SafetyReason::kOdometryStale);
  EXPECT_STREQ(v.text, "odometry stale");
  EXPECT_EQ(r.stale_input(), SafetyInput::kOdometry);
  EXPECT_EQ(r.failsafe_hovers(), 1u);
}

TEST(SafetyTransitions, UnguardedStatesAreNotChecked) {
  // A hover at the start or a landing under way: stale inputs change nothing.
  SafetyRunner r = depth_and_odometry();
  for (double t = 0.0; t < 3.0; t += 0.02) EXPECT_TRUE(r.step(t, {NAN, NAN}, false).nominal());
  EXPECT_EQ(r.failsafe_hovers(), 0u);
  // The first guarded tick with a stale input hovers.
  EXPECT_EQ(r.step(3.0, {NAN, 3.0}, true).reason, SafetyReason::kDepthStale);
}

TEST(SafetyTransitions, FreshAgainResumesAndCountsTheTimeHeld) {
  SafetyRunner r = held_at(1.0);
  auto v = r.step(1.5, {1.2, 1.5}, true);  // depth still 0.3 s old
  EXPECT_EQ(v.state, SafetyState::kFailsafeHover);
  EXPECT_FALSE(v.entered);
  v = r.step(1.52, {1.51, 1.52}, false);  // fresh: resumes whatever the behaviour's state
  EXPECT_TRUE(v.nominal());
  EXPECT_TRUE(v.entered);
  EXPECT_TRUE(v.resumed);
  EXPECT_EQ(v.reason, SafetyReason::kInputsFresh);
  EXPECT_NEAR(r.held_s(), 0.52, 1e-12);
}

TEST(SafetyTransitions, StaleForFailsafeLandAfterLandsAndStaysLanding) {
  SafetyRunner r = held_at(1.0);
  EXPECT_FALSE(r.hover_expired(2.98));
  EXPECT_EQ(r.step(2.98, {0.0, 2.98}, true).state, SafetyState::kFailsafeHover);
  EXPECT_TRUE(r.hover_expired(3.0));
  auto v = r.step(3.0, {0.0, 3.0}, true);
  EXPECT_EQ(v.state, SafetyState::kFailsafeLand);
  EXPECT_TRUE(v.entered);
  EXPECT_TRUE(v.landing());
  EXPECT_EQ(v.reason, SafetyReason::kStaleTooLong);
  // Terminal: fresh inputs do not take it back into the air.
  v = r.step(3.02, {3.02, 3.02}, true);
  EXPECT_EQ(v.state, SafetyState::kFailsafeLand);
  EXPECT_FALSE(v.entered);
}

TEST(SafetyTransitions, ZeroFailsafeLandAfterLandsOnTheFirstHeldTick) {
  SafetyRunner r = held_at(1.0, 0.0, params(0.2, 0.0));
  EXPECT_EQ(r.step(1.02, {0.0, 1.02}, true).state, SafetyState::kFailsafeLand);
}

TEST(SafetyTransitions, TimeLimitLandsFromTheFirstTick) {
  SafetyParams p = params();
  p.time_limit_s = 10.0;
  SafetyRunner r = depth_and_odometry(p);
  EXPECT_TRUE(r.step(5.0, {5.0, 5.0}, false).nominal());  // the clock starts at the first tick
  EXPECT_FALSE(r.time_limit_passed(14.98));
  EXPECT_TRUE(r.step(14.98, {14.98, 14.98}, true).nominal());
  const auto v = r.step(15.0, {15.0, 15.0}, true);
  EXPECT_EQ(v.state, SafetyState::kTimeLimitLand);
  EXPECT_EQ(v.reason, SafetyReason::kTimeLimit);
  EXPECT_TRUE(v.landing());
}

TEST(SafetyTransitions, StaleBeatsTheTimeLimitOnTheSameTick) {
  SafetyParams p = params();
  p.time_limit_s = 1.0;
  SafetyRunner r = depth_and_odometry(p);
  r.step(0.0, {0.0, 0.0}, true);
  EXPECT_EQ(r.step(1.0, {0.5, 1.0}, true).state, SafetyState::kFailsafeHover);
}

TEST(SafetyTransitions, ResetStartsOver) {
  SafetyRunner r = held_at(1.0);
  r.reset();
  EXPECT_EQ(r.state(), SafetyState::kNominal);
  EXPECT_EQ(r.failsafe_hovers(), 0u);
  EXPECT_DOUBLE_EQ(r.held_s(), 0.0);
}

TEST(SafetyParamsValidate, RefusesWhatWouldTurnTheFailsafeOff) {
  SafetyParams p;
  p.max_input_age_s = INFINITY;
  try {
    p.validate("WhiskerFsm");
    FAIL() << "an infinite max_input_age_s was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("WhiskerFsm.max_input_age_s"), std::string::npos) << e.what();
  }
  p = SafetyParams{};
  p.failsafe_land_after_s = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = SafetyParams{};
  p.time_limit_s = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = SafetyParams{};
  EXPECT_NO_THROW(p.validate());  // no time limit
}

TEST(SafetyRunnerConstruction, WrongStampCountOrNoInputIsAnError) {
  SafetyRunner r = depth_and_odometry();
  EXPECT_THROW(r.step(0.0, {0.0}, true), std::invalid_argument);
  EXPECT_THROW(SafetyRunner(params(), {}), std::invalid_argument);
}
