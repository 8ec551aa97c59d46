// arena_markers(): the arena of a run as RViz markers, against hand-computed poses,
// scales, ids and colours.
#include <gtest/gtest.h>

#include <cmath>

#if __has_include("visualization_msgs/msg/marker_array.hpp")
#include "tactile_sim/logic/arena_markers.hpp"

using tactile_sim::Arena;
using tactile_sim::Vec2;
using visualization_msgs::msg::Marker;

TEST(ArenaMarkers, WallsAsCubesCylindersAsCylindersAfterADeleteAll) {
  Arena a;
  a.set_floor_z(0.2);
  const int o = a.add_obstacle("walls");
  a.add_wall(Vec2(0, 0), Vec2(2, 0), a.find_material("rigid"), o);
  a.add_wall(Vec2(1, 1), Vec2(1, 3), a.find_material("glass"), o);
  a.add_cylinder(Vec2(3, 3), 0.5, a.find_material("textile"), a.add_obstacle("pipe"));
  const auto out = tactile_sim::arena_markers(a, "map");
  ASSERT_EQ(out.markers.size(), 4u);
  EXPECT_EQ(out.markers[0].action, Marker::DELETEALL);

  const Marker& w0 = out.markers[1];
  EXPECT_EQ(w0.header.frame_id, "map");
  EXPECT_EQ(w0.ns, "arena_walls");
  EXPECT_EQ(w0.id, 0);
  EXPECT_EQ(w0.type, Marker::CUBE);
  EXPECT_DOUBLE_EQ(w0.pose.position.x, 1.0);
  EXPECT_DOUBLE_EQ(w0.pose.position.y, 0.0);
  EXPECT_DOUBLE_EQ(w0.pose.position.z, 0.7);  // floor 0.2 + half of 1 m
  EXPECT_DOUBLE_EQ(w0.pose.orientation.w, 1.0);
  EXPECT_DOUBLE_EQ(w0.scale.x, 2.0);
  EXPECT_DOUBLE_EQ(w0.scale.y, 0.01);
  EXPECT_DOUBLE_EQ(w0.scale.z, 1.0);
  EXPECT_FLOAT_EQ(w0.color.r, 0.6f);  // rigid: grey, opaque
  EXPECT_FLOAT_EQ(w0.color.a, 1.0f);

  const Marker& w1 = out.markers[2];  // along +y: yaw 90 deg
  EXPECT_EQ(w1.id, 1);
  EXPECT_DOUBLE_EQ(w1.pose.position.x, 1.0);
  EXPECT_DOUBLE_EQ(w1.pose.position.y, 2.0);
  EXPECT_NEAR(w1.pose.orientation.w, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(w1.pose.orientation.z, std::sqrt(0.5), 1e-12);
  EXPECT_DOUBLE_EQ(w1.scale.x, 2.0);
  EXPECT_FLOAT_EQ(w1.color.a, 0.4f);  // glass: translucent

  const Marker& c = out.markers[3];
  EXPECT_EQ(c.ns, "arena_cylinders");
  EXPECT_EQ(c.id, 0);
  EXPECT_EQ(c.type, Marker::CYLINDER);
  EXPECT_DOUBLE_EQ(c.pose.position.x, 3.0);
  EXPECT_DOUBLE_EQ(c.scale.x, 1.0);
  EXPECT_DOUBLE_EQ(c.scale.y, 1.0);
  EXPECT_FLOAT_EQ(c.color.b, 0.8f);  // textile: purple
}
#else
TEST(ArenaMarkers, WallsAsCubesCylindersAsCylindersAfterADeleteAll) {
  GTEST_SKIP() << "visualization_msgs not in this ROS 2 toolchain";
}
#endif
