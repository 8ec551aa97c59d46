#include "crazyflie_bridge/attitude_block.hpp"

#include <cmath>

namespace crazyflie_bridge {

std::optional<AttitudeBlock::Sample> AttitudeBlock::decode(const std::vector<double>& v, uint32_t timestamp_ms) {
  if (v.size() != 4 && v.size() != 7) return std::nullopt;
  for (double x : v) {
    if (!std::isfinite(x)) return std::nullopt;
  }
  if (v[0] < 0 || v[0] > 4294967295.0 || v[0] != std::floor(v[0])) return std::nullopt;
  Sample s;
  s.timestamp_ms = timestamp_ms;
  s.q = quatz::decompress(static_cast<uint32_t>(v[0]));
  // quatcompress only produces patterns whose three smaller components have
  // squares summing to <= 3/4; others (not from a firmware) decode to a
  // non-unit quaternion and are rejected.
  const double n2 = s.q.x * s.q.x + s.q.y * s.q.y + s.q.z * s.q.z + s.q.w * s.q.w;
  if (std::fabs(n2 - 1.0) > 1e-9) return std::nullopt;
  // stabilizer.c compressState(): rateRoll = gyro.x, ratePitch = -gyro.y,
  // rateYaw = gyro.z, each deg/s * (pi * 1000 / 180) -> mrad/s.
  s.rates[0] = v[1] * 1e-3;
  s.rates[1] = -v[2] * 1e-3;
  s.rates[2] = v[3] * 1e-3;
  if (v.size() == 7) {
    s.have_variances = true;
    for (int i = 0; i < 3; ++i) {
      if (v[4 + static_cast<size_t>(i)] < 0) return std::nullopt;
      s.position_variance[i] = v[4 + static_cast<size_t>(i)];
    }
  }
  return s;
}

}  // namespace crazyflie_bridge
