// tactile_common/ros_qos.hpp on a real rclcpp::Node: data publishers are reliable and
// volatile (REP 2003), latched ones reliable and transient local with intra-process off,
// and a user re-tunes either through the node's qos_overrides.<topic>.publisher.* parameters.

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "rclcpp/rclcpp.hpp"
#include "std_msgs/msg/string.hpp"
#include "tactile_common/ros_qos.hpp"

namespace {

class RosQos : public ::testing::Test {
 protected:
  void SetUp() override {
    context_ = std::make_shared<rclcpp::Context>();
    context_->init(0, nullptr);
  }
  void TearDown() override { context_->shutdown("test done"); }
  rclcpp::NodeOptions options() const { return rclcpp::NodeOptions().context(context_).use_global_arguments(false); }
  std::shared_ptr<rclcpp::Context> context_;
};

TEST_F(RosQos, DataPublishersAreReliableVolatileKeepLast10) {
  auto node = std::make_shared<rclcpp::Node>("probe", "/cf", options().use_intra_process_comms(true));
  const auto pub = tactile_common::data_publisher<std_msgs::msg::String>(*node, "depth");
  const rclcpp::QoS qos = pub->get_actual_qos();
  EXPECT_EQ(qos.reliability(), rclcpp::ReliabilityPolicy::Reliable);
  EXPECT_EQ(qos.durability(), rclcpp::DurabilityPolicy::Volatile);
  EXPECT_EQ(qos.history(), rclcpp::HistoryPolicy::KeepLast);
  EXPECT_EQ(qos.depth(), 10u);
  // The override parameters are declared, read-only, with the values in use.
  EXPECT_EQ(node->get_parameter("qos_overrides./cf/depth.publisher.reliability").as_string(), "reliable");
  EXPECT_EQ(node->get_parameter("qos_overrides./cf/depth.publisher.depth").as_int(), 10);
  EXPECT_TRUE(node->describe_parameter("qos_overrides./cf/depth.publisher.reliability").read_only);
  EXPECT_FALSE(node->has_parameter("qos_overrides./cf/depth.publisher.durability"));  // not overridable
}

TEST_F(RosQos, AUserOverridesReliabilityAndDepthThroughParameters) {
  auto opts = options();
  opts.parameter_overrides({{"qos_overrides./cf/depth.publisher.reliability", "best_effort"},
                            {"qos_overrides./cf/depth.publisher.depth", int64_t{3}}});
  auto node = std::make_shared<rclcpp::Node>("probe", "/cf", opts);
  const rclcpp::QoS qos = tactile_common::data_publisher<std_msgs::msg::String>(*node, "depth")->get_actual_qos();
  EXPECT_EQ(qos.reliability(), rclcpp::ReliabilityPolicy::BestEffort);
  EXPECT_EQ(qos.depth(), 3u);
}

TEST_F(RosQos, LatchedPublishersAreTransientLocalOutsideIntraProcessAndOverridable) {
  auto opts = options().use_intra_process_comms(true);
  opts.parameter_overrides({{"qos_overrides./cf/map.publisher.depth", int64_t{2}}});
  auto node = std::make_shared<rclcpp::Node>("probe", "/cf", opts);
  // Would throw on Humble's rclcpp under intra-process; the latched publisher turns it off.
  const auto pub = tactile_common::latched_publisher<std_msgs::msg::String>(*node, "map");
  const rclcpp::QoS qos = pub->get_actual_qos();
  EXPECT_EQ(qos.reliability(), rclcpp::ReliabilityPolicy::Reliable);
  EXPECT_EQ(qos.durability(), rclcpp::DurabilityPolicy::TransientLocal);
  EXPECT_EQ(qos.depth(), 2u);
}

}  // namespace
