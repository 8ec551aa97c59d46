// Node-logic tests of xplorer_force_est: messages in/out, parameters, bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

using namespace xplorer_force_est;
using tactile_common::ParamMap;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();

sensor_msgs::msg::Imu imu(int64_t ns, const Vec3& acc) {
  sensor_msgs::msg::Imu m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.orientation.w = 1.0;
  m.linear_acceleration.x = acc.x();
  m.linear_acceleration.y = acc.y();
  m.linear_acceleration.z = acc.z();
  return m;
}

tactile_msgs::msg::ArmImuArray arms(int64_t ns, const std::array<double, 4>& th, int skip = -1) {
  tactile_msgs::msg::ArmImuArray a;
  tactile_common::to_stamp(ns, a.header.stamp);
  a.header.frame_id = "base_link";
  for (int i = 0; i < 4; ++i) {
    if (i == skip) continue;
    tactile_msgs::msg::ArmImu m;
    m.arm_id = static_cast<uint8_t>(i);
    m.arm_angle = th[static_cast<size_t>(i)];
    a.arms.push_back(m);
  }
  return a;
}

tactile_msgs::msg::ThrustCommand thrust(double normalized) {
  tactile_msgs::msg::ThrustCommand t;
  t.normalized = normalized;
  t.total_thrust = kNaN;
  return t;
}
}  // namespace

TEST(XplorerForceEstLogic, DefaultsRoundTripAndRepoConfigMatches) {
  const ParamMap d = XplorerForceEstLogic::default_parameters();
  const auto p = XplorerForceEstLogic::params_from(d);
  EXPECT_DOUBLE_EQ(p.estimator.arm_stiffness, 1.307);
  EXPECT_DOUBLE_EQ(p.estimator.thrust_scale, 32.5);
  const ParamMap f = tactile_common::load_node_parameters("../../config/xplorer_force_est.yaml", "xplorer_force_est", d);
  for (const auto& kv : d.values()) {
    EXPECT_TRUE(f.values().at(kv.first) == kv.second) << "config/xplorer_force_est.yaml differs from the defaults at " << kv.first;
  }
}

TEST(XplorerForceEstLogic, BadParametersNameTheKey) {
  ParamMap m = XplorerForceEstLogic::default_parameters();
  m.set("observer_gain", 100.0);
  try {
    XplorerForceEstLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("observer_gain"), std::string::npos) << e.what();
  }
  m = XplorerForceEstLogic::default_parameters();
  m.set("kappa_mode", std::string("fast"));
  EXPECT_THROW(XplorerForceEstLogic::params_from(m), tactile_common::ParamError);
  m = XplorerForceEstLogic::default_parameters();
  m.set("arm_directions", std::vector<double>{0.0, 1.0});
  EXPECT_THROW(XplorerForceEstLogic::params_from(m), tactile_common::ParamError);
}

// The windows and arm_hold_samples were narrowed to int unchecked: 2^32 + 5
// became 5 and passed validate(). Now every integer parameter set to its
// default + 2^32 is rejected with its key and the value as given; an even
// window inside the range gets validate()'s own message, once.
TEST(XplorerForceEstLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(XplorerForceEstLogic::default_parameters(),
                                                        [](const ParamMap& m) { XplorerForceEstLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 3u);  // arm_median_window, arm_hold_samples, com_median_window
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
  ParamMap m = XplorerForceEstLogic::default_parameters();
  m.set("com_median_window", int64_t{4});
  try {
    XplorerForceEstLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("com_median_window: must be odd and in [1, 15], got 4"), std::string::npos)
        << e.what();
  }
}

// Issue 35 item 5: every key has a description, a unit and the range validate() takes
// for it alone (none wider: range_leaks), and none is live (the component applies none).
TEST(XplorerForceEstLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = XplorerForceEstLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const ParamMap& m) { XplorerForceEstLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  ASSERT_NE(d.info("arm_median_window"), nullptr);
  EXPECT_EQ(d.info("arm_median_window")->range->text(), "[1, 15]");
  EXPECT_EQ(d.info("arm_stiffness")->unit, "N m/rad");
  EXPECT_EQ(d.info("arm_damping")->range->text(), "[0, inf)");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(XplorerForceEstLogic, StaticPushPublishesWorldAndBodyWrench) {
  XplorerForceEstLogic logic(XplorerForceEstLogic::params_from(XplorerForceEstLogic::default_parameters()));
  const Params& p = logic.params().estimator;
  const double hover = p.mass * p.gravity / p.thrust_scale;
  // Body yawed 90 deg: a push along world -y is a push along body -x, on arms 0 and 1.
  const Quat q(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  const double th = 0.0406;  // static deflection of a 0.5 N share (test_force_estimator)
  XplorerForceEstLogic::Outputs out;
  for (int k = 0; k < 150; ++k) {
    const int64_t t0 = k * 20'000'000LL;
    logic.on_thrust(thrust(hover));
    for (int j = 0; j < 10; ++j) {
      auto m = imu(t0 + j * 2'000'000LL, Vec3(-1.0 / p.mass, 0, p.gravity));  // body -x push of 1 N
      m.orientation.w = q.w();
      m.orientation.z = q.z();
      logic.on_imu(m);
    }
    out = logic.on_arm_imu(arms(t0 + 19'000'000LL, {-th, th, 0.0, 0.0}));
  }
  ASSERT_TRUE(out.world && out.body);
  EXPECT_EQ(out.world->header.frame_id, "odom");  // the IMU attitude's frame (REP 105)
  EXPECT_EQ(out.body->header.frame_id, "base_link");
  EXPECT_NEAR(out.body->wrench.force.x, -1.0, 0.1);
  EXPECT_NEAR(out.body->wrench.force.y, 0.0, 0.05);
  EXPECT_NEAR(out.world->wrench.force.y, -1.0, 0.1);
  EXPECT_NEAR(out.world->wrench.force.x, 0.0, 0.05);
  EXPECT_EQ(logic.stats().published, 150u);
  EXPECT_EQ(logic.stats().published_degraded, 0u);
}

TEST(XplorerForceEstLogic, BadInputIsCountedNeverPassedOn) {
  XplorerForceEstLogic logic(XplorerForceEstLogic::params_from(XplorerForceEstLogic::default_parameters()));
  logic.on_imu(imu(0, Vec3(kNaN, 0, 9.81)));
  auto bad_q = imu(1000, Vec3(0, 0, 9.81));
  bad_q.orientation.w = 0.5;  // not a unit quaternion
  logic.on_imu(bad_q);
  EXPECT_EQ(logic.stats().dropped_nonfinite_imu, 2u);
  logic.on_thrust(thrust(kNaN));  // normalised NaN and total NaN
  EXPECT_EQ(logic.stats().dropped_nonfinite_thrust, 1u);
  // Missing arm 2 and a duplicated/bad arm id.
  auto a = arms(20'000'000, {0.01, 0.01, 0.0, 0.0}, 2);
  tactile_msgs::msg::ArmImu extra;
  extra.arm_id = 7;
  a.arms.push_back(extra);
  a.arms.push_back(a.arms.front());
  auto out = logic.on_arm_imu(a);
  ASSERT_TRUE(out.world);
  EXPECT_TRUE(std::isfinite(out.world->wrench.force.x));
  EXPECT_EQ(logic.stats().arm_bad_id, 2u);
  EXPECT_EQ(logic.stats().arm_missing[2], 1u);
  EXPECT_EQ(logic.stats().published_degraded, 1u);
  EXPECT_FALSE(logic.estimate().arm_valid[2]);
  // An impossible deflection (1e9 rad, the simulator's out_of_range fault) is missing, not a force.
  auto big = arms(40'000'000, {1e9, 0.0, 0.0, 0.0});
  big.arms[0].orientation.w = 0.0;  // and no usable attitude either
  logic.on_arm_imu(big);
  EXPECT_EQ(logic.stats().arm_out_of_range, 1u);
  EXPECT_EQ(logic.stats().arm_missing[0], 1u);
  EXPECT_TRUE(std::isfinite(logic.estimate().force_world.x()));
  EXPECT_LT(std::abs(logic.estimate().arm_force[0]), 1.0);
  // Out of order.
  EXPECT_FALSE(logic.on_arm_imu(arms(10'000'000, {0, 0, 0, 0})).world);
  EXPECT_EQ(logic.stats().dropped_out_of_order, 1u);
}

TEST(XplorerForceEstLogic, NanArmAngleFallsBackToTheArmImuAttitude) {
  XplorerForceEstLogic logic(XplorerForceEstLogic::params_from(XplorerForceEstLogic::default_parameters()));
  logic.on_imu(imu(0, Vec3(0, 0, 9.81)));
  auto a = arms(20'000'000, {kNaN, 0.0, 0.0, 0.0});
  // Arm 0 attitude: body (identity) turned by its direction -45 deg plus theta = 0.03 rad.
  const Quat qa(Eigen::AngleAxisd(-M_PI / 4 + 0.03, Vec3::UnitZ()));
  a.arms[0].orientation.w = qa.w();
  a.arms[0].orientation.z = qa.z();
  logic.on_arm_imu(a);
  EXPECT_EQ(logic.stats().arm_from_orientation, 1u);
  EXPECT_EQ(logic.stats().arm_missing[0], 0u);
  EXPECT_NEAR(logic.estimate().theta[0], 0.03, 1e-9);
}

// Issue 33 (stale inputs): the flight-controller IMU stops while the arm IMUs
// go on. Each arm set still produced a wrench, stamped fresh, from the last
// attitude and acceleration, so the XPLORER FSM (which checks the wrench's
// age) moved on it. Now an arm set more than max_sample_gap_s after the last
// IMU sample publishes nothing (counted); the IMU back -> wrenches again.
TEST(XplorerForceEstLogic, NoWrenchFromAStaleFlightControllerImu) {
  XplorerForceEstLogic logic(XplorerForceEstLogic::params_from(XplorerForceEstLogic::default_parameters()));
  const Params& p = logic.params().estimator;
  const int64_t gap = tactile_common::from_seconds(logic.params().max_sample_gap_s);
  const int64_t imu_stops = 1'000'000'000, imu_back = 2'000'000'000;
  int published_stale = 0, published_fresh = 0, published_back = 0;
  for (int k = 0; k < 150; ++k) {
    const int64_t t0 = k * 20'000'000LL;
    logic.on_thrust(thrust(p.mass * p.gravity / p.thrust_scale));
    for (int j = 0; j < 10; ++j) {
      const int64_t ti = t0 + j * 2'000'000LL;
      if (ti < imu_stops || ti >= imu_back) logic.on_imu(imu(ti, Vec3(0, 0, p.gravity)));
    }
    const int64_t ta = t0 + 19'000'000LL;
    const bool out = logic.on_arm_imu(arms(ta, {0.0, 0.0, 0.0, 0.0})).world.has_value();
    const int64_t last_imu = ta < imu_stops ? ta : (ta < imu_back ? imu_stops - 2'000'000LL : ta);
    if (ta - last_imu > gap) {
      published_stale += out;
    } else if (ta < imu_back) {
      published_fresh += out;
    } else {
      published_back += out;
    }
  }
  EXPECT_EQ(published_stale, 0) << "a wrench was published from a flight-controller IMU older than max_sample_gap_s";
  EXPECT_GT(published_fresh, 70);  // up to 0.5 s after the IMU stopped: still published
  EXPECT_EQ(published_back, 50);   // the IMU back: every arm set
  EXPECT_EQ(logic.stats().dropped_imu_stale, static_cast<uint64_t>(150 - published_fresh - published_back));
}
