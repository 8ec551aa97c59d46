// Path rules of the exploration sequencer. See path_rules.hpp.
#include "gpis_explorer/path_rules.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gpis_explorer/sequencer.hpp"

namespace gpis_explorer {

double segment_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((c - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - c).norm();
}

double surface_distance(const Gpis& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.label(i) == kSurfaceLabel) best = std::min(best, segment_distance(a, b, g.point(i)));
  }
  return best;
}

bool PathRules::near_corner(const Eigen::Vector2d& q) const {
  for (const auto& c : corners_) {
    if ((q - c).norm() < p_.explorer.corner_exclusion) return true;
  }
  return false;
}

bool PathRules::side_blocked(const Eigen::Vector2d& pos, double yaw, tactile_fsm::Side side) const {
  const double s = side == tactile_fsm::Side::kLeft ? 1.0 : -1.0;
  const Eigen::Vector2d fx(std::cos(yaw), std::sin(yaw)), fy(-std::sin(yaw), std::cos(yaw));
  const Gpis& g = ex_.gpis();
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.label(i) != kSurfaceLabel) continue;
    const Eigen::Vector2d d = g.point(i) - pos;
    const double lateral = s * d.dot(fy), forward = d.dot(fx);
    if (lateral > 0.0 && lateral < p_.side_clearance && std::abs(forward) < p_.side_clearance) return true;
  }
  if (p_.wall_extension <= 0.0) return false;
  for (const auto& w : walls_) {
    if (ray_to_wall_line(pos, s * fy, w.a, w.b, p_.wall_extension) < p_.side_clearance) return true;
  }
  return false;
}

double PathRules::surface_clearance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  return surface_distance(ex_.gpis(), a, b);
}

bool PathRules::corner_clear(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  // Keep corner_exclusion from every corner centroid (000 eq. 45 region); from
  // a start already closer than that, do not get any closer.
  for (const auto& c : corners_) {
    const double limit = std::min(p_.explorer.corner_exclusion, (a - c).norm() - 1e-3);
    if (segment_distance(a, b, c) < limit) return false;
  }
  return true;
}

bool PathRules::staging_for(const Eigen::Vector2d& from, const Eigen::Vector2d& q, Eigen::Vector2d* staging,
                            double* approach_heading) const {
  // Outward normal of the implicit surface at the target: the mean grows from
  // -1 (interior) to 0 (surface), so grad f (000 eq. 36) points out of the room.
  const GpisExplorer& g = ex_;  // the solver's mean and gradient (exact or local)
  const Eigen::Vector2d grad = g.gradient(q);
  if (!(grad.allFinite() && grad.norm() > 1e-9)) return false;
  const Eigen::Vector2d n = grad.normalized();
  const Eigen::Vector2d s = q - p_.approach_standoff * n;
  if (!ex_.grid().contains(s) || near_corner(s)) return false;
  if (!(g.mean(s) < 0.0)) return false;  // the staging point must be on the interior side
  // Leg 1 (from -> staging): clear of known surface points and corners, and
  // not through the predicted surface (mean < 0 along it).
  const double d0 = surface_clearance(from, from);
  if (surface_clearance(from, s) < std::min(p_.path_clearance, d0 - 1e-3)) return false;
  if (!corner_clear(from, s)) return false;
  const int samples = std::max(2, static_cast<int>(std::ceil((s - from).norm() / 0.1)));
  for (int k = 1; k <= samples; ++k) {
    if (!(g.mean(from + (s - from) * (static_cast<double>(k) / samples)) < 0.0)) return false;
  }
  // Leg 2 (staging -> target, head-on): no known surface point beside it.
  const Eigen::Vector2d q_short = q - std::min(p_.approach_clearance, p_.approach_standoff) * n;
  if (surface_clearance(s, q_short) < p_.approach_clearance) return false;
  if (!corner_clear(s, q)) return false;
  *staging = s;
  *approach_heading = std::atan2(n.y(), n.x());
  return true;
}

bool PathRules::beyond_known_surface(const Eigen::Vector2d& pos, double heading) const {
  // Flown through an opening: every known surface point lies at least
  // exit_beyond behind the drone along the leg's heading (a convex room's
  // walls all end at the exit's wall line). A contour point inside a large
  // room (few points, the GPIS contour well inside the walls) followed by
  // exit_confirm_distance of free flight is not yet an exit.
  const Eigen::Vector2d h(std::cos(heading), std::sin(heading));
  const Gpis& g = ex_.gpis();
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.label(i) == kSurfaceLabel && (g.point(i) - pos).dot(h) > -p_.exit_beyond) return false;
  }
  return true;
}

bool PathRules::retreat_blocked(const Eigen::Vector2d& pos, double yaw, double lateral) const {
  // The backward leg (retreat_speed for what is left of retreat_time_s plus a
  // margin) must not bring the centre closer than retreat_clearance to a known
  // surface point it is not already that close to.
  const Eigen::Vector2d back(-std::cos(yaw), -std::sin(yaw));
  const Eigen::Vector2d side(-std::sin(yaw), std::cos(yaw));
  // ... and sideways as far as the retreat would move (retreat_toward_follow_start).
  const Eigen::Vector2d end =
      pos + back * (p_.retreat_speed * p_.retreat_time_s + 0.05) + side * (lateral * p_.retreat_time_s);
  const Gpis& g = ex_.gpis();
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.label(i) != kSurfaceLabel) continue;
    const Eigen::Vector2d q = g.point(i);
    const double now = (q - pos).norm();
    if (segment_distance(pos, end, q) < std::min(p_.retreat_clearance, now - 1e-3)) return true;
  }
  return false;
}

bool PathRules::in_corridor(const Eigen::Vector2d& q, const Eigen::Vector2d& pos, double heading) const {
  const Eigen::Vector2d h(std::cos(heading), std::sin(heading)), n(-h.y(), h.x());
  const Eigen::Vector2d d = q - pos;
  return d.dot(h) > -0.05 && std::abs(d.dot(n)) < p_.corridor_half_width;
}

}  // namespace gpis_explorer
