// Transforms of the rclcpp components (tactile_common/frames.hpp has the frame
// tree). Header-only and included only by rclcpp components built with
// tactile_component_tf() where tf2_ros is found (the Kilted extras overlay, any
// apt install of ROS 2; the Jazzy toolchain here has no tf2_ros: there the
// components broadcast no transforms and say so in their log).
//
// /tf_static is transient local, so its broadcaster is created with
// latched_publisher_options() (intra-process off: Humble's rclcpp refuses a
// transient-local publisher under intra-process, tactile_common/ros_qos.hpp);
// /tf is volatile and keeps the node's intra-process setting.
#pragma once

#include <memory>
#include <vector>

#include "geometry_msgs/msg/transform_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "rclcpp/rclcpp.hpp"
#include "tactile_common/frames.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tf2_ros/static_transform_broadcaster.hpp"
#include "tf2_ros/transform_broadcaster.hpp"

namespace tactile_common {

/// The transform header.frame_id -> child_frame_id of an odometry message (its pose).
inline geometry_msgs::msg::TransformStamped odometry_transform(const nav_msgs::msg::Odometry& odom) {
  geometry_msgs::msg::TransformStamped t;
  t.header = odom.header;
  t.child_frame_id = odom.child_frame_id;
  t.transform.translation.x = odom.pose.pose.position.x;
  t.transform.translation.y = odom.pose.pose.position.y;
  t.transform.translation.z = odom.pose.pose.position.z;
  t.transform.rotation = odom.pose.pose.orientation;
  return t;
}

/// Static transforms as messages, stamped `stamp`.
inline std::vector<geometry_msgs::msg::TransformStamped> static_transforms(const std::vector<StaticFrame>& frames,
                                                                           const builtin_interfaces::msg::Time& stamp) {
  std::vector<geometry_msgs::msg::TransformStamped> out;
  for (const auto& f : frames) {
    geometry_msgs::msg::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = f.parent;
    t.child_frame_id = f.child;
    t.transform.translation.x = f.transform.xyz[0];
    t.transform.translation.y = f.transform.xyz[1];
    t.transform.translation.z = f.transform.xyz[2];
    const auto q = f.transform.quaternion();
    t.transform.rotation.x = q[0];
    t.transform.rotation.y = q[1];
    t.transform.rotation.z = q[2];
    t.transform.rotation.w = q[3];
    out.push_back(t);
  }
  return out;
}

/// A /tf_static broadcaster that is safe inside an intra-process container.
template <class NodeT>
std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster(NodeT& node) {
  auto options = latched_publisher_options();
  options.qos_overriding_options = rclcpp::QosOverridingOptions{rclcpp::QosPolicyKind::Depth,
                                                                rclcpp::QosPolicyKind::History,
                                                                rclcpp::QosPolicyKind::Reliability};
  return std::make_unique<tf2_ros::StaticTransformBroadcaster>(node, tf2_ros::StaticBroadcasterQoS(), options);
}

}  // namespace tactile_common
