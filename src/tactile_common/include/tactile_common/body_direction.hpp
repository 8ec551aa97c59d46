// Contact and move directions of a vehicle in its body frame (FLU): the one definition the
// XPLORER exploration FSM (tactile_fsm) and its contact mapper (mapping_pcl) share.
//
// Paper 001 Sec. IV-A: the contact direction C_n is one-hot over the body axes b1, -b1, b2,
// -b2 (the axis of the larger averaged body-force component above a threshold; the obstacle
// lies opposite to the force it exerts), and the move direction lambda of the right-hand
// traversal is C_n turned by -90 deg. The values equal tactile_msgs/msg/FsmState's
// DIRECTION_* constants (the state message carries C_n and lambda; tactile_fsm checks the
// correspondence at compile time). Header only (Eigen).
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace tactile_common {

enum class BodyDirection : uint8_t {
  kNone = 0,    ///< no contact / no move direction (FsmState.DIRECTION_NONE)
  kPlusX = 1,   ///< b1, ahead
  kMinusX = 2,  ///< -b1, behind
  kPlusY = 3,   ///< b2, left
  kMinusY = 4,  ///< -b2, right
};

inline const char* to_string(BodyDirection d) {
  switch (d) {
    case BodyDirection::kNone: return "none";
    case BodyDirection::kPlusX: return "+X";
    case BodyDirection::kMinusX: return "-X";
    case BodyDirection::kPlusY: return "+Y";
    case BodyDirection::kMinusY: return "-Y";
  }
  return "?";
}

/// The body-frame unit vector of `d` (x-y); zero for kNone.
inline Eigen::Vector2d unit(BodyDirection d) {
  switch (d) {
    case BodyDirection::kPlusX: return {1.0, 0.0};
    case BodyDirection::kMinusX: return {-1.0, 0.0};
    case BodyDirection::kPlusY: return {0.0, 1.0};
    case BodyDirection::kMinusY: return {0.0, -1.0};
    case BodyDirection::kNone: break;
  }
  return {0.0, 0.0};
}

/// Right-hand traversal (001 Sec. IV-A): lambda is C_n turned by -90 deg (obstacle ahead ->
/// move right, on the right -> move back, behind -> move left, on the left -> move forward).
inline BodyDirection right_hand(BodyDirection contact) {
  switch (contact) {
    case BodyDirection::kPlusX: return BodyDirection::kMinusY;
    case BodyDirection::kMinusY: return BodyDirection::kMinusX;
    case BodyDirection::kMinusX: return BodyDirection::kPlusY;
    case BodyDirection::kPlusY: return BodyDirection::kPlusX;
    case BodyDirection::kNone: break;
  }
  return BodyDirection::kNone;
}

/// Contact direction from a body force (001 Sec. IV-A: |b_delta_f_x| > delta_0 -> contact along
/// b1, likewise b2): the axis of the larger |component| if that exceeds `threshold` [N]; the
/// obstacle lies opposite to the force (force along -b1 -> obstacle at +b1). kNone below the
/// threshold or for a non-finite force. A tie of |x| and |y| goes to the x axis.
inline BodyDirection contact_direction(const Eigen::Vector2d& force_body, double threshold) {
  const double fx = force_body.x(), fy = force_body.y();
  if (!std::isfinite(fx) || !std::isfinite(fy)) return BodyDirection::kNone;
  if (std::abs(fx) >= std::abs(fy)) {
    if (std::abs(fx) <= threshold) return BodyDirection::kNone;
    return fx < 0.0 ? BodyDirection::kPlusX : BodyDirection::kMinusX;
  }
  if (std::abs(fy) <= threshold) return BodyDirection::kNone;
  return fy < 0.0 ? BodyDirection::kPlusY : BodyDirection::kMinusY;
}

}  // namespace tactile_common
