// Node logic of the XPLORER contact mapper: parameters, inputs, PointCloud2, PLY.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mapping_pcl/xplorer_map_logic.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"

using namespace mapping_pcl;
using tactile_common::ParamMap;

namespace {
geometry_msgs::msg::WrenchStamped wrench(double fx, double fy, const char* frame = "base_link") {
  geometry_msgs::msg::WrenchStamped w;
  w.header.frame_id = frame;
  w.wrench.force.x = fx;
  w.wrench.force.y = fy;
  return w;
}
nav_msgs::msg::Odometry odom(int64_t ns, double x, double y, double z, double yaw) {
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ns, o.header.stamp);
  o.header.frame_id = "odom";
  o.child_frame_id = "base_link";
  o.pose.pose.position.x = x;
  o.pose.pose.position.y = y;
  o.pose.pose.position.z = z;
  o.pose.pose.orientation.w = std::cos(yaw / 2);
  o.pose.pose.orientation.z = std::sin(yaw / 2);
  return o;
}
}  // namespace

TEST(XplorerMapLogic, DefaultsAndRepoConfig) {
  const ParamMap d = XplorerMapLogic::default_parameters();
  const auto p = XplorerMapLogic::params_from(d);
  EXPECT_DOUBLE_EQ(p.stamping.delta_map, 1.51);
  EXPECT_DOUBLE_EQ(p.stamping.corner_offset, 0.417);
  EXPECT_EQ(p.force_average_samples, 50);
  const ParamMap f = tactile_common::load_node_parameters("../../config/xplorer_mapping.yaml", "xplorer_mapping", d);
  for (const auto& kv : d.values()) EXPECT_TRUE(f.values().at(kv.first) == kv.second) << kv.first;
  ParamMap bad = d;
  bad.set("slab_size", std::vector<double>{0.25, 0.08});
  EXPECT_THROW(XplorerMapLogic::params_from(bad), tactile_common::ParamError);
  bad = d;
  bad.set("delta_map", -1.0);
  try {
    XplorerMapLogic::params_from(bad);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("delta_map"), std::string::npos) << e.what();
  }
}

// outlier_mean_k and force_average_samples were narrowed to int unchecked:
// 2^32 + 20 became 20 and passed validate(). Now every integer parameter set
// to its default + 2^32 is rejected with its key and the value as given.
TEST(XplorerMapLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(XplorerMapLogic::default_parameters(),
                                                        [](const ParamMap& m) { XplorerMapLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 3u);  // outlier_mean_k, force_average_samples, force_now_samples
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
}

// Issue 35 item 5: every key has a description, a unit and the range validate() takes
// for it alone (none wider: range_leaks), and none is live (the component applies none).
TEST(XplorerMapLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = XplorerMapLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak : tactile_common::range_leaks(d, [](const ParamMap& m) { XplorerMapLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  ASSERT_NE(d.info("delta_map"), nullptr);
  EXPECT_EQ(d.info("delta_map")->unit, "N");
  EXPECT_EQ(d.info("delta_map")->range->text(), "(0, inf)");
  EXPECT_EQ(d.info("outlier_face_support")->range->text(), "(0, 1]");
  EXPECT_EQ(d.info("outlier_face_tolerance")->range->text(), "[0.0001, inf)");
  // inf is a valid age (never stale): the range keeps it.
  EXPECT_EQ(d.info("max_odometry_age_s")->range->text(), "(0, inf]");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(XplorerMapLogic, StampsWhilePressingAndPublishesPointCloud2) {
  XplorerMapLogic logic(XplorerMapLogic::params_from(XplorerMapLogic::default_parameters()));
  const int64_t dt = logic.period_ns();
  std::optional<sensor_msgs::msg::PointCloud2> last;
  for (int k = 0; k < 60; ++k) {  // 2 s at 30 Hz; force 2 N along -x (obstacle ahead)
    const int64_t t = k * dt;
    logic.on_odometry(odom(t, 0.0, 0.0, 0.7, 0.0));
    logic.on_wrench_body(wrench(-2.0, 0.0));
    if (auto c = logic.on_timer(t)) last = c;
  }
  EXPECT_EQ(logic.mapper().stats().slabs, 60u);
  EXPECT_EQ(logic.stats().published, 2u);  // 1 Hz
  ASSERT_TRUE(last);
  EXPECT_EQ(last->header.frame_id, "odom");  // the frame of the odometry poses
  EXPECT_EQ(last->point_step, 12u);
  ASSERT_EQ(last->fields.size(), 3u);
  EXPECT_EQ(last->fields[2].name, "z");
  EXPECT_EQ(last->fields[2].offset, 8u);
  EXPECT_EQ(last->data.size(), 12u * last->width);
  // Decode the first point by hand (little endian float32): inside the slab ahead.
  uint32_t u = 0;
  for (int b = 0; b < 4; ++b) u |= static_cast<uint32_t>(last->data[static_cast<size_t>(b)]) << (8 * b);
  float x;
  std::memcpy(&x, &u, 4);
  EXPECT_GE(x, 0.21f - 1e-6f);
  EXPECT_LE(x, 0.29f + 1e-6f);
  const MapMeasurement m = logic.finalize();
  EXPECT_NEAR(m.length, 0.25, 0.011);
  EXPECT_NEAR(m.width, 0.08, 0.011);
}

TEST(XplorerMapLogic, FsmStateGatesTheStamping) {
  XplorerMapLogic logic(XplorerMapLogic::params_from(XplorerMapLogic::default_parameters()));
  tactile_msgs::msg::FsmState st;
  st.state = "tactile_turning";
  logic.on_fsm_state(st);
  logic.on_odometry(odom(0, 0, 0, 0.7, 0));
  logic.on_wrench_body(wrench(-2.0, 0.0));
  logic.on_timer(0);
  EXPECT_EQ(logic.stats().ticks_gated, 1u);
  EXPECT_EQ(logic.map().size(), 0u);
  st.state = "tactile_traversal";  // entered 0.5 s ago: still gated (min_state_time_s = 2 s)
  tactile_common::to_stamp(tactile_common::from_seconds(0.5), st.header.stamp);
  st.time_in_state = 0.5;
  logic.on_fsm_state(st);
  logic.on_timer(tactile_common::from_seconds(0.5));
  EXPECT_EQ(logic.stats().ticks_gated, 2u);
  logic.on_odometry(odom(tactile_common::from_seconds(2.0), 0, 0, 0.7, 0));
  logic.on_timer(tactile_common::from_seconds(2.0));
  EXPECT_EQ(logic.mapper().stats().slabs, 1u);
}

TEST(XplorerMapLogic, BadInputIsCountedAndNothingIsStamped) {
  XplorerMapLogic logic(XplorerMapLogic::params_from(XplorerMapLogic::default_parameters()));
  logic.on_timer(0);  // no input yet
  EXPECT_EQ(logic.stats().ticks_without_input, 1u);
  logic.on_wrench_body(wrench(std::nan(""), 0.0));
  logic.on_wrench_body(wrench(-2.0, 0.0, "map"));  // world frame: wrong input
  EXPECT_EQ(logic.stats().dropped_nonfinite, 1u);
  EXPECT_EQ(logic.stats().dropped_wrong_frame, 1u);
  auto o = odom(0, 0, 0, 0.7, 0);
  o.pose.pose.position.x = std::nan("");
  logic.on_odometry(o);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 2u);
  logic.on_wrench_body(wrench(-2.0, 0.0));
  logic.on_odometry(odom(0, 0, 0, 0.7, 0));
  logic.on_timer(tactile_common::from_seconds(1.0));  // odometry 1 s old: stale
  EXPECT_EQ(logic.stats().ticks_without_input, 2u);
  EXPECT_EQ(logic.map().size(), 0u);
  EXPECT_THROW(logic.save_ply(), std::invalid_argument);  // no ply_file
}

TEST(XplorerMapLogic, SavePlyWritesTheConfiguredFormat) {
  ParamMap d = XplorerMapLogic::default_parameters();
  d.set("ply_binary", true);
  XplorerMapLogic logic(XplorerMapLogic::params_from(d));
  logic.on_odometry(odom(0, 0, 0, 0.7, 0));
  logic.on_wrench_body(wrench(0.0, 2.0));  // pushed left: obstacle on the right
  logic.on_timer(0);
  const std::string path = ::testing::TempDir() + "xplorer_map_logic_test.ply";
  logic.save_ply(path);
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  EXPECT_NE(s.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(s.find("comment frame odom"), std::string::npos);
  EXPECT_NE(s.find("element vertex " + std::to_string(logic.map().size())), std::string::npos);
  std::remove(path.c_str());
}

// edge_from_arms: fresh angles of all four arms move the slab's near face to
// the deflected outline (0.205988 m for arms 0/1 folded by -/+0.05 rad, see
// test_xplorer_stamping); bad arm samples are counted and ignored; stale or
// incomplete angles fall back to the fixed 0.21 m.
TEST(XplorerMapLogic, ArmAnglesSetTheSlabOffset) {
  auto arms = [](int64_t ns, std::array<double, 4> th) {
    tactile_msgs::msg::ArmImuArray a;
    tactile_common::to_stamp(ns, a.header.stamp);
    for (uint8_t i = 0; i < 4; ++i) {
      tactile_msgs::msg::ArmImu m;
      m.arm_id = i;
      m.arm_angle = th[i];
      a.arms.push_back(m);
    }
    return a;
  };
  auto at_once = XplorerMapLogic::default_parameters();
  at_once.set("corner_release_s", 0.0);  // slabs straight into the map
  XplorerMapLogic logic(XplorerMapLogic::params_from(at_once));
  logic.on_odometry(odom(0, 0.0, 0.0, 0.7, 0.0));
  logic.on_wrench_body(wrench(-2.0, 0.0));
  auto bad = arms(0, {-0.05, 0.05, 0.0, 0.0});
  bad.arms[2].arm_angle = std::nan("");
  bad.arms[3].arm_angle = 1.0;  // beyond the end stops
  bad.arms[1].arm_id = 7;
  logic.on_arm_imu(bad);
  EXPECT_EQ(logic.stats().dropped_arm_samples, 3u);
  logic.on_timer(0);  // arms 1-3 never seen: fixed offset
  EXPECT_EQ(logic.mapper().stats().offset_from_arms, 0u);
  EXPECT_NEAR(logic.map().measure().min.x(), 0.21, 1e-6);

  XplorerMapLogic fresh(XplorerMapLogic::params_from(at_once));
  fresh.on_odometry(odom(0, 0.0, 0.0, 0.7, 0.0));
  fresh.on_wrench_body(wrench(-2.0, 0.0));
  fresh.on_arm_imu(arms(0, {-0.05, 0.05, 0.0, 0.0}));
  fresh.on_timer(0);
  EXPECT_EQ(fresh.mapper().stats().offset_from_arms, 1u);
  EXPECT_NEAR(fresh.map().measure().min.x(), 0.205988, 1e-6);
  EXPECT_EQ(fresh.stats().received_arm_imu, 1u);
  // 0.5 s later without new arm angles (max_arm_age_s 0.1): the fixed offset again.
  fresh.on_odometry(odom(tactile_common::from_seconds(0.5), 0.0, 0.0, 0.7, 0.0));
  fresh.on_timer(tactile_common::from_seconds(0.5));
  EXPECT_EQ(fresh.mapper().stats().slabs, 2u);
  EXPECT_EQ(fresh.mapper().stats().offset_from_arms, 1u);
}
