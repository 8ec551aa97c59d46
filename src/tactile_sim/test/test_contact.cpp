// Penalty contact of a circle with the arena: hand-computed forces from the
// built-in materials, friction bounds, episodes, corners, and a 1 kHz
// integration check.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_sim/contact.hpp"

using tactile_sim::Arena;
using tactile_sim::CircleContact;
using tactile_sim::ContactParams;
using tactile_sim::ContactResult;
using tactile_sim::Vec2;

namespace {

// Wall along y at x = 1 (rigid unless given).
Arena wall_arena(const std::string& material = "rigid") {
  return Arena::from_yaml_text("walls:\n  - points: [[1, -2], [1, 2]]\n    material: " + material + "\n",
                               "t.yaml");
}

}  // namespace

TEST(Contact, StaticPenetrationGivesStiffnessTimesDepth) {
  const Arena a = wall_arena();
  const auto& m = a.material(0);
  CircleContact c;
  // Centre 0.95, radius 0.06: 0.01 m into the wall at x = 1.
  const ContactResult r = c.step(a, {0.95, 0.3}, 0.06, Vec2::Zero());
  ASSERT_TRUE(r.contact);
  EXPECT_NEAR(r.penetration, 0.01, 1e-12);
  EXPECT_NEAR(r.normal_force, m.stiffness * 0.01, 1e-9);
  EXPECT_TRUE(r.force.isApprox(Vec2(-m.stiffness * 0.01, 0.0), 1e-12));
  EXPECT_TRUE(r.normal.isApprox(Vec2(-1, 0)));
  EXPECT_TRUE(r.point.isApprox(Vec2(1, 0.3)));
  EXPECT_EQ(r.obstacle_id, 0);
  EXPECT_EQ(r.friction_force, 0.0);
  EXPECT_EQ(r.count, 1);
}

TEST(Contact, TextileIsSofterThanRigid) {
  const Arena rigid = wall_arena("rigid"), textile = wall_arena("textile");
  CircleContact c1, c2;
  const double f_rigid = c1.step(rigid, {0.95, 0}, 0.06, Vec2::Zero()).normal_force;
  const double f_textile = c2.step(textile, {0.95, 0}, 0.06, Vec2::Zero()).normal_force;
  EXPECT_NEAR(f_textile, textile.material(2).stiffness * 0.01, 1e-9);
  EXPECT_LT(f_textile, f_rigid);
}

TEST(Contact, DampingAddsOnApproachAndNeverPulls) {
  const Arena a = wall_arena();
  const auto& m = a.material(0);
  CircleContact c;
  // Moving into the wall at 0.1 m/s: k x + c v.
  ContactResult r = c.step(a, {0.95, 0}, 0.06, {0.1, 0});
  EXPECT_NEAR(r.normal_force, m.stiffness * 0.01 + m.damping * 0.1, 1e-9);
  EXPECT_NEAR(r.impact_speed, 0.1, 1e-12);
  // Leaving fast with a small penetration: k x - c v < 0 -> clamped to 0.
  r = c.step(a, {0.9405, 0}, 0.06, {-1.0, 0});  // 0.5 mm in: 1.5 N - 6 N
  EXPECT_TRUE(r.contact);
  EXPECT_EQ(r.normal_force, 0.0);
  EXPECT_TRUE(r.force.isZero());
}

TEST(Contact, NoForceWithoutContact) {
  const Arena a = wall_arena();
  CircleContact c;
  const ContactResult r = c.step(a, {0.5, 0}, 0.06, {0.3, 0.2});
  EXPECT_FALSE(r.contact);
  EXPECT_FALSE(r.began);
  EXPECT_TRUE(r.force.isZero());
  EXPECT_EQ(r.obstacle_id, -1);
  // Beyond the wall's end (y > 2) nothing either.
  EXPECT_FALSE(c.step(a, {1.0, 2.1}, 0.06, Vec2::Zero()).contact);
}

TEST(Contact, FrictionOpposesSlidingAndIsBoundedByMuN) {
  const Arena a = wall_arena();
  const auto& m = a.material(0);
  ContactParams p;
  CircleContact c(p);
  const double n = m.stiffness * 0.01;
  // Fast slide +y: full Coulomb friction mu N along -y.
  ContactResult r = c.step(a, {0.95, 0}, 0.06, {0, 0.5});
  EXPECT_NEAR(r.force.y(), -m.friction * n, 1e-9);
  EXPECT_NEAR(r.force.x(), -n, 1e-9);
  EXPECT_NEAR(r.friction_force, m.friction * n, 1e-9);
  // Slide -y: sign flips.
  r = c.step(a, {0.95, 0}, 0.06, {0, -0.5});
  EXPECT_NEAR(r.force.y(), m.friction * n, 1e-9);
  // Below the regularisation speed: linear in the speed, below mu N.
  r = c.step(a, {0.95, 0}, 0.06, {0, 0.25 * p.friction_slip_speed});
  EXPECT_NEAR(r.force.y(), -0.25 * m.friction * n, 1e-9);
  // At rest: none.
  r = c.step(a, {0.95, 0}, 0.06, Vec2::Zero());
  EXPECT_EQ(r.force.y(), 0.0);
  // Bounded for every speed and direction.
  for (double s : {1e-6, 0.001, 0.01, 0.02, 0.1, 1.0, 10.0}) {
    for (double ang : {0.3, 1.2, 2.5, -2.0}) {
      const Vec2 v(0.2 * std::cos(ang), s * std::sin(ang));
      r = c.step(a, {0.95, 0}, 0.06, v);
      EXPECT_LE(r.friction_force, m.friction * r.normal_force * (1 + 1e-12));
      EXPECT_LE(r.force.y() * v.y(), 0.0);  // opposes the tangential velocity
    }
  }
}

TEST(Contact, ImpactFlaggedOncePerEpisode) {
  const Arena a = wall_arena();
  CircleContact c;  // release gap 2 mm
  const double r = 0.06;
  EXPECT_FALSE(c.step(a, {0.93, 0}, r, {0.2, 0}).began);         // 1 cm gap
  ContactResult hit = c.step(a, {0.945, 0}, r, {0.2, 0});         // 5 mm in
  EXPECT_TRUE(hit.began);
  EXPECT_NEAR(hit.impact_speed, 0.2, 1e-12);
  EXPECT_FALSE(c.step(a, {0.947, 0}, r, {0.1, 0}).began);         // still in
  EXPECT_FALSE(c.step(a, {0.939, 0}, r, {-0.1, 0}).contact);      // 1 mm gap: chatter
  EXPECT_FALSE(c.step(a, {0.9405, 0}, r, {0.1, 0}).began);        // back in: same episode
  EXPECT_TRUE(c.in_episode());
  EXPECT_FALSE(c.step(a, {0.9, 0}, r, {-0.2, 0}).contact);         // 4 cm away: episode over
  EXPECT_FALSE(c.in_episode());
  EXPECT_TRUE(c.step(a, {0.945, 0}, r, {0.2, 0}).began);          // new impact
  c.reset();
  EXPECT_TRUE(c.step(a, {0.945, 0}, r, Vec2::Zero()).began);
}

TEST(Contact, ConcaveCornerPushesFromBothWallsConvexVertexOnce) {
  // Room corner at (1, 1): both walls push.
  const Arena room = Arena::from_yaml_text("rooms:\n  - {center: [0, 0], size: [2, 2]}\n", "t.yaml");
  CircleContact c;
  const double k = room.material(0).stiffness;
  ContactResult r = c.step(room, {0.96, 0.97}, 0.05, Vec2::Zero());
  EXPECT_EQ(r.count, 2);
  EXPECT_NEAR(r.force.x(), -k * 0.01, 1e-9);
  EXPECT_NEAR(r.force.y(), -k * 0.02, 1e-9);
  // Outside a box's corner: both edges report the vertex; one force of k * depth.
  const Arena box = Arena::from_yaml_text("boxes:\n  - {center: [0, 0], size: [2, 2]}\n", "t.yaml");
  CircleContact c2;
  const Vec2 centre = Vec2(1, 1) + 0.04 * Vec2(1, 1).normalized();
  r = c2.step(box, centre, 0.05, Vec2::Zero());
  EXPECT_EQ(r.count, 1);
  EXPECT_NEAR(r.normal_force, box.material(0).stiffness * 0.01, 1e-9);
  EXPECT_TRUE(r.normal.isApprox(Vec2(1, 1).normalized(), 1e-12));
}

TEST(Contact, CylinderNormalIsRadial) {
  const Arena a = Arena::from_yaml_text("cylinders:\n  - {center: [0, 0], radius: 0.15}\n", "t.yaml");
  CircleContact c;
  // Circle of radius 0.05 at distance 0.19 from the centre along (0.6, 0.8): 0.01 deep.
  const ContactResult r = c.step(a, 0.19 * Vec2(0.6, 0.8), 0.05, Vec2::Zero());
  ASSERT_TRUE(r.contact);
  EXPECT_NEAR(r.penetration, 0.01, 1e-12);
  EXPECT_TRUE(r.normal.isApprox(Vec2(0.6, 0.8), 1e-12));
  EXPECT_TRUE(r.point.isApprox(0.15 * Vec2(0.6, 0.8), 1e-12));
}

TEST(Contact, ThinWallCrossingKeepsTheSideItCameFrom) {
  const Arena a = wall_arena();
  CircleContact c;
  const double k = a.material(0).stiffness;
  c.step(a, {0.97, 0}, 0.06, {0.5, 0});
  // The centre is now 1 cm past the wall: the force still pushes back (-x)
  // with depth r + d = 0.07.
  const ContactResult r = c.step(a, {1.01, 0}, 0.06, Vec2::Zero());
  ASSERT_TRUE(r.contact);
  EXPECT_NEAR(r.penetration, 0.07, 1e-12);
  EXPECT_NEAR(r.force.x(), -k * 0.07, 1e-9);
}

TEST(Contact, OneKilohertzIntegrationIsStable) {
  // A 44 g body (whiskered Crazyflie) pressed against the wall by 0.5 N while
  // sliding at 0.3 m/s, semi-implicit Euler at 1 kHz: it must come to rest in
  // contact, the normal force settling at 0.5 N, without oscillation growth.
  const Arena a = wall_arena();
  CircleContact c;
  const double m = 0.044, dt = 1e-3, r = 0.06;
  Vec2 x(1.0 - r + 0.5 / a.material(0).stiffness, 0.0), v(0.0, 0.3);
  int impacts = 0;
  double max_speed_late = 0;
  ContactResult res;
  for (int i = 0; i < 3000; ++i) {
    res = c.step(a, x, r, v);
    impacts += res.began;
    const Vec2 f = res.force + Vec2(0.5, 0.0);
    v += dt * f / m;
    x += dt * v;
    ASSERT_TRUE(x.allFinite());
    if (i > 2000) max_speed_late = std::max(max_speed_late, v.norm());
  }
  EXPECT_EQ(impacts, 1);
  EXPECT_LT(max_speed_late, 1e-3);
  EXPECT_NEAR(res.normal_force, 0.5, 1e-3);
  EXPECT_NEAR(res.penetration, 0.5 / a.material(0).stiffness, 1e-6);
  // Coulomb: it stopped within the distance a constant mu N deceleration
  // allows (plus the regularisation's slow tail).
  const double mu_n = a.material(0).friction * 0.5;
  EXPECT_LT(x.y(), 0.3 * 0.3 / (2 * mu_n / m) + 0.01);
}

TEST(Contact, BounceLosesEnergy) {
  // Free 44 g body hitting the wall at 0.5 m/s: it leaves slower (damping),
  // in one impact, and the peak force stays finite.
  const Arena a = wall_arena();
  CircleContact c;
  const double m = 0.044, dt = 1e-3, r = 0.06;
  Vec2 x(0.9, 0.0), v(0.5, 0.0);
  int impacts = 0;
  for (int i = 0; i < 1000; ++i) {
    const ContactResult res = c.step(a, x, r, v);
    impacts += res.began;
    v += dt * res.force / m;
    x += dt * v;
  }
  EXPECT_EQ(impacts, 1);
  EXPECT_LT(v.x(), 0.0);
  EXPECT_GT(v.x(), -0.5);
  EXPECT_LT(x.x(), 0.94);
}

TEST(Contact, ParamsValidate) {
  ContactParams p;
  p.friction_slip_speed = 0.0;
  EXPECT_THROW(CircleContact{p}, std::invalid_argument);
  p = ContactParams{};
  p.release_gap = -1;
  EXPECT_THROW(CircleContact{p}, std::invalid_argument);
}
