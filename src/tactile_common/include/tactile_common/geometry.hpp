// Small planar-pose helpers shared by the node logics.
#pragma once

#include <cmath>

namespace tactile_common {

/// Yaw [rad] of a unit quaternion (members w, x, y, z, e.g.
/// geometry_msgs::msg::Quaternion): the first angle of the intrinsic Z-Y-X
/// (yaw-pitch-roll) decomposition, atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)),
/// in (-pi, pi]. The heading of a planar pose whatever its roll and pitch.
template <class Quaternion>
double yaw_of(const Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

}  // namespace tactile_common
