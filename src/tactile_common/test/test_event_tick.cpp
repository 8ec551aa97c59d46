// EventTick (event_tick.hpp): the rules against hand-worked sequences.
#include "tactile_common/event_tick.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace {
using tactile_common::EventTick;
constexpr int64_t kMs = 1'000'000;

TEST(EventTick, RefusesANonPositivePeriod) {
  EXPECT_THROW(EventTick(0), std::invalid_argument);
  EXPECT_THROW(EventTick(-20 * kMs), std::invalid_argument);
}

TEST(EventTick, StepsOnEveryArrivalAndTheWatchdogStaysQuietWhileInputsFlow) {
  EventTick tick(20 * kMs);
  // Inputs at 50 Hz, phase 7 ms after the watchdog's calls at 0, 20, 40, ...
  int event_steps = 0, watchdog_steps = 0;
  for (int k = 0; k < 50; ++k) {
    if (tick.on_watchdog()) ++watchdog_steps;
    if (tick.on_event(k * 20 * kMs + 7 * kMs)) ++event_steps;
  }
  EXPECT_EQ(event_steps, 50);
  EXPECT_EQ(watchdog_steps, 1);  // the first call, before any input
  EXPECT_EQ(tick.stats().event_steps, 50u);
  EXPECT_EQ(tick.stats().watchdog_steps, 1u);
  EXPECT_EQ(tick.stats().skipped_events, 0u);
}

TEST(EventTick, TheWatchdogStepsEveryPeriodOnceTheInputStops) {
  EventTick tick(20 * kMs);
  EXPECT_TRUE(tick.on_event(5 * kMs));
  EXPECT_FALSE(tick.on_watchdog());  // the input stepped the node in this period
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(tick.on_watchdog()) << "watchdog call " << k;
  EXPECT_EQ(tick.stats().watchdog_steps, 10u);
  // The input returns: it drives the node again and the watchdog goes quiet.
  EXPECT_TRUE(tick.on_event(300 * kMs));
  EXPECT_FALSE(tick.on_watchdog());
}

TEST(EventTick, ArrivalsFasterThanTwicePerPeriodAreRateLimitedAndTheHeldOneStepsAtTheWatchdog) {
  EventTick tick(20 * kMs);
  EXPECT_TRUE(tick.on_event(0));
  EXPECT_FALSE(tick.on_event(9 * kMs));  // < T/2 after the last event step
  EXPECT_EQ(tick.stats().skipped_events, 1u);
  // The held-back arrival is not left for a second period: the watchdog steps for it
  // although an event stepped in this period.
  EXPECT_TRUE(tick.on_watchdog());
  // Inputs at 50 Hz again: each steps, the watchdog stays quiet.
  EXPECT_TRUE(tick.on_event(20 * kMs));
  EXPECT_FALSE(tick.on_watchdog());
  EXPECT_TRUE(tick.on_event(40 * kMs));
  EXPECT_FALSE(tick.on_watchdog());
  EXPECT_EQ(tick.stats().event_steps, 3u);
  EXPECT_EQ(tick.stats().watchdog_steps, 1u);
}

TEST(EventTick, AWatchdogStepNeverHoldsAnArrivalBack) {
  EventTick tick(20 * kMs);
  EXPECT_TRUE(tick.on_watchdog());   // no input yet
  EXPECT_TRUE(tick.on_event(1 * kMs));  // 1 ms after the watchdog's step: steps at once
  EXPECT_TRUE(tick.on_event(11 * kMs)); // exactly T/2 after the last event step
}

TEST(EventTick, AClockThatGoesBackStartsTheRateLimitOver) {
  EventTick tick(20 * kMs);
  EXPECT_TRUE(tick.on_event(1000 * kMs));
  // The clock went back (a bag played again): arrivals step again at once instead of
  // being held back until the old time is reached.
  EXPECT_TRUE(tick.on_event(5 * kMs));
  EXPECT_TRUE(tick.on_event(25 * kMs));
  EXPECT_FALSE(tick.on_event(30 * kMs));  // the rate limit holds on the new timeline
}

}  // namespace
