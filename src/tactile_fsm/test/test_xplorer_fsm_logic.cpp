// Node logic of the XPLORER behaviours: parameters, messages, stale and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"

using namespace tactile_fsm;
using tactile_common::ParamMap;

namespace {
nav_msgs::msg::Odometry odom(int64_t ns, double x, double y, double z) {
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ns, o.header.stamp);
  o.pose.pose.position.x = x;
  o.pose.pose.position.y = y;
  o.pose.pose.position.z = z;
  o.pose.pose.orientation.w = 1.0;
  return o;
}
geometry_msgs::msg::WrenchStamped wrench(int64_t ns, double fx, const char* frame = "odom") {
  geometry_msgs::msg::WrenchStamped w;
  tactile_common::to_stamp(ns, w.header.stamp);
  w.header.frame_id = frame;
  w.wrench.force.x = fx;
  return w;
}
}  // namespace

TEST(XplorerFsmLogic, DefaultsAndRepoConfig) {
  const ParamMap d = XplorerFsmLogic::default_parameters();
  const auto p = XplorerFsmLogic::params_from(d);
  EXPECT_DOUBLE_EQ(p.fsm.delta_0, 1.5);
  EXPECT_DOUBLE_EQ(p.fsm.yaw_rate_trigger, 0.4);
  EXPECT_DOUBLE_EQ(p.fsm.turn_rate, 0.26);
  EXPECT_DOUBLE_EQ(p.fsm.contact_force, 1.25);
  EXPECT_DOUBLE_EQ(p.fsm.admittance.damping[0], 24.5);
  const ParamMap f = tactile_common::load_node_parameters("../../config/xplorer_fsm.yaml", "xplorer_fsm", d);
  for (const auto& kv : d.values()) EXPECT_TRUE(f.values().at(kv.first) == kv.second) << kv.first;
  ParamMap bad = d;
  bad.set("mission", std::string("fly"));
  EXPECT_THROW(XplorerFsmLogic::params_from(bad), tactile_common::ParamError);
  bad = d;
  bad.set("damping", std::vector<double>{1, 2, 3});
  EXPECT_THROW(XplorerFsmLogic::params_from(bad), tactile_common::ParamError);
  bad = d;
  bad.set("delta_psi0", 1.0);
  try {
    XplorerFsmLogic::params_from(bad);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("delta_psi0"), std::string::npos) << e.what();
  }
}

// force_average_samples was narrowed to int unchecked: 2^32 + 50 became 50 and
// passed validate(). Now it is rejected with its key and the value as given.
TEST(XplorerFsmLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(XplorerFsmLogic::default_parameters(),
                                                        [](const ParamMap& m) { XplorerFsmLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 2u);  // force_average_samples, max_clockwise_turns_in_a_row
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
}

// Every key carries a description, a unit and the range params_from()/validate() accept
// for it alone (never wider: a value just outside each end is refused); all read at start.
TEST(XplorerFsmLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = XplorerFsmLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak : tactile_common::range_leaks(d, [](const ParamMap& m) { XplorerFsmLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  // An unbounded range means every finite value: infinity itself is refused.
  for (const auto& leak :
       tactile_common::infinities_accepted(d, [](const ParamMap& m) { XplorerFsmLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is accepted";
  }
  ASSERT_NE(d.info("turn_limit"), nullptr);
  EXPECT_EQ(d.info("turn_limit")->range->text(), "(0, 3.14159]");  // (0, pi] (001: 180 deg)
  EXPECT_EQ(d.info("turn_limit")->unit, "rad");
  ASSERT_NE(d.info("delta_0"), nullptr);
  EXPECT_EQ(d.info("delta_0")->unit, "N");
  ASSERT_NE(d.info("contact_backoff_time"), nullptr);
  EXPECT_EQ(d.info("contact_backoff_time")->range->text(), "[0, 2]");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(XplorerFsmLogic, SetpointsStateMessagesAndBadInput) {
  XplorerFsmLogic logic(XplorerFsmLogic::params_from(XplorerFsmLogic::default_parameters()));
  // No input yet: nothing to command.
  EXPECT_FALSE(logic.on_timer(0).setpoint);
  EXPECT_EQ(logic.stats().ticks_stale, 1u);
  logic.on_odometry(odom(0, 0, 0, 0));
  logic.on_wrench(wrench(0, 0.0));
  auto out = logic.on_timer(20000000);
  ASSERT_TRUE(out.setpoint);
  EXPECT_NEAR(out.setpoint->pose.position.z, 0.7, 1e-12);  // take-off to the hover height
  ASSERT_TRUE(out.state);
  EXPECT_EQ(out.state->behaviour, "xplorer_exploration");
  EXPECT_EQ(out.state->state, "takeoff");
  // Bad input.
  logic.on_wrench(wrench(0, std::nan("")));
  logic.on_wrench(wrench(0, 1.0, "base_link"));
  logic.on_wrench(wrench(0, 1.0, "map"));  // not the odometry's frame (xplorer_force_est said map before)
  auto o = odom(0, 0, 0, 0);
  o.pose.pose.orientation.w = 0.0;
  logic.on_odometry(o);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 2u);
  EXPECT_EQ(logic.stats().dropped_wrong_frame, 2u);
  // At the hover height: transition published.
  logic.on_odometry(odom(40000000, 0, 0, 0.7));
  out = logic.on_timer(40000000);
  ASSERT_TRUE(out.state);
  EXPECT_EQ(out.state->state, "exploration");
  EXPECT_EQ(out.state->previous_state, "takeoff");
  // Stale input (1 s old): the last setpoint is held, counted.
  out = logic.on_timer(1040000000);
  ASSERT_TRUE(out.setpoint);
  EXPECT_EQ(logic.stats().ticks_stale, 2u);
}

// Issue 33, the shared fail-safe (SafetyRunner). XPLORER held the last setpoint
// forever on stale odometry or wrench, said nothing in FsmState and never landed.
namespace {
constexpr int64_t kTick = XplorerFsmLogic::kTimerPeriodNs;

/// Flies the logic to Exploration with fresh odometry and a zero wrench up to `until_ns`;
/// returns the last setpoint.
geometry_msgs::msg::PoseStamped fly_to_exploration(XplorerFsmLogic& logic, int64_t until_ns) {
  geometry_msgs::msg::PoseStamped last;
  for (int64_t ns = 0; ns <= until_ns; ns += kTick) {
    logic.on_odometry(odom(ns, 0.0, 0.0, ns == 0 ? 0.0 : 0.7));
    logic.on_wrench(wrench(ns, 0.0));
    const auto out = logic.on_timer(ns);
    if (out.setpoint) last = *out.setpoint;
  }
  EXPECT_EQ(logic.fsm().state(), XplorerState::kExploration);
  return last;
}
double yaw_of(const geometry_msgs::msg::PoseStamped& p) {
  return 2.0 * std::atan2(p.pose.orientation.z, p.pose.orientation.w);
}
}  // namespace

// Odometry stops (the wrench goes on): FAILSAFE_HOVER with REASON_FAILSAFE_ODOMETRY_STALE
// from the first tick it is older than max_input_age_s, the last setpoint held; after
// failsafe_land_after_s FAILSAFE_LAND (REASON_FAILSAFE_STALE_TOO_LONG): x, y and yaw of the
// last setpoint, its height descending at failsafe_land_speed to kLandFloorZ, no odometry
// read. FsmState on each entry and at 5 Hz.
TEST(XplorerFsmLogic, StaleOdometryHoldsTheLastSetpointThenLands) {
  XplorerFsmLogic logic(XplorerFsmLogic::params_from(XplorerFsmLogic::default_parameters()));
  const auto& p = logic.params();
  const int64_t last_odom = 1'000'000'000;
  const auto held = fly_to_exploration(logic, last_odom);
  const int64_t age_ns = tactile_common::from_seconds(p.safety.max_input_age_s);
  const int64_t hover_ns = last_odom + age_ns + kTick;  // the first tick the odometry is stale
  const int64_t land_ns = hover_ns + tactile_common::from_seconds(p.safety.failsafe_land_after_s);
  int hover_states = 0, land_states = 0;
  double last_z = held.pose.position.z;
  for (int64_t ns = last_odom + kTick; ns <= land_ns + 5'000'000'000; ns += kTick) {
    logic.on_wrench(wrench(ns, 0.0));
    const auto out = logic.on_timer(ns);
    ASSERT_TRUE(out.setpoint) << ns;
    const auto& sp = *out.setpoint;
    EXPECT_DOUBLE_EQ(sp.pose.position.x, held.pose.position.x) << ns;
    EXPECT_DOUBLE_EQ(sp.pose.position.y, held.pose.position.y) << ns;
    EXPECT_NEAR(yaw_of(sp), yaw_of(held), 1e-12) << ns;
    if (ns < land_ns) {
      EXPECT_DOUBLE_EQ(sp.pose.position.z, held.pose.position.z) << ns;
    } else {
      const double want = std::max(XplorerFsmLogic::kLandFloorZ,
                                   held.pose.position.z - p.failsafe_land_speed * tactile_common::to_seconds(ns - land_ns));
      EXPECT_NEAR(sp.pose.position.z, want, 1e-9) << ns;
      EXPECT_LE(sp.pose.position.z, last_z);
    }
    last_z = sp.pose.position.z;
    if (!out.state) continue;
    const auto& s = *out.state;
    if (ns < hover_ns) {
      EXPECT_EQ(s.state, "exploration") << ns;  // the odometry still fresh
    } else if (ns < land_ns) {
      EXPECT_EQ(s.state, "FAILSAFE_HOVER");
      EXPECT_EQ(s.reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_ODOMETRY_STALE);
      EXPECT_EQ(s.reason, "odometry stale");
      EXPECT_EQ(s.previous_state, "exploration");
      if (hover_states++ == 0) { EXPECT_EQ(ns, hover_ns); }
    } else {
      EXPECT_EQ(s.state, "FAILSAFE_LAND");
      EXPECT_EQ(s.reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
      EXPECT_EQ(s.previous_state, "FAILSAFE_HOVER");
      if (land_states++ == 0) { EXPECT_EQ(ns, land_ns); }
    }
  }
  EXPECT_EQ(hover_states, 10);  // on entry and at 5 Hz for 2 s
  EXPECT_GE(land_states, 25);
  EXPECT_DOUBLE_EQ(last_z, XplorerFsmLogic::kLandFloorZ);  // 0.7 m at 0.25 m/s: down within 3.2 s
  EXPECT_EQ(logic.stats().failsafe_hovers, 1u);
  EXPECT_EQ(logic.stats().failsafe_landings, 1u);
  // Terminal: fresh inputs again do not resume the exploration.
  const int64_t ns = land_ns + 5'020'000'000;
  logic.on_odometry(odom(ns, 0.0, 0.0, 0.0));
  logic.on_wrench(wrench(ns, 0.0));
  const auto out = logic.on_timer(ns);
  ASSERT_TRUE(out.setpoint);
  EXPECT_DOUBLE_EQ(out.setpoint->pose.position.z, XplorerFsmLogic::kLandFloorZ);
  EXPECT_EQ(logic.safety().state(), SafetyState::kFailsafeLand);
}

// The wrench stops for 0.5 s (the odometry goes on): FAILSAFE_HOVER with
// REASON_FAILSAFE_FORCE_STALE, the FSM not stepped; fresh again: the FSM resumes in its
// state, FsmState previous_state FAILSAFE_HOVER and REASON_FAILSAFE_INPUTS_FRESH, never a
// landing.
TEST(XplorerFsmLogic, StaleForceHoversThenResumes) {
  XplorerFsmLogic logic(XplorerFsmLogic::params_from(XplorerFsmLogic::default_parameters()));
  const int64_t last_wrench = 1'000'000'000, back = 1'500'000'000;
  const auto held = fly_to_exploration(logic, last_wrench);
  const uint64_t transitions = logic.fsm().transitions();
  bool hovered = false, resumed = false;
  for (int64_t ns = last_wrench + kTick; ns <= 2'000'000'000; ns += kTick) {
    logic.on_odometry(odom(ns, 0.0, 0.0, 0.7));
    if (ns >= back) logic.on_wrench(wrench(ns, 0.0));
    const auto out = logic.on_timer(ns);
    ASSERT_TRUE(out.setpoint);
    const bool stale = ns > last_wrench + 200'000'000 && ns < back;
    if (stale) { EXPECT_DOUBLE_EQ(out.setpoint->pose.position.x, held.pose.position.x) << ns; }
    if (!out.state) continue;
    if (out.state->state == "FAILSAFE_HOVER") {
      EXPECT_TRUE(stale) << ns;
      EXPECT_EQ(out.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_FORCE_STALE);
      EXPECT_EQ(out.state->reason, "force stale");
      hovered = true;
    }
    if (ns == back) {
      EXPECT_EQ(out.state->state, "exploration");
      EXPECT_EQ(out.state->previous_state, "FAILSAFE_HOVER");
      EXPECT_EQ(out.state->reason_code, tactile_msgs::msg::FsmState::REASON_FAILSAFE_INPUTS_FRESH);
      resumed = true;
    }
    EXPECT_NE(out.state->state, "FAILSAFE_LAND");
  }
  EXPECT_TRUE(hovered);
  EXPECT_TRUE(resumed);
  EXPECT_EQ(logic.fsm().state(), XplorerState::kExploration);
  EXPECT_EQ(logic.fsm().transitions(), transitions);  // the hold is no FSM transition
  EXPECT_EQ(logic.stats().failsafe_hovers, 1u);
  EXPECT_EQ(logic.stats().failsafe_landings, 0u);
  EXPECT_EQ(logic.safety().state(), SafetyState::kNominal);
}

// The FSM's timers are paused in FAILSAFE_HOVER: a contact starts Tactile-traversal
// with contact_backoff_time (0.3 s) of holding the position of the contact; the
// odometry stops at that contact and comes back 0.5 s later. 0.2 s of the back-off
// run before the hover (the odometry still fresh), ~0.3 s are held; on the resumed
// ticks the back-off still has ~0.1 s to run, so the setpoint is still the
// back-off's. With the flight's clock it would have ended in the hover.
TEST(XplorerFsmLogic, FailsafeHoverPausesTheFsmTimers) {
  XplorerFsmLogic logic(XplorerFsmLogic::params_from(XplorerFsmLogic::default_parameters()));
  ASSERT_NEAR(logic.params().fsm.contact_backoff_time, 0.3, 1e-12);
  int64_t ns = 1'000'000'000;
  fly_to_exploration(logic, ns);
  std::optional<geometry_msgs::msg::PoseStamped> backoff;
  for (ns += kTick; ns <= 3'000'000'000 && !backoff; ns += kTick) {
    logic.on_odometry(odom(ns, 0.0, 0.0, 0.7));
    logic.on_wrench(wrench(ns, 3.0));
    const auto out = logic.on_timer(ns);
    if (logic.fsm().state() == XplorerState::kTactileTraversal) backoff = out.setpoint;
  }
  ASSERT_TRUE(backoff) << "no contact";
  const int64_t contact = ns - kTick, back = contact + 500'000'000;
  bool held = false;
  std::optional<geometry_msgs::msg::PoseStamped> first_resumed;
  for (; ns <= back + 400'000'000; ns += kTick) {
    if (ns >= back) logic.on_odometry(odom(ns, 0.0, 0.0, 0.7));
    logic.on_wrench(wrench(ns, 3.0));
    const auto out = logic.on_timer(ns);
    held = held || logic.safety().state() == SafetyState::kFailsafeHover;
    if (ns == back) first_resumed = out.setpoint;
  }
  ASSERT_TRUE(held);
  ASSERT_TRUE(first_resumed);
  EXPECT_EQ(logic.safety().state(), SafetyState::kNominal);
  EXPECT_NEAR(logic.safety().held_s(), 0.3 - 0.02, 2.5 * tactile_common::to_seconds(kTick));
  EXPECT_EQ(logic.fsm().state(), XplorerState::kTactileTraversal);
  // Still the back-off's setpoint on resuming: the position at the contact.
  EXPECT_DOUBLE_EQ(first_resumed->pose.position.x, backoff->pose.position.x);
  EXPECT_DOUBLE_EQ(first_resumed->pose.position.y, backoff->pose.position.y);
  // ... and no longer once the FSM's clock passed it.
  EXPECT_FALSE(logic.fsm().backing_off(logic.fsm_clock(tactile_common::to_seconds(ns - kTick))));
}

// The wrench stops for good: FAILSAFE_HOVER (force) then FAILSAFE_LAND exactly
// failsafe_land_after_s later (here set to 0.5 s), the descent from the held setpoint.
TEST(XplorerFsmLogic, StaleForceLandsAfterFailsafeLandAfterS) {
  ParamMap m = XplorerFsmLogic::default_parameters();
  m.set("failsafe_land_after_s", 0.5);
  XplorerFsmLogic logic(XplorerFsmLogic::params_from(m));
  const int64_t last_wrench = 1'000'000'000;
  const auto held = fly_to_exploration(logic, last_wrench);
  std::vector<std::pair<int64_t, std::string>> states;
  geometry_msgs::msg::PoseStamped last;
  for (int64_t ns = last_wrench + kTick; ns <= 3'000'000'000; ns += kTick) {
    logic.on_odometry(odom(ns, 0.0, 0.0, 0.7));
    const auto out = logic.on_timer(ns);
    ASSERT_TRUE(out.setpoint);
    last = *out.setpoint;
    if (out.state && out.state->state != "exploration" && (states.empty() || states.back().second != out.state->state))
      states.emplace_back(ns, out.state->state);
  }
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[0], std::make_pair(int64_t{1'220'000'000}, std::string("FAILSAFE_HOVER")));
  EXPECT_EQ(states[1], std::make_pair(int64_t{1'720'000'000}, std::string("FAILSAFE_LAND")));
  // 1.28 s of descent at 0.25 m/s from 0.7 m.
  EXPECT_NEAR(last.pose.position.z, held.pose.position.z - 0.25 * 1.28, 1e-9);
}

TEST(XplorerFsmLogic, FailsafeParametersAreValidated) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"failsafe_land_after_s", -1.0}, {"failsafe_land_speed", 0.0}, {"max_input_age_s", 0.0}}) {
    ParamMap m = XplorerFsmLogic::default_parameters();
    m.set(key, value);
    try {
      XplorerFsmLogic::params_from(m);
      ADD_FAILURE() << key << " = " << value << " accepted";
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}
