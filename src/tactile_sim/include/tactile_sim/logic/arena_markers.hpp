// The arena of a run as RViz markers (visualization_msgs/MarkerArray), for the simulator's
// latched sim/arena topic. Header-only: compiled only where visualization_msgs is (every
// ROS-free build; ROS builds whose toolchain has it, see tactile_msgs/README.md).
#pragma once

#include <cmath>
#include <string>

#include "tactile_sim/arena.hpp"
#include "visualization_msgs/msg/marker_array.hpp"

namespace tactile_sim {

/// Drawn height of the walls and cylinders above the floor [m]: display only (the
/// simulator's walls are unbounded vertical planes, arena.hpp).
constexpr double kArenaMarkerHeight = 1.0;
/// Drawn thickness of a wall [m] (the simulator's walls have none).
constexpr double kArenaWallThickness = 0.01;

/// One CUBE per wall (ns "arena_walls", id = wall index: centre at mid-segment, yaw along
/// it, x = length, y = kArenaWallThickness, z = kArenaMarkerHeight from floor_z) and one
/// CYLINDER per cylinder (ns "arena_cylinders", id = index, diameter 2 r), in `frame_id`
/// (the world: map), stamp 0 (static; RViz uses the latest transform). A DELETEALL first
/// clears a previous run's arena. Colour by material: glass translucent light blue,
/// textile purple, anything else (rigid) grey.
inline visualization_msgs::msg::MarkerArray arena_markers(const Arena& arena, const std::string& frame_id) {
  using visualization_msgs::msg::Marker;
  visualization_msgs::msg::MarkerArray out;
  Marker clear;
  clear.action = Marker::DELETEALL;
  out.markers.push_back(clear);
  const auto paint = [&arena](Marker& m, int material) {
    const std::string& name = arena.material(material).name;
    const auto rgba = [&m](float r, float g, float b, float a) {
      m.color.r = r;
      m.color.g = g;
      m.color.b = b;
      m.color.a = a;
    };
    if (name == "glass") {
      rgba(0.6f, 0.8f, 1.0f, 0.4f);
    } else if (name == "textile") {
      rgba(0.6f, 0.3f, 0.8f, 1.0f);
    } else {
      rgba(0.6f, 0.6f, 0.6f, 1.0f);
    }
  };
  const double z = arena.floor_z() + 0.5 * kArenaMarkerHeight;
  for (std::size_t i = 0; i < arena.walls().size(); ++i) {
    const Wall& w = arena.walls()[i];
    Marker m;
    m.header.frame_id = frame_id;
    m.ns = "arena_walls";
    m.id = static_cast<int>(i);
    m.type = Marker::CUBE;
    m.action = Marker::ADD;
    const Vec2 mid = 0.5 * (w.a + w.b), d = w.b - w.a;
    const double yaw = std::atan2(d.y(), d.x());
    m.pose.position.x = mid.x();
    m.pose.position.y = mid.y();
    m.pose.position.z = z;
    m.pose.orientation.w = std::cos(0.5 * yaw);
    m.pose.orientation.z = std::sin(0.5 * yaw);
    m.scale.x = d.norm();
    m.scale.y = kArenaWallThickness;
    m.scale.z = kArenaMarkerHeight;
    paint(m, w.material);
    out.markers.push_back(m);
  }
  for (std::size_t i = 0; i < arena.cylinders().size(); ++i) {
    const Cylinder& c = arena.cylinders()[i];
    Marker m;
    m.header.frame_id = frame_id;
    m.ns = "arena_cylinders";
    m.id = static_cast<int>(i);
    m.type = Marker::CYLINDER;
    m.action = Marker::ADD;
    m.pose.position.x = c.center.x();
    m.pose.position.y = c.center.y();
    m.pose.position.z = z;
    m.pose.orientation.w = 1.0;
    m.scale.x = 2.0 * c.radius;
    m.scale.y = 2.0 * c.radius;
    m.scale.z = kArenaMarkerHeight;
    paint(m, c.material);
    out.markers.push_back(m);
  }
  return out;
}

}  // namespace tactile_sim
