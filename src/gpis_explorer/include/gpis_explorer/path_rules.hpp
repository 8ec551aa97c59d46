// The exploration sequencer's path rules: where a leg, a slide, a retreat or an
// approach may go, decided on what is known (workspace rules; 000 gives the
// corner penalty, eq. 45, and "discourage entry into concave, high-risk areas",
// but no path rule). The whiskers see only what is ahead within +-2.5 cm of the
// axis and the guard is 16 cm wide: walls met at grazing incidence or wall ends
// beside the axis are not felt before the guard, so the legs keep away from what
// was touched before.
//
// The map the rules read: the GPIS training points labelled surface (0), the
// corner centroids kept away from, and the wall lines of earlier wall follows.
// PathRules holds references only (build one per question, as the sequencer
// does): every rule is a pure function of that map and its arguments, unit
// tested on hand-made maps (test_path_rules.cpp). The numbers are
// SequencerParams' (see its comments for each one's origin).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "gpis_explorer/explorer.hpp"
#include "tactile_fsm/whisker_wall_follower.hpp"

namespace gpis_explorer {

struct SequencerParams;

/// Distance from c to the segment a-b.
double segment_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

/// Distance from the segment a-b to the nearest surface training point
/// (label 0) of g; infinity without one.
double surface_distance(const Gpis& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b);

/// A wall touched in a wall follow: the touched span's ends on its fitted line
/// (SequencerParams::wall_extension).
struct WallLine {
  Eigen::Vector2d a, b;
};

class PathRules {
 public:
  /// `explorer`: its training points (surface, label 0) and, for staging_for,
  /// its posterior mean and gradient (000 eq. 36) and grid; `corners`: the
  /// centroids kept away from (000 eq. 42-45); `walls`: wall lines.
  PathRules(const SequencerParams& p, const GpisExplorer& explorer, const std::vector<Eigen::Vector2d>& corners,
            const std::vector<WallLine>& walls)
      : p_(p), ex_(explorer), corners_(corners), walls_(walls) {}

  /// Distance from the segment a-b to the nearest known surface point (a == b: from a point).
  double surface_clearance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// q within explorer.corner_exclusion of a corner centroid.
  bool near_corner(const Eigen::Vector2d& q) const;
  /// The segment a-b keeps explorer.corner_exclusion from every corner
  /// centroid; from a start a already closer, it gets no closer.
  bool corner_clear(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// A wall follow's sideways slide toward `side` from pos (heading yaw) must
  /// stop: a known surface point within side_clearance beside the frame on
  /// that side (|forward| < side_clearance), or a wall line, extended by
  /// wall_extension, crossing the sideways ray within side_clearance (the
  /// frame has no side whiskers).
  bool side_blocked(const Eigen::Vector2d& pos, double yaw, tactile_fsm::Side side) const;
  /// A retreat (backward at retreat_speed for retreat_time_s + 5 cm, and
  /// sideways at `lateral` body-y speed) would bring the centre closer than
  /// retreat_clearance to a known surface point it is not already that close to.
  bool retreat_blocked(const Eigen::Vector2d& pos, double yaw, double lateral) const;
  /// q lies in the guard's corridor of a leg along `heading` from pos: at
  /// most 5 cm behind and within corridor_half_width of the axis.
  bool in_corridor(const Eigen::Vector2d& q, const Eigen::Vector2d& pos, double heading) const;
  /// Every known surface point lies at least exit_beyond behind pos along
  /// `heading` (flown through an opening of a convex room).
  bool beyond_known_surface(const Eigen::Vector2d& pos, double heading) const;
  /// The head-on approach of target q from `from`: the staging point
  /// approach_standoff inside q along the GPIS normal (grad f / |grad f|),
  /// inside the grid, not near a corner, on the interior side (mean < 0);
  /// leg 1 (from -> staging) keeps path_clearance from known surface points
  /// (or, from a start already closer, gets no closer), keeps clear of
  /// corners and stays on the interior side (mean < 0 every 0.1 m); leg 2
  /// (staging -> q, shortened by approach_clearance) keeps approach_clearance
  /// and clear of corners. False when any of these fails.
  bool staging_for(const Eigen::Vector2d& from, const Eigen::Vector2d& q, Eigen::Vector2d* staging,
                   double* approach_heading) const;

 private:
  const SequencerParams& p_;
  const GpisExplorer& ex_;
  const std::vector<Eigen::Vector2d>& corners_;
  const std::vector<WallLine>& walls_;
};

}  // namespace gpis_explorer
