// whisker_localization on the standalone host: the node reads
// config/whisker_localization.yaml, takes base moments and odometry from the
// bus and publishes its result and pose set (paper 002, Table II sweep 03).
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/time.hpp"
#include "whisker_localization/stage_sim.hpp"

namespace wl = whisker_localization;

TEST(WhiskerLocalizationHost, SweepPublishesAShrinkingPoseSet) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  const double pi = 3.14159265358979323846;
  const double heading = -pi / 2 + 40.0 * pi / 180.0;
  const double reach = 0.075 - 0.004 / std::cos(40.0 * pi / 180.0);
  wl::Pose2 base{-0.012 - reach * std::cos(heading), -reach * std::sin(heading), heading};
  auto logic = tactile_cli::add_whisker_localization(
      host, tactile_cli::overrides({{"use_prior", true}, {"prior_x", base.x}, {"prior_y", base.y},
                                    {"prior_yaw", base.theta}}));
  std::vector<tactile_msgs::msg::LocalizationResult> results;
  std::size_t pose_sets = 0;
  host.bus().subscribe<tactile_msgs::msg::LocalizationResult>(
      wl::WhiskerLocalizationLogic::kResultTopic,
      [&](const tactile_msgs::msg::LocalizationResult& m) { results.push_back(m); });
  host.bus().subscribe<geometry_msgs::msg::PoseArray>(wl::WhiskerLocalizationLogic::kPoseSetTopic,
                                                      [&](const geometry_msgs::msg::PoseArray&) { ++pose_sets; });
  const wl::ElasticaSolver solver{wl::BeamParams{}};
  const wl::BoundaryMap world({wl::concave_corner_polyline(0.05, 0.15, 0.00005)}, 0.001);
  const wl::Pose2 motion{0.0005 * std::cos(-heading), 0.0005 * std::sin(-heading), 0.0};
  wl::Pose2 stage{};
  for (int k = 0; k < 40; ++k) {
    if (k > 0) {
      base = wl::compose(base, motion);
      stage = wl::compose(stage, motion);
    }
    const auto wc = wl::tip_wall_contact(solver, world, base);
    ASSERT_TRUE(wc.contact && wc.ok);
    const int64_t ns = 1000000 + k * 20000000LL;
    nav_msgs::msg::Odometry o;
    tactile_common::to_stamp(ns, o.header.stamp);
    o.pose.pose.position.x = stage.x;
    o.pose.pose.position.y = stage.y;
    o.pose.pose.orientation.w = 1.0;
    host.bus().publish(wl::WhiskerLocalizationLogic::kOdomTopic, o, ns);
    geometry_msgs::msg::WrenchStamped w;
    tactile_common::to_stamp(ns, w.header.stamp);
    w.wrench.torque.z = wc.m0;
    host.bus().publish(wl::WhiskerLocalizationLogic::kMomentTopic, w, ns);
  }
  ASSERT_EQ(results.size(), 40u);
  EXPECT_EQ(pose_sets, 40u);
  const auto& last = results.back();
  ASSERT_FALSE(last.pose_set.poses.empty());
  EXPECT_LT(last.pose_set.poses.size(), results[8].pose_set.poses.size());  // the set shrinks
  EXPECT_LT(std::hypot(last.best_estimate.position.x - base.x, last.best_estimate.position.y - base.y), 0.003);
  bool reported = false;
  for (const auto& r : host.reports()) reported |= r.name == "/whisker_localization";
  EXPECT_TRUE(reported);
}
