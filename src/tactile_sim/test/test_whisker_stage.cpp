// The whisker_stage vehicle (paper 002's nitinol whisker on a linear stage):
// kinematics, base moments against walls (tip contact) and pins (point mode)
// equal to whisker_localization's elastica solutions, noise, scenario errors.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"
#include "tactile_sim/whisker_stage.hpp"

using namespace tactile_sim;
namespace wl = whisker_localization;

namespace {

Arena corner_arena() {
  Arena a;
  const int id = a.add_obstacle("corner");
  const auto pts = wl::concave_corner_polyline(0.05, 0.15, 0.001);
  for (std::size_t i = 1; i < pts.size(); ++i) {
    a.add_wall(Vec2(pts[i - 1][0], pts[i - 1][1]), Vec2(pts[i][0], pts[i][1]), 0, id);
  }
  return a;
}

WhiskerStageParams quiet() {
  WhiskerStageParams p;
  p.noise_relative = 0.0;
  p.noise_absolute = 0.0;
  return p;
}

}  // namespace

TEST(WhiskerStage, MovesStraightAtItsSpeedAndTurns) {
  WhiskerStage s(quiet(), Vec3(0.0, 0.0, 0.0), 0.0, 1);
  s.set_setpoint(Vec3(0.03, 0.04, 0.0), 0.5);
  for (int k = 0; k < 1000; ++k) s.step(0.001);  // 1 s at 20 mm/s: 20 mm of the 50 mm
  EXPECT_NEAR(s.state().position.x(), 0.012, 1e-12);
  EXPECT_NEAR(s.state().position.y(), 0.016, 1e-12);
  EXPECT_NEAR(s.yaw(), 0.5, 1e-12);  // 1 rad/s reached 0.5 rad
  for (int k = 0; k < 2000; ++k) s.step(0.001);
  EXPECT_NEAR(s.state().position.x(), 0.03, 1e-12);  // stops exactly on the setpoint
  EXPECT_NEAR(s.state().position.y(), 0.04, 1e-12);
}

TEST(WhiskerStage, WallMomentIsTheTipContactOfTheElasticaModel) {
  const Arena arena = corner_arena();
  const wl::BoundaryMap map(wall_polylines(arena), 0.001);
  ASSERT_EQ(wall_polylines(arena).size(), 1u);  // the corner is one polyline
  wl::Table2Params t2;
  wl::Pose2 start, motion;
  wl::table2_sweep(t2, 0, start, motion);
  WhiskerStage s(quiet(), Vec3(start.x, start.y, 0.0), start.theta, 1);
  const auto r = s.sense(arena);
  const auto ref = wl::tip_wall_contact(s.solver(), map, start);
  ASSERT_TRUE(r.contact && r.tip && r.ok);
  EXPECT_GT(r.m0_true, 1e-4);  // about 1 mN m at 4 mm penetration
  EXPECT_NEAR(r.m0_true, ref.m0, 1e-12);
  EXPECT_EQ(r.m0, r.m0_true);  // no noise configured
  EXPECT_NEAR(r.contact_point.x(), ref.tip_x, 1e-12);
  // Far from the wall: no contact, zero moment.
  WhiskerStage far(quiet(), Vec3(-0.05, 0.2, 0.0), 0.0, 1);
  EXPECT_FALSE(far.sense(arena).contact);
}

TEST(WhiskerStage, PinIsPointModeOnTheSideItPresses) {
  Arena arena;
  arena.add_cylinder(Vec2(0.1, 0.0), 0.0005, 0, arena.add_obstacle("pin"));
  // Whisker along +x from (0.05, 0.01): the pin at p_x = 50 mm, 10 mm to the right: free.
  WhiskerStage s(quiet(), Vec3(0.05, 0.01, 0.0), 0.0, 1);
  EXPECT_FALSE(s.sense(arena).contact);
  // Touch on the axis: contact, no moment.
  s.set_setpoint(Vec3(0.05, 0.0, 0.0), 0.0);
  for (int k = 0; k < 1000; ++k) s.step(0.001);
  auto r = s.sense(arena);
  EXPECT_TRUE(r.contact);
  EXPECT_NEAR(r.m0_true, 0.0, 1e-15);
  // Base moved 3 mm to -y: the pin at (50, +3) mm in the sensor frame.
  s.set_setpoint(Vec3(0.05, -0.003, 0.0), 0.0);
  for (int k = 0; k < 1000; ++k) s.step(0.001);
  r = s.sense(arena);
  const auto ref = s.solver().solve_point(0.05, 0.003);
  ASSERT_TRUE(r.contact && ref.ok);
  EXPECT_NEAR(r.m0_true, ref.base_moment, 1e-12);
  EXPECT_NEAR(r.m0_true, 3.0 * 52e9 * 5.555e-15 * 0.003 / (0.05 * 0.05), 0.05 * r.m0_true);  // ~ 3 EI t / p_x^2
  // Back across the axis beyond the pin's radius: released.
  s.set_setpoint(Vec3(0.05, 0.002, 0.0), 0.0);
  for (int k = 0; k < 1000; ++k) s.step(0.001);
  EXPECT_FALSE(s.sense(arena).contact);
}

TEST(WhiskerStage, NoiseIsRelativePlusAbsoluteOrBounded) {
  const Arena arena = corner_arena();
  wl::Pose2 start, motion;
  wl::table2_sweep(wl::Table2Params{}, 0, start, motion);
  WhiskerStageParams p;  // 0.5 % + 0.2 uN m
  WhiskerStage g(p, Vec3(start.x, start.y, 0.0), start.theta, 7);
  double sum = 0.0, sum2 = 0.0, m = 0.0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const auto r = g.sense(arena);
    m = r.m0_true;
    sum += r.m0 - m;
    sum2 += (r.m0 - m) * (r.m0 - m);
  }
  const double sd = std::sqrt(sum2 / n), expected = std::hypot(0.005 * m, 2e-7);
  EXPECT_NEAR(sd, expected, 0.15 * expected);
  EXPECT_LT(std::fabs(sum / n), 4.0 * expected / std::sqrt(n));
  p.noise_relative = 0.05;
  p.noise_bounded = true;
  WhiskerStage b(p, Vec3(start.x, start.y, 0.0), start.theta, 7);
  double lo = 1.0, hi = -1.0;
  for (int k = 0; k < n; ++k) {
    const auto r = b.sense(arena);
    lo = std::min(lo, r.m0 / r.m0_true - 1.0);
    hi = std::max(hi, r.m0 / r.m0_true - 1.0);
  }
  EXPECT_GE(lo, -0.05);
  EXPECT_LE(hi, 0.05);
  EXPECT_LT(lo, -0.04);  // uniform over the whole band
  EXPECT_GT(hi, 0.04);
}

TEST(WhiskerStage, ScenarioPublishesBaseMomentsAndRejectsBadParameters) {
  const std::string yaml =
      "name: t\nduration_s: 1\n"
      "arena:\n  walls:\n    - points: [[-0.15, 0.0], [0.1, 0.0]]\n"
      "vehicle:\n  type: whisker_stage\n  initial: {x: -0.0455, y: 0.0538, yaw_deg: -50}\n"
      "  params: {sample_rate_hz: 100, noise_relative: 0.0, noise_absolute: 0.0}\n"
      "graph: none\n";
  const Scenario s = load_scenario_from_string(yaml, "scn.yaml", ".");
  EXPECT_EQ(s.vehicle, VehicleType::kWhiskerStage);
  SimLogic sim(s, 1);
  SimLogic::Outputs out;
  int moments = 0;
  double m0 = 0.0;
  for (int64_t k = 0; k <= 100; ++k) {
    out.clear();
    sim.step(k * sim.period_ns(), out);
    for (const auto& w : out.wrench) {
      if (w.topic == "whisker/base_wrench") {
        ++moments;
        m0 = w.msg.wrench.torque.z;
      }
    }
  }
  EXPECT_EQ(moments, 11);  // 100 Hz over 0.1 s, first sample included
  EXPECT_GT(m0, 1e-4);     // the tip presses the floor
  EXPECT_GT(sim.summary().at("whisker_contact_fraction"), 0.99);
  auto error_of = [](const std::string& y) {
    try {
      SimLogic bad(load_scenario_from_string(y, "scn.yaml", "."), 1);
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string bad = yaml;
  bad.replace(bad.find("sample_rate_hz: 100"), 19, "sample_rate: 100");
  EXPECT_NE(error_of(bad).find("vehicle.params.sample_rate: unknown parameter of whisker_stage"), std::string::npos)
      << error_of(bad);
  bad = yaml;
  bad.replace(bad.find("noise_relative: 0.0"), 19, "noise_relative: 2.0");
  EXPECT_NE(error_of(bad).find("scn.yaml: vehicle.params: WhiskerStageParams.noise_relative"), std::string::npos)
      << error_of(bad);
}
