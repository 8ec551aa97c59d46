// Penalty contact of a circle (body, propeller guard, arm tip) with the arena's
// walls and cylinders, seen from above. Spring-damper normal force from the
// surface material (never pulling), regularised Coulomb friction against the
// tangential velocity. Model and choices: docs/physics.md, "Arena and contact".
#pragma once

#include "tactile_sim/arena.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_sim {

struct ContactParams {
  /// Friction regularisation speed [m/s]: below it friction grows linearly
  /// with the sliding speed (viscous), above it is mu * N. Keeps stiction-like
  /// behaviour stable at a 1 kHz step. Choice.
  double friction_slip_speed = 0.02;
  /// A contact episode ends only once the gap exceeds this [m] (hysteresis,
  /// so a chattering contact is one impact). Choice.
  double release_gap = 0.002;
  /// Max. surfaces summed at once (corners touch two walls).
  static constexpr int kMaxContacts = 8;

  void validate() const;  ///< throws std::invalid_argument naming the field
};

/// Contact force on the circle in one step (world frame, x-y).
struct ContactResult {
  bool contact = false;        ///< penetrating at least one surface
  bool began = false;          ///< a new contact episode began this step (log an impact)
  Vec2 force = Vec2::Zero();   ///< total force on the circle [N] (normal + friction)
  double normal_force = 0.0;   ///< sum of normal force magnitudes [N]
  double friction_force = 0.0; ///< sum of friction force magnitudes [N]
  double penetration = 0.0;    ///< deepest penetration [m]
  Vec2 point = Vec2::Zero();   ///< contact point of the deepest contact (on the surface)
  Vec2 normal = Vec2::Zero();  ///< its unit normal out of the obstacle (toward the circle)
  double impact_speed = 0.0;   ///< approach speed along the normal at the deepest contact [m/s]
  int obstacle_id = -1;
  int material = -1;
  int count = 0;               ///< surfaces in contact
};

/// One contact body (keep one per circle: body, guard, arm tip i). Holds the
/// episode state; allocation-free per step, deterministic.
class CircleContact {
 public:
  explicit CircleContact(const ContactParams& params = {});

  /// Contact of a circle at `center` with `radius`, moving with `velocity`.
  ContactResult step(const Arena& arena, const Vec2& center, double radius, const Vec2& velocity);

  bool in_episode() const { return in_episode_; }
  void reset();
  const ContactParams& params() const { return params_; }

 private:
  ContactParams params_;
  bool in_episode_ = false;
  // Normals of the surfaces touched in the previous step (thin walls: if the
  // centre crosses a wall the previous side is kept, see physics.md).
  int prev_count_ = 0;
  int prev_obstacle_[ContactParams::kMaxContacts] = {};
  Vec2 prev_normal_[ContactParams::kMaxContacts];
};

}  // namespace tactile_sim
