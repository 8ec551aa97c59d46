#include "tactile_sim/robot_model.hpp"

#include <cmath>
#include <string>

namespace tactile_sim {

namespace {

using tactile_common::RobotLink;
using tactile_common::RobotModel;
namespace frames = tactile_common::frames;

RobotLink link(std::string name, std::string parent, std::array<double, 3> xyz, std::array<double, 3> rpy = {}) {
  RobotLink l;
  l.name = std::move(name);
  l.parent = std::move(parent);
  l.origin.xyz = xyz;
  l.origin.rpy = rpy;
  return l;
}

RobotModel base(const char* name, RobotLink::Shape shape, std::array<double, 3> size) {
  RobotModel m;
  m.name = name;
  m.root.name = frames::kBaseLink;
  m.root.shape = shape;
  m.root.size = size;
  m.root.colour = "black";
  return m;
}

/// imu_link, flow and tof_down at the centre of mass (the sensor models of
/// sensors.hpp measure there); tof_down's x axis points down (Ry(+90 deg)).
void centre_sensors(RobotModel& m, bool downward) {
  m.links.push_back(link(frames::kImu, frames::kBaseLink, {0, 0, 0}));
  if (!downward) return;
  m.links.push_back(link(frames::kFlow, frames::kBaseLink, {0, 0, 0}));
  m.links.push_back(link(frames::kTofDown, frames::kBaseLink, {0, 0, 0}, {0, M_PI / 2, 0}));
}

/// A cylinder visual along the link's x axis from 0 to `length`.
void shaft(RobotLink& l, double radius, double length, const char* colour) {
  l.shape = RobotLink::Shape::kCylinder;
  l.size = {radius, length, 0};
  l.visual_origin.xyz = {length / 2, 0, 0};
  l.visual_origin.rpy = {0, M_PI / 2, 0};
  l.colour = colour;
}

}  // namespace

RobotModel robot_model(const CrazyflieParams& p) {
  p.validate();
  // Body: the Crazyflie 2.x frame, 92 mm motor to motor (bitcraze datasheet), as a
  // flat box; the guard circle (guard_radius) is the contact model, not drawn.
  RobotModel m = base("whiskered_crazyflie", RobotLink::Shape::kBox, {0.092, 0.092, 0.03});
  if (p.whiskers_enabled) {
    const char* names[2] = {frames::kWhiskerLeft, frames::kWhiskerRight};
    for (int i = 0; i < 2; ++i) {
      const double side = (i == 0 ? 0.5 : -0.5) * p.whisker_spacing;  // as WhiskerCrazyflie::sense_whiskers
      RobotLink w = link(names[i], frames::kBaseLink, {p.whisker_base_x, side, 0},
                         {0, -p.whisker.placement_angle, 0});  // pitched up by alpha
      shaft(w, 0.001, p.whisker.length, "silver");  // drawn 2 mm thick (the wire is 0.4 mm: invisible)
      m.links.push_back(w);
    }
  }
  centre_sensors(m, true);
  return m;
}

RobotModel robot_model(const XplorerParams& p) {
  p.validate();
  RobotModel m = base("xplorer", RobotLink::Shape::kCylinder, {p.body_radius, 0.04, 0});
  for (int i = 0; i < 4; ++i) {
    const double a = Xplorer::kArmDirections[static_cast<size_t>(i)];
    const std::string arm = "arm" + std::to_string(i);
    RobotLink l = link(arm, frames::kBaseLink, {p.hinge_offset * std::cos(a), p.hinge_offset * std::sin(a), 0},
                       {0, 0, a});
    shaft(l, 0.008, p.arm_length, "grey");
    m.links.push_back(l);
    m.links.push_back(link(arm + "_imu", arm, {p.arm_imu_position, 0, 0}));
    RobotLink rotor = link("rotor" + std::to_string(i), arm, {p.arm_length, 0, 0});
    rotor.shape = RobotLink::Shape::kCylinder;  // the propeller guard (contact circle)
    rotor.size = {p.guard_radius, 0.01, 0};
    rotor.colour = "orange";
    m.links.push_back(rotor);
  }
  centre_sensors(m, false);
  return m;
}

RobotModel robot_model(const DuctedQuadParams& p) {
  p.validate();
  const double L = p.rotor_offset;
  RobotModel m = base("ducted_quadrotor", RobotLink::Shape::kBox, {L, L, 0.03});
  // DuctedQuad's rotor order: counter-clockwise from the front-right one.
  const std::array<std::array<double, 3>, 4> at{{{L, -L, 0}, {L, L, 0}, {-L, L, 0}, {-L, -L, 0}}};
  for (int i = 0; i < 4; ++i) {
    RobotLink duct = link("rotor" + std::to_string(i), frames::kBaseLink, at[static_cast<size_t>(i)]);
    duct.shape = RobotLink::Shape::kCylinder;  // the duct (guard_radius: R + wall)
    duct.size = {p.guard_radius, 0.03, 0};
    duct.colour = "orange";
    m.links.push_back(duct);
  }
  centre_sensors(m, true);
  return m;
}

RobotModel robot_model(const WhiskerStageParams& p) {
  p.validate();
  RobotModel m = base("whisker_stage", RobotLink::Shape::kBox, {0.04, 0.04, 0.02});
  RobotLink w = link("whisker_base", frames::kBaseLink, {0, 0, 0});
  shaft(w, 0.001, p.beam.length, "silver");
  m.links.push_back(w);
  return m;
}

}  // namespace tactile_sim
