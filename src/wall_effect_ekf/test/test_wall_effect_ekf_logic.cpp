// Node logic of wall_effect_ekf: parameters (repo config = defaults, errors
// name the key), input validation counted in Stats, staleness, and a stream of
// messages generated from the model near a wall giving a detected wall.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"

using namespace wall_effect_ekf;
using tactile_common::ParamMap;

namespace {

sensor_msgs::msg::Imu imu(int64_t ns, const Vec3& a, const Vec3& w) {
  sensor_msgs::msg::Imu m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.linear_acceleration.x = a.x();
  m.linear_acceleration.y = a.y();
  m.linear_acceleration.z = a.z();
  m.angular_velocity.x = w.x();
  m.angular_velocity.y = w.y();
  m.angular_velocity.z = w.z();
  return m;
}
tactile_msgs::msg::ThrustCommand thrust(int64_t ns, const Vec4& t) {
  tactile_msgs::msg::ThrustCommand m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.total_thrust = t.sum();
  m.rotor_thrust = {t[0], t[1], t[2], t[3]};
  return m;
}

}  // namespace

TEST(WallEffectEkfLogic, RepoConfigEqualsDefaults) {
  const ParamMap d = WallEffectEkfLogic::default_parameters();
  const ParamMap f = tactile_common::load_node_parameters("../../config/wall_effect_ekf.yaml", "/wall_effect_ekf", d);
  for (const auto& [key, value] : d.values()) {
    ASSERT_TRUE(f.has(key)) << key;
    EXPECT_EQ(f.origin(key), "../../config/wall_effect_ekf.yaml") << key << " not set in the config file";
    EXPECT_TRUE(value == f.values().at(key)) << key;
  }
  EXPECT_NO_THROW(WallEffectEkfLogic::params_from(f));
}

TEST(WallEffectEkfLogic, BadParametersNameTheKey) {
  ParamMap m = WallEffectEkfLogic::default_parameters();
  m.set("ekf.r_flow", -1.0);
  try {
    WallEffectEkfLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("ekf.r_flow"), std::string::npos) << e.what();
  }
  m = WallEffectEkfLogic::default_parameters();
  m.set("proximity.b2", 1.5);
  try {
    WallEffectEkfLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("proximity.b2"), std::string::npos) << e.what();
  }
  m = WallEffectEkfLogic::default_parameters();
  m.set("vehicle.inertia_diag", std::vector<double>{1e-3, 1e-3});
  EXPECT_THROW(WallEffectEkfLogic::params_from(m), tactile_common::ParamError);
  m.set("vehicle.inertia_diag", std::vector<double>{1e-3, -1e-3, 1e-3});
  try {
    WallEffectEkfLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("ros__parameters.vehicle.inertia_diag: VehicleParams.inertia_diag[1]"),
              std::string::npos)
        << e.what();
  }
  // A rate so small that ekf.dt = 1 / rate_hz overflows: EkfParams refuses dt, which is no
  // key of its own; the error names rate_hz (it named vehicle.inertia_diag).
  m = WallEffectEkfLogic::default_parameters();
  m.set("rate_hz", 1e-310);
  try {
    WallEffectEkfLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("wall_effect_ekf.ros__parameters.rate_hz: "), std::string::npos) << e.what();
  }
}

// Every integer parameter set to its default + 2^32 is rejected with its key
// and the value as given (min_flow_quality: [0, 255], the OpticalFlow quality byte).
TEST(WallEffectEkfLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(WallEffectEkfLogic::default_parameters(),
                                                        [](const ParamMap& m) { WallEffectEkfLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 1u);  // min_flow_quality
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
}

// Issue 35 item 5: every key has a description, a unit and the range validate() takes
// for it alone (none wider: range_leaks; an unbounded end means every finite value:
// infinities_accepted), and none is live (the component applies none).
TEST(WallEffectEkfLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = WallEffectEkfLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  EXPECT_EQ(d.infos().size(), d.values().size());
  const auto params_from = [](const ParamMap& m) { WallEffectEkfLogic::params_from(m); };
  for (const auto& leak : tactile_common::range_leaks(d, params_from)) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& inf : tactile_common::infinities_accepted(d, params_from)) {
    ADD_FAILURE() << inf.key << " = " << inf.value << " is accepted, its described range says finite";
  }
  ASSERT_NE(d.info("proximity.b1"), nullptr);
  EXPECT_EQ(d.info("proximity.b1")->range->text(), "(0, 1)");
  EXPECT_EQ(d.info("min_flow_quality")->range->text(), "[0, 255]");
  EXPECT_EQ(d.info("ekf.q_distance")->range->text(), "[0, inf)");
  EXPECT_EQ(d.info("ekf.q_distance")->unit, "m/sqrt(s)");
  EXPECT_EQ(d.info("rate_hz")->unit, "Hz");
  EXPECT_EQ(d.info("vehicle.linear_drag")->unit, "N s/m");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(WallEffectEkfLogic, BadInputIsCountedAndDropped) {
  WallEffectEkfLogic logic(WallEffectEkfLogic::params_from(WallEffectEkfLogic::default_parameters()));
  logic.on_imu(imu(0, Vec3(0, NAN, 9.8), Vec3::Zero()));
  tactile_msgs::msg::ThrustCommand t = thrust(0, Vec4::Constant(0.7));
  t.rotor_thrust.pop_back();
  logic.on_thrust(t);
  logic.on_thrust(thrust(0, Vec4(0.7, -0.1, 0.7, 0.7)));
  tactile_msgs::msg::OpticalFlow f;
  f.flow_x = NAN;
  logic.on_flow(f);
  f.flow_x = 0.0;
  f.quality = 0;
  logic.on_flow(f);
  sensor_msgs::msg::Range r;
  r.range = INFINITY;
  logic.on_range(r);
  // Nothing valid yet: no step, no output.
  EXPECT_FALSE(logic.on_timer(10'000'000).has_value());
  const auto& s = logic.stats();
  EXPECT_EQ(s.dropped_nonfinite, 2u);
  EXPECT_EQ(s.dropped_bad_thrust, 2u);
  EXPECT_EQ(s.dropped_low_quality, 1u);
  EXPECT_EQ(s.dropped_out_of_range, 1u);
  EXPECT_EQ(s.ticks_without_input, 1u);
  EXPECT_EQ(s.published, 0u);
}

TEST(WallEffectEkfLogic, StaleInputsStopTheFilter) {
  WallEffectEkfLogic logic(WallEffectEkfLogic::params_from(WallEffectEkfLogic::default_parameters()));
  auto t = thrust(0, Vec4::Constant(0.28 * kGravity / 4));
  t.header.frame_id = "cf1/base_link";
  logic.on_thrust(t);
  logic.on_imu(imu(0, Vec3(0, 0, kGravity), Vec3::Zero()));
  const auto out = logic.on_timer(10'000'000);
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->header.frame_id, "cf1/base_link");  // the body frame of the thrusts (a prefixed vehicle)
  EXPECT_FALSE(logic.on_timer(200'000'000).has_value());  // 0.2 s > max_input_age_s
  EXPECT_EQ(logic.stats().ticks_without_input, 1u);
}

TEST(WallEffectEkfLogic, DetectsAWallFromModelMessages) {
  // A vehicle hovering level 0.16 m from a wall on its right (body -y):
  // the messages the simulator would send, generated from the model.
  const auto params = WallEffectEkfLogic::params_from(WallEffectEkfLogic::default_parameters());
  WallEffectEkfLogic logic(params);
  WallState truth;
  truth.y = 0.16;
  truth.z = 0.8;
  const VehicleParams& v = params.ekf.vehicle;
  // Thrusts that balance the near-wall roll torque and carry the weight (eq. 36 with B of eq. 8).
  Mat4 M;
  M.topRows<3>() = torque_matrix(truth.y, truth.R, v);
  M.row(3).setOnes();
  const Vec4 T = M.fullPivLu().solve(Vec4(0, 0, 0, v.mass * kGravity / rotor_wrench(Vec4::Constant(0.25), truth.y, truth.R, v).force_wall.z()));
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::optional<tactile_msgs::msg::WallEstimate> last;
  for (int k = 0; k < 300; ++k) {  // 3 s
    const int64_t ns = static_cast<int64_t>(k) * 10'000'000;
    logic.on_thrust(thrust(ns, T));
    for (int j = 0; j < 5; ++j)
      logic.on_imu(imu(ns, predict_accel(truth, T, v) + 0.04 * Vec3(n(rng), n(rng), n(rng)), 0.003 * Vec3(n(rng), n(rng), n(rng))));
    tactile_msgs::msg::OpticalFlow f;
    f.flow_x = 0.02 * n(rng);
    f.flow_y = 0.02 * n(rng);
    f.quality = 200;
    logic.on_flow(f);
    if (k % 2 == 0) {
      sensor_msgs::msg::Range r;
      r.range = static_cast<float>(truth.z + 0.003 * n(rng));
      logic.on_range(r);
    }
    last = logic.on_timer(ns);
    ASSERT_TRUE(last.has_value());
  }
  EXPECT_TRUE(last->wall_detected);
  EXPECT_NEAR(last->distance, 0.16, 0.015);
  EXPECT_NEAR(last->direction, -M_PI / 2, 0.2);  // the wall is on the right
  EXPECT_NEAR(last->height, 0.8, 0.02);
  EXPECT_GT(last->covariance[0], 0.0);
  EXPECT_EQ(last->covariance[1], last->covariance[3]);
  EXPECT_EQ(logic.stats().published, 300u);
}
