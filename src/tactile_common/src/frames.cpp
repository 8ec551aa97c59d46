#include "tactile_common/frames.hpp"

#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

namespace tactile_common {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string triple(const std::array<double, 3>& v) {
  return number(v[0]) + " " + number(v[1]) + " " + number(v[2]);
}

std::string origin_xml(const RigidTransform& t) {
  return "<origin xyz=\"" + triple(t.xyz) + "\" rpy=\"" + triple(t.rpy) + "\"/>";
}

bool finite(const std::array<double, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

void check_link(const RobotLink& l, const std::string& where) {
  if (!finite(l.origin.xyz) || !finite(l.origin.rpy) || !finite(l.visual_origin.xyz) ||
      !finite(l.visual_origin.rpy) || !finite(l.size)) {
    throw std::invalid_argument(where + ": origin, visual origin and size must be finite");
  }
  if (l.size[0] < 0.0 || l.size[1] < 0.0 || l.size[2] < 0.0) {
    throw std::invalid_argument(where + ": size must not be negative");
  }
}

void link_xml(std::string& out, const RobotLink& l, std::string_view prefix) {
  out += "  <link name=\"" + prefixed(prefix, l.name) + "\"";
  if (l.shape == RobotLink::Shape::kNone) {
    out += "/>\n";
    return;
  }
  out += ">\n    <visual>\n      " + origin_xml(l.visual_origin) + "\n      <geometry>";
  switch (l.shape) {
    case RobotLink::Shape::kBox:
      out += "<box size=\"" + triple(l.size) + "\"/>";
      break;
    case RobotLink::Shape::kCylinder:
      out += "<cylinder radius=\"" + number(l.size[0]) + "\" length=\"" + number(l.size[1]) + "\"/>";
      break;
    case RobotLink::Shape::kSphere:
      out += "<sphere radius=\"" + number(l.size[0]) + "\"/>";
      break;
    case RobotLink::Shape::kNone:
      break;
  }
  out += "</geometry>\n      <material name=\"" + l.colour + "\"/>\n    </visual>\n  </link>\n";
}

}  // namespace

void validate_frame_prefix(std::string_view prefix, std::string_view where) {
  if (prefix.empty()) return;
  const std::string got = " (got '" + std::string(prefix) + "')";
  if (prefix.front() == '/') {
    throw std::invalid_argument(std::string(where) + ": must not start with '/': tf2 frame names are relative" + got);
  }
  if (prefix.back() != '/') {
    throw std::invalid_argument(std::string(where) + ": must end with '/', e.g. cf1/" + got);
  }
  if (prefix.find("//") != std::string_view::npos) {
    throw std::invalid_argument(std::string(where) + ": must not contain '//'" + got);
  }
  for (char c : prefix) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '/';
    if (!ok) {
      throw std::invalid_argument(std::string(where) + ": only letters, digits, '_' and '/' are allowed" + got);
    }
  }
}

std::string prefixed(std::string_view prefix, std::string_view frame) {
  std::string s(prefix);
  s += frame;
  return s;
}

std::array<double, 4> RigidTransform::quaternion() const {
  // URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll), so q = qz * qy * qx.
  const double cr = std::cos(rpy[0] / 2), sr = std::sin(rpy[0] / 2);
  const double cp = std::cos(rpy[1] / 2), sp = std::sin(rpy[1] / 2);
  const double cy = std::cos(rpy[2] / 2), sy = std::sin(rpy[2] / 2);
  return {sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
          cr * cp * cy + sr * sp * sy};
}

void RobotModel::validate() const {
  if (name.empty()) throw std::invalid_argument("RobotModel.name: must not be empty");
  if (root.name != frames::kBaseLink) {
    throw std::invalid_argument("RobotModel " + name + ": the root link must be base_link, got '" + root.name + "'");
  }
  check_link(root, "RobotModel " + name + ": link base_link");
  std::set<std::string> defined{root.name};
  for (const auto& l : links) {
    const std::string where = "RobotModel " + name + ": link '" + l.name + "'";
    if (l.name.empty()) throw std::invalid_argument("RobotModel " + name + ": a link has no name");
    if (!defined.insert(l.name).second) throw std::invalid_argument(where + ": defined twice");
    if (defined.count(l.parent) == 0) {
      throw std::invalid_argument(where + ": parent '" + l.parent + "' is not defined before it");
    }
    check_link(l, where);
  }
}

std::vector<StaticFrame> static_frames(const RobotModel& model, std::string_view prefix) {
  model.validate();
  std::vector<StaticFrame> out;
  out.reserve(model.links.size());
  for (const auto& l : model.links) out.push_back({prefixed(prefix, l.parent), prefixed(prefix, l.name), l.origin});
  return out;
}

std::string to_urdf(const RobotModel& model, std::string_view prefix) {
  model.validate();
  std::string out = "<?xml version=\"1.0\"?>\n<robot name=\"" + model.name + "\">\n";
  out +=
      "  <material name=\"grey\"><color rgba=\"0.6 0.6 0.6 1\"/></material>\n"
      "  <material name=\"black\"><color rgba=\"0.1 0.1 0.1 1\"/></material>\n"
      "  <material name=\"silver\"><color rgba=\"0.85 0.85 0.9 1\"/></material>\n"
      "  <material name=\"orange\"><color rgba=\"1 0.5 0 1\"/></material>\n";
  link_xml(out, model.root, prefix);
  for (const auto& l : model.links) {
    link_xml(out, l, prefix);
    out += "  <joint name=\"" + prefixed(prefix, l.parent + "_to_" + l.name) + "\" type=\"fixed\">\n    <parent link=\"" +
           prefixed(prefix, l.parent) + "\"/>\n    <child link=\"" + prefixed(prefix, l.name) + "\"/>\n    " +
           origin_xml(l.origin) + "\n  </joint>\n";
  }
  out += "</robot>\n";
  return out;
}

}  // namespace tactile_common
