// The sequencer's path rules (PathRules) one by one on hand-made maps: a few
// surface (label 0) and interior (label -1) training points, corner centroids
// and wall lines placed by hand, SequencerParams' defaults unless a test says.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "gpis_explorer/path_rules.hpp"
#include "gpis_explorer/sequencer.hpp"

using gpis_explorer::GpisExplorer;
using gpis_explorer::PathRules;
using gpis_explorer::SequencerParams;
using gpis_explorer::WallLine;
using tactile_fsm::Side;
using V = Eigen::Vector2d;

namespace {

struct Map {
  SequencerParams p;
  GpisExplorer ex{SequencerParams{}.explorer};
  std::vector<V> corners;
  std::vector<WallLine> walls;
  void surface(const V& q) { ASSERT_EQ(ex.add_point(q, gpis_explorer::kSurfaceLabel), gpis_explorer::AddStatus::kAdded); }
  void interior(const V& q) { ASSERT_EQ(ex.add_point(q, gpis_explorer::kInteriorLabel), gpis_explorer::AddStatus::kAdded); }
  PathRules rules() const { return PathRules(p, ex, corners, walls); }
};

}  // namespace

// Distance of a segment (or a point) to the nearest surface point; interior
// points do not count; no surface point: infinity.
TEST(PathRules, SurfaceClearanceCountsSurfacePointsOnly) {
  Map m;
  EXPECT_TRUE(std::isinf(m.rules().surface_clearance({0, 0}, {2, 0})));
  m.surface({1.0, 0.3});
  m.interior({0.5, 0.05});
  EXPECT_NEAR(m.rules().surface_clearance({0, 0}, {2, 0}), 0.3, 1e-12);
  EXPECT_NEAR(m.rules().surface_clearance({0, 0}, {0, 0}), std::hypot(1.0, 0.3), 1e-12);
  EXPECT_NEAR(m.rules().surface_clearance({3, 0.3}, {4, 0.3}), 2.0, 1e-12);  // beyond the segment's end
}

// corner_exclusion (0.2 m) around each centroid: a point inside is near; a
// segment passing inside is not clear; from a start already inside, moving
// away is clear, moving closer is not.
TEST(PathRules, CornersKeepTheirExclusion) {
  Map m;
  const double e = m.p.explorer.corner_exclusion;
  m.corners = {{1.0, 0.0}};
  const PathRules r = m.rules();
  EXPECT_TRUE(r.near_corner({1.0, e - 0.01}));
  EXPECT_FALSE(r.near_corner({1.0, e + 0.01}));
  EXPECT_TRUE(r.corner_clear({0.0, e + 0.01}, {2.0, e + 0.01}));
  EXPECT_FALSE(r.corner_clear({0.0, e - 0.01}, {2.0, e - 0.01}));
  EXPECT_TRUE(r.corner_clear({1.0, 0.5 * e}, {1.0, 0.8 * e}));   // away from it
  EXPECT_FALSE(r.corner_clear({1.0, 0.5 * e}, {1.0, 0.3 * e}));  // closer
}

// A slide to the left (+y at yaw 0) stops for a surface point within
// side_clearance (0.25 m) to the left and within +-side_clearance ahead/behind;
// one further ahead, or on the right, does not stop it.
TEST(PathRules, SideBlockedByAKnownPointBesideTheFrame) {
  Map m;
  m.surface({0.05, 0.2});
  EXPECT_TRUE(m.rules().side_blocked({0, 0}, 0.0, Side::kLeft));
  EXPECT_FALSE(m.rules().side_blocked({0, 0}, 0.0, Side::kRight));
  Map ahead;
  ahead.surface({0.3, 0.2});
  EXPECT_FALSE(ahead.rules().side_blocked({0, 0}, 0.0, Side::kLeft));
  // Turned by 90 deg the frame's left is -x.
  Map turned;
  turned.surface({-0.2, 0.05});
  EXPECT_TRUE(turned.rules().side_blocked({0, 0}, M_PI / 2, Side::kLeft));
  EXPECT_FALSE(turned.rules().side_blocked({0, 0}, M_PI / 2, Side::kRight));
}

// A wall line touched 1.0-1.2 m along x at y = -0.2: extended by
// wall_extension (3 m) it crosses the right slide's ray 0.2 m from the centre
// (< side_clearance): blocked; not extended far enough (0.5 m), or off, it does not.
TEST(PathRules, SideBlockedByAnExtendedWallLine) {
  Map m;
  m.walls = {{{1.0, -0.2}, {1.2, -0.2}}};
  EXPECT_TRUE(m.rules().side_blocked({0, 0}, 0.0, Side::kRight));
  EXPECT_FALSE(m.rules().side_blocked({0, 0}, 0.0, Side::kLeft));
  m.p.wall_extension = 0.5;
  EXPECT_FALSE(m.rules().side_blocked({0, 0}, 0.0, Side::kRight));
  m.p.wall_extension = 0.0;
  EXPECT_FALSE(m.rules().side_blocked({0, 0}, 0.0, Side::kRight));
}

// The retreat from the origin at yaw 0 ends at (-0.15, 0) (0.1 m/s for 1 s
// plus 5 cm) and sideways by lateral * retreat_time_s: blocked when that
// brings the centre within retreat_clearance (0.14 m) of a surface point it
// is not already that close to.
TEST(PathRules, RetreatBlockedByAPointBehind) {
  Map behind;
  behind.surface({-0.2, 0.05});  // 0.21 m now, 0.07 m from the end
  EXPECT_TRUE(behind.rules().retreat_blocked({0, 0}, 0.0, 0.0));
  EXPECT_FALSE(behind.rules().retreat_blocked({0, 0}, M_PI, 0.0));  // turned: the retreat goes away from it
  Map margin;  // 0.12 m from the end with the 5 cm margin, 0.17 m without it
  margin.surface({-0.27, 0.0});
  EXPECT_TRUE(margin.rules().retreat_blocked({0, 0}, 0.0, 0.0));
  Map far;
  far.surface({-0.2, 0.25});
  EXPECT_FALSE(far.rules().retreat_blocked({0, 0}, 0.0, 0.0));
  Map beside;  // already 0.1 m away: the retreat gets no closer, not blocked
  beside.surface({0.0, 0.1});
  EXPECT_FALSE(beside.rules().retreat_blocked({0, 0}, 0.0, 0.0));
  Map side;  // 0.25 m from the straight end, 0.05 m from the end moved 0.2 m to the right
  side.surface({-0.15, -0.25});
  EXPECT_FALSE(side.rules().retreat_blocked({0, 0}, 0.0, 0.0));
  EXPECT_TRUE(side.rules().retreat_blocked({0, 0}, 0.0, -0.2));
}

// The guard's corridor: within corridor_half_width (0.11 m) of the leg's axis,
// from 5 cm behind the centre on.
TEST(PathRules, CorridorIsTheGuardsWidthAhead) {
  Map m;
  const PathRules r = m.rules();
  EXPECT_TRUE(r.in_corridor({0.5, 0.10}, {0, 0}, 0.0));
  EXPECT_FALSE(r.in_corridor({0.5, 0.12}, {0, 0}, 0.0));
  EXPECT_FALSE(r.in_corridor({0.5, -0.12}, {0, 0}, 0.0));
  EXPECT_TRUE(r.in_corridor({-0.04, 0.0}, {0, 0}, 0.0));
  EXPECT_FALSE(r.in_corridor({-0.06, 0.0}, {0, 0}, 0.0));
  EXPECT_TRUE(r.in_corridor({1.1, 1.5}, {1, 1}, M_PI / 2));
  EXPECT_FALSE(r.in_corridor({1.5, 1.1}, {1, 1}, M_PI / 2));
}

// Through an opening: every surface point at least exit_beyond (0.3 m) behind
// the drone along the heading.
TEST(PathRules, BeyondKnownSurfaceOnlyPastEveryWall) {
  Map m;
  m.surface({0.0, 1.0});
  m.surface({0.0, -1.0});
  EXPECT_TRUE(m.rules().beyond_known_surface({0.5, 0.0}, 0.0));
  EXPECT_FALSE(m.rules().beyond_known_surface({0.2, 0.0}, 0.0));
  EXPECT_FALSE(m.rules().beyond_known_surface({0.5, 0.0}, M_PI));
  Map none;  // nothing touched: nothing ahead
  EXPECT_TRUE(none.rules().beyond_known_surface({0.0, 0.0}, 0.0));
}

namespace {
/// A wall of surface points at x = 1 (y = -0.6 .. 0.6), the interior at the
/// origin, fitted; `extra` surface points added before the fit.
void wall_ahead(Map& m, const std::vector<V>& extra) {
  m.ex.centre_grid(0.0, 0.0);
  for (int k = -3; k <= 3; ++k) m.surface({1.0, 0.2 * k});
  m.interior({0.0, 0.0});
  for (const auto& q : extra) m.surface(q);
  m.ex.update();
}
}  // namespace

// The head-on approach of the target (1, 0) on the wall: the staging point
// approach_standoff (0.4 m) inside along the GPIS normal, facing the normal.
// Leg 1 (origin -> staging, 0.4 m from the wall point (1, 0) at its end) is
// refused at path_clearance 0.45 m and taken at 0.35 m; for the target
// (1, -0.1), a surface point at (0.9, 0) about 0.1 m beside the head-on leg
// refuses it at approach_clearance 0.14 m and not at 0.05 m; a corner
// centroid at the staging point refuses it (through near_corner(staging) and
// corner_clear of leg 1 alike: either alone refuses this case).
TEST(PathRules, StagingPointInsideAlongTheNormalWithClearLegs) {
  Map m;
  wall_ahead(m, {});
  V s;
  double heading = NAN;
  ASSERT_TRUE(m.rules().staging_for({0, 0}, {1.0, 0.0}, &s, &heading));
  const V n = m.ex.gradient({1.0, 0.0}).normalized();
  EXPECT_LT((s - (V(1.0, 0.0) - m.p.approach_standoff * n)).norm(), 1e-12);
  EXPECT_NEAR(heading, std::atan2(n.y(), n.x()), 1e-12);
  EXPECT_NEAR(heading, 0.0, 0.05);  // the wall faces the origin
  EXPECT_NEAR(m.rules().surface_clearance({0, 0}, s), 0.4, 0.02);

  m.p.path_clearance = 0.45;
  EXPECT_FALSE(m.rules().staging_for({0, 0}, {1.0, 0.0}, &s, &heading));
  m.p.path_clearance = 0.35;
  EXPECT_TRUE(m.rules().staging_for({0, 0}, {1.0, 0.0}, &s, &heading));

  Map leg2;
  wall_ahead(leg2, {{0.9, 0.0}});
  EXPECT_FALSE(leg2.rules().staging_for({0, 0}, {1.0, -0.1}, &s, &heading));
  leg2.p.approach_clearance = 0.05;
  EXPECT_TRUE(leg2.rules().staging_for({0, 0}, {1.0, -0.1}, &s, &heading));

  Map corner;
  wall_ahead(corner, {});
  corner.corners = {{0.6, 0.0}};
  EXPECT_FALSE(corner.rules().staging_for({0, 0}, {1.0, 0.0}, &s, &heading));
}
