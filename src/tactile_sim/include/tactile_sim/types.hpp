// Common types of the SITL world (core layer: Eigen only, no ROS, no messages).
// Frames follow REP-103: world ENU (x east, y north, z up), body FLU (x
// forward, y left, z up); SI units.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>

namespace tactile_sim {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;
using Mat3 = Eigen::Matrix3d;

constexpr double kGravity = 9.81;  ///< [m/s^2]

/// Random source of a model. Every model owns one, seeded from the scenario
/// seed and a per-model stream id (see stream_seed), so adding a model does
/// not change the noise of the others.
using Rng = std::mt19937_64;

/// Seed of stream `stream` of a run with seed `seed` (SplitMix64 mixing).
inline uint64_t stream_seed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// State of a rigid body: position and velocity in the world frame,
/// orientation body->world, angular velocity in the body frame.
struct RigidBodyState {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();

  /// Heading (yaw about world z) [rad].
  double yaw() const {
    const Vec3 x = orientation * Vec3::UnitX();
    return std::atan2(x.y(), x.x());
  }
};

/// A body or guard impact with the arena (a whisker touching is not one).
struct CollisionEvent {
  double time_s = 0.0;       ///< simulated time of the impact
  std::string part;          ///< "body", "guard", "arm0".."arm3"
  Vec2 point = Vec2::Zero();  ///< contact point in the world (x, y)
  Vec2 normal = Vec2::Zero(); ///< unit normal out of the obstacle
  double impact_speed = 0.0;  ///< normal speed at the impact [m/s]
  int obstacle_id = -1;       ///< arena obstacle index
};

}  // namespace tactile_sim
