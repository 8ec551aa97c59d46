// Node logic of the XPLORER behaviours: parameters, messages, stale and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
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
