// The attitude log block of the bridge's odometry: the firmware's compressed
// state estimate (stabilizer.c, log group stateEstimateZ)
//   quat      uint32  quatcompress(x, y, z, w) of the estimate's attitude
//   rateRoll  int16   gyro x [mrad/s]
//   ratePitch int16   -gyro y [mrad/s]  (the firmware's legacy pitch sign)
//   rateYaw   int16   gyro z [mrad/s]
// (10 bytes) and, where the firmware logs them (Kalman estimator,
// estimator_kalman.c: kalman.varX/varY/varZ = P[X][X], P[Y][Y], P[Z][Z] [m^2]),
// the position variances (12 bytes more: 22 of the 26 a block can carry).
// The 24-byte state block (stateEstimate.x/y/z/yaw/vx/vy, floats) has no room
// for them, hence a second block at the same period.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "crazyflie_bridge/protocol.hpp"

namespace crazyflie_bridge {

class AttitudeBlock {
 public:
  static std::vector<std::string> compressed_vars() {
    return {"stateEstimateZ.quat", "stateEstimateZ.rateRoll", "stateEstimateZ.ratePitch", "stateEstimateZ.rateYaw"};
  }
  static std::vector<std::string> variance_vars() { return {"kalman.varX", "kalman.varY", "kalman.varZ"}; }

  struct Sample {
    quatz::Quat q;                  ///< attitude (x, y, z, w), world <- body
    double rates[3] = {0, 0, 0};    ///< body rates p, q, r [rad/s], REP-103 (pitch sign restored)
    bool have_variances = false;
    double position_variance[3] = {0, 0, 0};  ///< [m^2] kalman.varX/Y/Z
    uint32_t timestamp_ms = 0;      ///< firmware time (24 bit)
  };

  /// Decodes one sample of the layout (4 values, or 7 with the variances).
  /// Returns nullopt for a value that is not finite or out of its type's
  /// range, a quaternion pattern quatcompress cannot produce (it would decode
  /// to a non-unit quaternion) or a negative variance (counted by the caller).
  static std::optional<Sample> decode(const std::vector<double>& values, uint32_t timestamp_ms);
};

}  // namespace crazyflie_bridge
