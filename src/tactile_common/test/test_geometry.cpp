#include "tactile_common/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

struct Quat {
  double w, x, y, z;
};

/// q = q_z(yaw) * q_y(pitch) * q_x(roll), written out (Z-Y-X convention).
Quat from_euler(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  return {cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
          cr * cp * sy - sr * sp * cy};
}

}  // namespace

TEST(Geometry, YawOfPureYawRotations) {
  EXPECT_DOUBLE_EQ(tactile_common::yaw_of(Quat{1, 0, 0, 0}), 0.0);
  // 90 deg about z: (cos 45, 0, 0, sin 45).
  EXPECT_NEAR(tactile_common::yaw_of(Quat{std::sqrt(0.5), 0, 0, std::sqrt(0.5)}), M_PI / 2, 1e-15);
  EXPECT_NEAR(tactile_common::yaw_of(Quat{std::sqrt(0.5), 0, 0, -std::sqrt(0.5)}), -M_PI / 2, 1e-15);
  // 180 deg: (0, 0, 0, 1) -> pi.
  EXPECT_NEAR(tactile_common::yaw_of(Quat{0, 0, 0, 1}), M_PI, 1e-15);
}

TEST(Geometry, YawOfIgnoresRollAndPitch) {
  for (double yaw : {-3.0, -1.2, 0.0, 0.4, 2.9}) {
    for (double roll : {-0.5, 0.0, 0.3}) {
      for (double pitch : {-0.4, 0.0, 0.6}) {
        EXPECT_NEAR(tactile_common::yaw_of(from_euler(roll, pitch, yaw)), yaw, 1e-12)
            << "roll " << roll << " pitch " << pitch;
      }
    }
  }
}
