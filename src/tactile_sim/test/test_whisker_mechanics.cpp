// Whisker PRBM (000 eq. S1-S10) against hand computation, the Fig. S2b trend,
// and the contact geometry in the plane.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tactile_sim/whisker_mechanics.hpp"

namespace tactile_sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Reference values computed by hand (independent Python script, E = 75 GPa,
// d_w = 0.4 mm, l_o = 0.2 m, alpha = 45 deg, d = 0.05 m):
//   P_c = (0.2 - 0.05 cos45, 0.05 sin45) = (0.1646447, 0.0353553)      S3
//   theta = atan(0.0353553 / 0.1646447) = 0.2115250 rad                 S6
//   n = tan(1.5 theta) = 0.3293..., gamma = 0.839470                    S2, S7
//   K = 1.041023e-3 N m/rad                                             S8
//   F = 1.249342e-3 N                                                   S1
//   N = F / sin(1.5 theta + alpha) = 1.399945e-3 N                      S10
//   M = N * 0.2 sin45 = 1.979791e-4 N m
TEST(WhiskerPrbm, MatchesHandComputationAt45Deg5cm) {
  WhiskerParams p;
  const PrbmState s = prbm_contact(p, 0.05);
  EXPECT_NEAR(s.px, 0.2 - 0.05 * std::cos(45 * kDeg), 1e-12);
  EXPECT_NEAR(s.py, 0.05 * std::sin(45 * kDeg), 1e-12);
  EXPECT_NEAR(s.theta, 0.21152499, 1e-7);
  EXPECT_NEAR(s.beta, 1.5 * 0.21152499, 1e-7);
  EXPECT_NEAR(s.n, std::tan(1.5 * 0.21152499), 1e-7);
  EXPECT_NEAR(s.gamma, 0.841655 - 0.0067807 * s.n + 0.000438 * s.n * s.n, 1e-12);
  EXPECT_NEAR(s.spring_k, 1.0410230e-3, 1e-9);
  EXPECT_NEAR(s.force_f, 1.2493419e-3, 1e-9);
  EXPECT_NEAR(s.normal_force, 1.3999446e-3, 1e-9);
  EXPECT_NEAR(s.base_moment, 1.3999446e-3 * 0.2 * std::sin(45 * kDeg), 1e-10);
}

// S9 written out (F = E I poly theta gamma^2 / (|P_c|^2 (cos theta + n sin theta)))
// must agree with S1 + S8 for any alpha, d.
TEST(WhiskerPrbm, S1WithS8EqualsS9ClosedForm) {
  for (double alpha_deg : {10.0, 30.0, 45.0, 70.0}) {
    for (double d : {0.005, 0.02, 0.06}) {
      WhiskerParams p;
      p.placement_angle = alpha_deg * kDeg;
      const PrbmState s = prbm_contact(p, d);
      const double a = p.placement_angle;
      const double px = 0.2 - d * std::cos(a), py = d * std::sin(a);
      const double th = std::atan(py / px);
      const double n = std::tan(1.5 * th);
      const double g = 0.841655 - 0.0067807 * n + 0.000438 * n * n;
      const double poly = 2.654855 - 0.0509896 * n + 0.0126749 * n * n -
                          0.00142039 * n * n * n + 0.0000584525 * n * n * n * n;
      const double ei = 75e9 * M_PI * std::pow(0.4e-3, 4) / 64.0;
      const double f = ei * poly * th * g * g / ((px * px + py * py) *
                                                 (std::cos(th) + n * std::sin(th)));
      EXPECT_NEAR(s.force_f, f, 1e-12 + 1e-9 * f) << alpha_deg << " " << d;
      EXPECT_NEAR(s.normal_force, f / std::sin(1.5 * th + a), 1e-12) << alpha_deg << " " << d;
    }
  }
}

TEST(WhiskerPrbm, SecondMomentAndReach) {
  WhiskerParams p;
  EXPECT_NEAR(p.second_moment(), M_PI * 2.56e-14 / 64.0, 1e-22);
  EXPECT_NEAR(p.horizontal_reach(), 0.2 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p.contact_height(), 0.2 * std::sqrt(0.5), 1e-12);
}

TEST(WhiskerPrbm, ZeroDepthGivesNoForce) {
  WhiskerParams p;
  const PrbmState s = prbm_contact(p, 0.0);
  EXPECT_EQ(s.normal_force, 0.0);
  EXPECT_EQ(s.base_moment, 0.0);
  EXPECT_EQ(prbm_contact(p, -0.01).normal_force, 0.0);
}

// 000 Fig. S2b: at equal contact depth the normal force falls as the
// placement angle increases.
TEST(WhiskerPrbm, NormalForceFallsWithPlacementAngle) {
  for (double d : {0.01, 0.03, 0.05}) {
    double prev = INFINITY;
    for (double alpha_deg : {5.0, 15.0, 30.0, 45.0, 60.0, 75.0}) {
      WhiskerParams p;
      p.placement_angle = alpha_deg * kDeg;
      const double n = prbm_contact(p, d).normal_force;
      EXPECT_GT(n, 0.0);
      EXPECT_LT(n, prev) << "d=" << d << " alpha=" << alpha_deg;
      prev = n;
    }
  }
  // And the decrease flattens beyond 45 deg (000 Fig. S2b reference plane).
  WhiskerParams p15, p45, p75;
  p15.placement_angle = 15 * kDeg;
  p45.placement_angle = 45 * kDeg;
  p75.placement_angle = 75 * kDeg;
  const double d = 0.05;
  const double drop_15_45 = prbm_contact(p15, d).normal_force - prbm_contact(p45, d).normal_force;
  const double drop_45_75 = prbm_contact(p45, d).normal_force - prbm_contact(p75, d).normal_force;
  EXPECT_GT(drop_15_45, drop_45_75);
}

TEST(WhiskerPrbm, ForceAndMomentGrowWithDepth) {
  WhiskerParams p;
  // Monotone up to d ~ 0.12 m (depth ~ 21 mm at 45 deg); beyond it the eq. S6
  // angle approaches atan(cot alpha) and N flattens and falls slightly. The
  // propeller guard reaches the wall before that (docs/physics.md).
  double prev_n = 0.0, prev_m = 0.0;
  for (double d = 0.005; d < 0.116; d += 0.01) {
    const PrbmState s = prbm_contact(p, d);
    EXPECT_GT(s.normal_force, prev_n) << d;
    EXPECT_GT(s.base_moment, prev_m) << d;
    prev_n = s.normal_force;
    prev_m = s.base_moment;
  }
  // Milli-newton forces as in 000 ("only milli-Newton forces").
  EXPECT_LT(prbm_contact(p, 0.10).normal_force, 0.02);
}

TEST(WhiskerContact, WallStraightAheadGeometry) {
  WhiskerParams p;
  const Vec2 base(1.0, 2.0), fwd(1.0, 0.0);
  const double depth = 0.08;
  const WhiskerContact c =
      whisker_contact(p, base, fwd, Vec2::Zero(), true, depth, base + depth * fwd,
                      Vec2(-1.0, 0.0), 0.3, 7);
  ASSERT_TRUE(c.contact);
  EXPECT_DOUBLE_EQ(c.depth, depth);
  EXPECT_NEAR(c.deflection, p.horizontal_reach() - depth, 1e-12);
  EXPECT_NEAR(c.normal_force, prbm_contact(p, p.horizontal_reach() - depth).normal_force, 1e-15);
  EXPECT_GT(c.base_moment, 0.0);
  EXPECT_EQ(c.friction_force, 0.0);  // not sliding
  EXPECT_NEAR(c.force_on_body.x(), -c.normal_force, 1e-15);
  EXPECT_NEAR(c.force_on_body.y(), 0.0, 1e-15);
  EXPECT_EQ(c.obstacle_id, 7);
  EXPECT_NEAR((c.tip - base).norm(), p.horizontal_reach(), 1e-12);
}

TEST(WhiskerContact, SlidingFrictionIsMuTimesNormalAgainstMotion) {
  WhiskerParams p;
  const Vec2 base(0.0, 0.0), fwd(1.0, 0.0), n(-1.0, 0.0);
  const WhiskerContact c = whisker_contact(p, base, fwd, Vec2(0.0, 0.2), true, 0.07,
                                           Vec2(0.07, 0.0), n, 0.4, 0);
  ASSERT_TRUE(c.contact);
  EXPECT_NEAR(c.friction_force, 0.4 * c.normal_force, 1e-15);
  EXPECT_LT(c.force_on_body.y(), 0.0);  // drags against +y motion
  EXPECT_NEAR(c.force_on_body.y(), -0.4 * c.normal_force, 1e-15);
}

TEST(WhiskerContact, ObliqueWallUsesNormalPenetration) {
  WhiskerParams p;
  const double phi = 30 * kDeg;
  const Vec2 n(-std::cos(phi), std::sin(phi));
  const WhiskerContact c = whisker_contact(p, Vec2::Zero(), Vec2(1, 0), Vec2::Zero(), true, 0.06,
                                           Vec2(0.06, 0.0), n, 0.3, 1);
  EXPECT_NEAR(c.deflection, (p.horizontal_reach() - 0.06) * std::cos(phi), 1e-12);
  EXPECT_DOUBLE_EQ(c.depth, 0.06);
}

TEST(WhiskerContact, NoContactBeyondReach) {
  WhiskerParams p;
  const WhiskerContact miss = whisker_contact(p, Vec2::Zero(), Vec2(1, 0), Vec2::Zero(), true,
                                              p.horizontal_reach() + 1e-6, Vec2::Zero(),
                                              Vec2(-1, 0), 0.3, 1);
  EXPECT_FALSE(miss.contact);
  EXPECT_TRUE(std::isnan(miss.depth));
  EXPECT_EQ(miss.base_moment, 0.0);
  const WhiskerContact none = whisker_contact(p, Vec2::Zero(), Vec2(1, 0), Vec2::Zero(), false,
                                              0.0, Vec2::Zero(), Vec2::Zero(), 0.3, -1);
  EXPECT_FALSE(none.contact);
  EXPECT_EQ(none.force_on_body, Vec2::Zero());
}

TEST(WhiskerParams, ValidateRejectsBadValues) {
  WhiskerParams p;
  EXPECT_NO_THROW(p.validate());
  p.placement_angle = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = WhiskerParams{};
  p.youngs_modulus = -1.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("youngs_modulus"), std::string::npos);
  }
  p = WhiskerParams{};
  p.length = NAN;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// ----------------------------------------------------------------- stick-slip

TEST(WhiskerStickSlip, ProfileIsASawtoothPerCycle) {
  const double L = 0.0015;
  const uint64_t seed = 42;
  for (int cycle = -3; cycle < 20; ++cycle) {
    // Within a cycle: linear in the phase, from -a to +a, a in [0.5, 1).
    const double u0 = cycle * L;
    const double lo = tactile_sim::stick_slip_profile(u0 + 1e-9 * L, L, seed, 2);
    const double mid = tactile_sim::stick_slip_profile(u0 + 0.5 * L, L, seed, 2);
    const double q = tactile_sim::stick_slip_profile(u0 + 0.75 * L, L, seed, 2);
    const double a = -lo;
    EXPECT_GE(a, 0.5 - 1e-6) << cycle;
    EXPECT_LT(a, 1.0) << cycle;
    EXPECT_NEAR(mid, 0.0, 1e-9) << cycle;
    EXPECT_NEAR(q, 0.5 * a, 1e-9) << cycle;  // a (2 * 0.75 - 1)
    // The slip: the load drops from +a to the next cycle's -a'.
    const double before = tactile_sim::stick_slip_profile(u0 + L * (1.0 - 1e-9), L, seed, 2);
    EXPECT_NEAR(before, a, 1e-6) << cycle;
  }
  // Deterministic; other obstacles / seeds give other amplitudes.
  EXPECT_EQ(tactile_sim::stick_slip_profile(0.0101, L, seed, 2), tactile_sim::stick_slip_profile(0.0101, L, seed, 2));
  EXPECT_NE(tactile_sim::stick_slip_profile(0.0101, L, seed, 2), tactile_sim::stick_slip_profile(0.0101, L, seed, 3));
  EXPECT_NE(tactile_sim::stick_slip_profile(0.0101, L, seed, 2), tactile_sim::stick_slip_profile(0.0101, L, seed + 1, 2));
  // Bad input gives no fluctuation.
  EXPECT_EQ(tactile_sim::stick_slip_profile(std::nan(""), L, seed, 2), 0.0);
  EXPECT_EQ(tactile_sim::stick_slip_profile(0.01, 0.0, seed, 2), 0.0);
}

TEST(WhiskerStickSlip, ProfileHasZeroMeanAlongTheWall) {
  // Each cycle integrates to zero, so the mean over whole cycles is 0.
  const double L = 0.0015;
  double sum = 0.0;
  const int n = 200000;  // 100 cycles, 2000 samples each
  for (int i = 0; i < n; ++i) sum += tactile_sim::stick_slip_profile((i + 0.5) * 100 * L / n, L, 7, 0);
  EXPECT_NEAR(sum / n, 0.0, 1e-9);
}

TEST(WhiskerStickSlip, MomentIsGainMuNLoTimesSlipTimesProfile) {
  WhiskerParams p;
  const Vec2 base(0.0, 0.0), fwd(1.0, 0.0), n(-1.0, 0.0);
  const double mu = 0.4;
  const Vec2 hit(0.07, 0.0123);
  // Full slip (|v_t| >= eps): moment = gain * mu * N * l_o sin(alpha) * profile(u), u = hit . tangent.
  const WhiskerContact c = whisker_contact(p, base, fwd, Vec2(0.0, 0.2), true, 0.07, hit, n, mu, 1);
  ASSERT_TRUE(c.contact);
  const Vec2 tangent(-n.y(), n.x());
  const double expected = p.stick_slip_gain * mu * c.normal_force * p.contact_height() *
                          tactile_sim::stick_slip_profile(hit.dot(tangent), p.stick_slip_length, p.stick_slip_seed, 1);
  EXPECT_NEAR(c.stick_slip_moment, expected, 1e-15);
  EXPECT_NE(c.stick_slip_moment, 0.0);
  EXPECT_NEAR(c.base_moment, std::max(c.prbm.base_moment + expected, 0.0), 1e-15);
  // Half the regularisation speed: half the fluctuation.
  const WhiskerContact half =
      whisker_contact(p, base, fwd, Vec2(0.0, 0.5 * p.friction_speed_eps), true, 0.07, hit, n, mu, 1);
  EXPECT_NEAR(half.stick_slip_moment, 0.5 * expected, 1e-15);
  // No sliding, no friction, or no gain: no fluctuation, moment = PRBM moment.
  for (const WhiskerContact& z :
       {whisker_contact(p, base, fwd, Vec2(0.0, 0.0), true, 0.07, hit, n, mu, 1),
        whisker_contact(p, base, fwd, Vec2(0.0, 0.2), true, 0.07, hit, n, 0.0, 1)}) {
    EXPECT_EQ(z.stick_slip_moment, 0.0);
    EXPECT_EQ(z.base_moment, z.prbm.base_moment);
  }
  WhiskerParams off = p;
  off.stick_slip_gain = 0.0;
  EXPECT_EQ(whisker_contact(off, base, fwd, Vec2(0.0, 0.2), true, 0.07, hit, n, mu, 1).stick_slip_moment, 0.0);
}

}  // namespace
}  // namespace tactile_sim
