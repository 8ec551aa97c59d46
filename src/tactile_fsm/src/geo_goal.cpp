#include "tactile_fsm/geo_goal.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tactile_fsm {
namespace {
void check(const char* name, const std::array<double, 3>& p) {
  for (double v : p)
    if (!std::isfinite(v)) throw std::invalid_argument(std::string(name) + ": must be finite");
  if (std::abs(p[0]) > 90.0) throw std::invalid_argument(std::string(name) + ".latitude: must be in [-90, 90] deg, got " + std::to_string(p[0]));
  if (std::abs(p[1]) > 180.0) throw std::invalid_argument(std::string(name) + ".longitude: must be in [-180, 180] deg, got " + std::to_string(p[1]));
}
}  // namespace

std::array<double, 3> wgs84_to_enu(const std::array<double, 3>& origin, const std::array<double, 3>& point) {
  check("origin", origin);
  check("point", point);
  const GeographicLib::LocalCartesian lc(origin[0], origin[1], origin[2]);  // WGS84 ellipsoid
  std::array<double, 3> enu{};
  lc.Forward(point[0], point[1], point[2], enu[0], enu[1], enu[2]);
  return enu;
}

}  // namespace tactile_fsm
