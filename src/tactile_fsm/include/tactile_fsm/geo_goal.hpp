// A WGS84 goal as a local ENU target (004: "position feedback is available
// (GPS or MoCap measurements)"), through GeographicLib's LocalCartesian.
#pragma once

#include <array>

namespace tactile_fsm {

/// ENU coordinates [m] of `point` {lat deg, lon deg, alt m} in the local
/// Cartesian frame at `origin` {lat deg, lon deg, alt m} (WGS84). Throws
/// std::invalid_argument naming the field for |lat| > 90, |lon| > 180 or
/// non-finite values.
std::array<double, 3> wgs84_to_enu(const std::array<double, 3>& origin, const std::array<double, 3>& point);

}  // namespace tactile_fsm
