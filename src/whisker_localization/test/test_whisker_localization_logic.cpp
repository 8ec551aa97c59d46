// Node logic: parameters (repo config = defaults, errors), message handling,
// bad input counted, and a closed loop against the tip-contact SITL.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "whisker_localization/stage_sim.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"

using namespace whisker_localization;
using tactile_common::ParamMap;

namespace {

nav_msgs::msg::Odometry odom(int64_t ns, const Pose2& p) {
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ns, o.header.stamp);
  o.pose.pose.position.x = p.x;
  o.pose.pose.position.y = p.y;
  o.pose.pose.orientation.z = std::sin(0.5 * p.theta);
  o.pose.pose.orientation.w = std::cos(0.5 * p.theta);
  return o;
}

geometry_msgs::msg::WrenchStamped moment(int64_t ns, double m) {
  geometry_msgs::msg::WrenchStamped w;
  tactile_common::to_stamp(ns, w.header.stamp);
  w.header.frame_id = "cf1/whisker_base";
  w.wrench.torque.z = m;
  return w;
}


/// Node parameters m with the localization started from a prior pose.
WhiskerLocalizationLogic::Params with_prior(ParamMap m, const Pose2& base) {
  m.set("use_prior", true);
  m.set("prior_x", base.x);
  m.set("prior_y", base.y);
  m.set("prior_yaw", base.theta);
  return WhiskerLocalizationLogic::params_from(m);
}
}  // namespace

TEST(WhiskerLocalizationLogic, RepoConfigEqualsDefaults) {
  const ParamMap d = WhiskerLocalizationLogic::default_parameters();
  const ParamMap f = tactile_common::load_node_parameters(std::string(WHISKER_LOC_CONFIG_DIR) + "/whisker_localization.yaml",
                                                          "whisker_localization", d);
  for (const auto& [key, value] : d.values()) {
    EXPECT_EQ(tactile_common::type_name(value), tactile_common::type_name(f.values().at(key))) << key;
    EXPECT_TRUE(value == f.values().at(key)) << key;
  }
  const auto p = WhiskerLocalizationLogic::params_from(f);
  EXPECT_DOUBLE_EQ(p.beam.moment_of_inertia, 5.555e-15);
}

TEST(WhiskerLocalizationLogic, BadParametersNameTheKey) {
  ParamMap m = WhiskerLocalizationLogic::default_parameters();
  m.set("beam.length", -1.0);
  try {
    WhiskerLocalizationLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("beam.length"), std::string::npos) << e.what();
  }
  m = WhiskerLocalizationLogic::default_parameters();
  m.set("epsilon", 2.0);
  try {
    WhiskerLocalizationLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("epsilon"), std::string::npos) << e.what();
  }
  m = WhiskerLocalizationLogic::default_parameters();
  m.set("slope_samples", int64_t{1});
  EXPECT_THROW(WhiskerLocalizationLogic::params_from(m), tactile_common::ParamError);
}

// Every integer parameter set to its default + 2^32 (an int would wrap it back
// to the default) is rejected with its key and the value as given.
TEST(WhiskerLocalizationLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(WhiskerLocalizationLogic::default_parameters(),
                                                        [](const ParamMap& m) { WhiskerLocalizationLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 5u);  // beam.n_segments ... refine_passes
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
}

// Issue 35 item 5: every key has a description, a unit and the range validate() takes
// for it alone (none wider: range_leaks), and none is live (the component applies none).
TEST(WhiskerLocalizationLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = WhiskerLocalizationLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const ParamMap& m) { WhiskerLocalizationLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  ASSERT_NE(d.info("beam.youngs_modulus"), nullptr);
  EXPECT_EQ(d.info("beam.youngs_modulus")->unit, "Pa");
  EXPECT_EQ(d.info("beam.n_segments")->range->text(), "[4, 100000]");
  EXPECT_EQ(d.info("epsilon")->range->text(), "[0, 1)");
  // validate() takes an infinite age (never stale): the range keeps it.
  EXPECT_EQ(d.info("max_odom_age_s")->range->text(), "(0, inf]");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

TEST(WhiskerLocalizationLogic, MapFileErrorsNameFileAndKey) {
  const std::string path = ::testing::TempDir() + "bad_map.yaml";
  {
    std::ofstream f(path);
    f << "polylines:\n  - [[0.0, 0.0], [0.1, zero]]\n";
  }
  try {
    load_map_file(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("polylines[0][1]"), std::string::npos) << e.what();
  }
  {
    std::ofstream f(path);
    f << "polylines:\n  - [[0.0, 0.0], [0.1, 0.0], [0.2, 0.05]]\n";
  }
  const auto pls = load_map_file(path);
  ASSERT_EQ(pls.size(), 1u);
  EXPECT_EQ(pls[0].size(), 3u);
  EXPECT_THROW(load_map_file(path + ".missing"), std::runtime_error);
  {
    std::ofstream f(path);
    f << "polylines: [";
  }
  EXPECT_THROW(load_map_file(path), std::runtime_error);  // truncated YAML
}

TEST(WhiskerLocalizationLogic, BadInputIsCountedAndDropped) {
  WhiskerLocalizationLogic logic(WhiskerLocalizationLogic::params_from(WhiskerLocalizationLogic::default_parameters()));
  EXPECT_FALSE(logic.on_moment(moment(1000, 1e-3)).result);  // no odometry yet
  EXPECT_EQ(logic.stats().dropped_no_odom, 1u);
  logic.on_odometry(odom(1000, Pose2{}));
  EXPECT_FALSE(logic.on_moment(moment(2000, std::nan(""))).result);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 1u);
  EXPECT_TRUE(logic.on_moment(moment(3000, 0.0)).result);  // no contact: published, empty set
  EXPECT_EQ(logic.stats().no_contact, 1u);
  EXPECT_FALSE(logic.on_moment(moment(3000, 1e-3)).result);  // same stamp
  EXPECT_EQ(logic.stats().dropped_out_of_order, 1u);
  EXPECT_FALSE(logic.on_moment(moment(int64_t{1000000000}, 1e-3)).result);  // odometry 1 s old
  EXPECT_EQ(logic.stats().dropped_no_odom, 2u);
}

TEST(WhiskerLocalizationLogic, HallFluxInputIsCalibratedToMoment) {
  ParamMap m = WhiskerLocalizationLogic::default_parameters();
  m.set("input", std::string("flux"));
  m.set("hall_coefficients", std::vector<double>{1e-5, 2e-4});  // M = 1e-5 + 2e-4 B
  WhiskerLocalizationLogic logic(WhiskerLocalizationLogic::params_from(m));
  logic.on_odometry(odom(1000, Pose2{}));
  const auto out = logic.on_moment(moment(1000, 4.0));  // B = 4 mT
  ASSERT_TRUE(out.result);
  EXPECT_NEAR(out.result->base_moment, 1e-5 + 8e-4, 1e-15);
  m.set("input", std::string("volts"));
  EXPECT_THROW(WhiskerLocalizationLogic::params_from(m), tactile_common::ParamError);
  m.set("input", std::string("flux"));
  m.set("hall_coefficients", std::vector<double>{});
  EXPECT_THROW(WhiskerLocalizationLogic::params_from(m), tactile_common::ParamError);
}

TEST(WhiskerLocalizationLogic, SweepAlongTheCornerLocalizesTheBase) {
  // Table II sweep 03 through the node logic: odometry of the stage (in its
  // own frame, starting at 0) and base moments from the tip-contact SITL.
  ParamMap m = WhiskerLocalizationLogic::default_parameters();
  const Table2Params t;
  const double L = t.beam.length, attack = t.attack_deg * 3.14159265358979 / 180.0;
  const double heading = -3.14159265358979 / 2 + attack;
  const double reach = L - t.penetration / std::cos(attack);
  Pose2 base{-0.012 - reach * std::cos(heading), -reach * std::sin(heading), heading};
  WhiskerLocalizationLogic logic(with_prior(m, base));
  const ElasticaSolver solver{BeamParams{}};
  const BoundaryMap world({concave_corner_polyline(0.05, 0.15, 0.00005)}, 0.001);
  const Pose2 motion{t.step * std::cos(-heading), t.step * std::sin(-heading), 0.0};
  Pose2 stage{};  // the odometry frame starts at the stage origin
  double err = 1.0;
  std::size_t set_size = 0;
  for (int k = 0; k < 40; ++k) {
    if (k > 0) {
      base = compose(base, motion);
      stage = compose(stage, motion);
    }
    const WallContact wc = tip_wall_contact(solver, world, base);
    ASSERT_TRUE(wc.contact && wc.ok);
    const int64_t ns = 1000000 + k * 20000000LL;
    logic.on_odometry(odom(ns, stage));
    const auto out = logic.on_moment(moment(ns, wc.m0));
    ASSERT_TRUE(out.result && out.pose_set);
    EXPECT_EQ(out.result->pose_set.poses.size(), out.pose_set->poses.size());
    EXPECT_EQ(out.result->header.frame_id, "map");  // the pose set
    EXPECT_EQ(out.result->contact_frame_id, "cf1/whisker_base");  // the contact point: the moment's frame
    if (k >= 5) {
      EXPECT_TRUE(out.result->contact_valid);
      EXPECT_NEAR(out.result->contact_point.x, wc.shape.contact_x, 1e-3);
    }
    if (!out.pose_set->poses.empty()) {
      err = std::hypot(out.result->best_estimate.position.x - base.x, out.result->best_estimate.position.y - base.y);
      set_size = out.pose_set->poses.size();
    }
  }
  std::printf("final error %.2f mm, set %zu poses\n", err * 1e3, set_size);
  EXPECT_LT(err, 0.003);
  EXPECT_LT(set_size, 50u);
  EXPECT_EQ(logic.stats().published, 40u);
}

TEST(WhiskerLocalizationLogic, MinStepLocalizesEveryHalfMillimetreAndRestartEmptiesTheSet) {
  // A continuously moving stage sampled every 0.1 mm: with min_step 0.49 mm
  // only every fifth contact sample is localized, the others are counted.
  ParamMap m = WhiskerLocalizationLogic::default_parameters();
  m.set("min_step", 0.00049);
  const Table2Params t;
  Pose2 base, step;
  table2_sweep(t, 1, base, step);
  WhiskerLocalizationLogic logic(with_prior(m, base));
  const ElasticaSolver solver{BeamParams{}};
  const BoundaryMap world({concave_corner_polyline(0.05, 0.15, 0.00005)}, 0.001);
  const Pose2 fine{0.2 * step.x, 0.2 * step.y, 0.0};  // 0.1 mm
  int published = 0;
  for (int k = 0; k < 100; ++k) {
    if (k > 0) base = compose(base, fine);
    const int64_t ns = 1000000 + k * 5000000LL;
    logic.on_odometry(odom(ns, base));  // odometry in the map frame
    const auto wc = tip_wall_contact(solver, world, base);
    ASSERT_TRUE(wc.contact && wc.ok);
    published += logic.on_moment(moment(ns, wc.m0)).result ? 1 : 0;
  }
  EXPECT_EQ(published, 20);  // samples 0, 5, 10, ...
  EXPECT_EQ(logic.stats().skipped_small_motion, 80u);
  EXPECT_FALSE(logic.localizer().set().empty());
  logic.restart(&base);
  EXPECT_TRUE(logic.localizer().set().empty());
  // After the restart the next sample is localized whatever the motion.
  const int64_t ns = 1000000 + 100 * 5000000LL;
  logic.on_odometry(odom(ns, base));
  EXPECT_TRUE(logic.on_moment(moment(ns, tip_wall_contact(solver, world, base).m0)).result);
}
