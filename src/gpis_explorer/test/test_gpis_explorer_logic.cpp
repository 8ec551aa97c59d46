// gpis_explorer node logic: parameters (defaults = repository config), input
// validation counters, message outputs.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "gpis_explorer/gpis_plot.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"

using gpis_explorer::GpisExplorerLogic;

namespace {
nav_msgs::msg::Odometry odom(int64_t ns, double x, double y) {
  nav_msgs::msg::Odometry m;
  tactile_common::to_stamp(ns, m.header.stamp);
  m.pose.pose.position.x = x;
  m.pose.pose.position.y = y;
  m.pose.pose.orientation.w = 1.0;
  return m;
}
}  // namespace

TEST(GpisExplorerLogic, RepositoryConfigEqualsDefaults) {
  const auto path = std::filesystem::path(__FILE__).parent_path() / ".." / ".." / ".." / "config" / "gpis_explorer.yaml";
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const auto defaults = GpisExplorerLogic::default_parameters();
  const auto loaded = tactile_common::load_node_parameters(path.string(), GpisExplorerLogic::kNodeName, defaults);
  for (const auto& [k, v] : defaults.values()) {
    EXPECT_EQ(loaded.values().at(k), v) << k;
  }
  EXPECT_NO_THROW(GpisExplorerLogic::params_from(loaded));
}

TEST(GpisExplorerLogic, BadParameterNamesKey) {
  auto m = GpisExplorerLogic::default_parameters();
  m.set("follow_side", std::string("up"));
  try {
    GpisExplorerLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("follow_side"), std::string::npos) << e.what();
  }
  m = GpisExplorerLogic::default_parameters();
  m.set("corner_curvature", 1.0);
  EXPECT_THROW(GpisExplorerLogic::params_from(m), tactile_common::ParamError);
  m = GpisExplorerLogic::default_parameters();
  m.set("gpis.max_points", int64_t{-3});
  EXPECT_THROW(GpisExplorerLogic::params_from(m), tactile_common::ParamError);
  // The solver (README "Local solver"): exact by default, local by name, nothing else.
  EXPECT_EQ(GpisExplorerLogic::params_from(GpisExplorerLogic::default_parameters()).sequencer.explorer.solver,
            gpis_explorer::GpisSolver::kExact);
  m = GpisExplorerLogic::default_parameters();
  m.set("gpis.solver", std::string("local"));
  EXPECT_EQ(GpisExplorerLogic::params_from(m).sequencer.explorer.solver, gpis_explorer::GpisSolver::kLocal);
  m.set("gpis.solver", std::string("sparse"));
  try {
    GpisExplorerLogic::params_from(m);
    FAIL() << "gpis.solver 'sparse' accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("gpis.solver"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'sparse'"), std::string::npos) << e.what();
  }
  m = GpisExplorerLogic::default_parameters();
  m.set("gpis.min_leaf_size", 0.1);  // < 2 overlap: validate()'s message
  try {
    GpisExplorerLogic::params_from(m);
    FAIL() << "gpis.min_leaf_size 0.1 accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("min_leaf_size: must be >= 2 overlap"), std::string::npos) << e.what();
  }
}

// The integer parameters were clamped before they were checked (grid_cells,
// probe_directions, max_updates, ...: min(value, cap)), so 2^32 + 4
// surface points per follow ran as 1000 and grid_cells 2^32 + 10 was reported
// as 1000000. Now every integer parameter set to its default + 2^32 is
// rejected with its key and the value as given.
TEST(GpisExplorerLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(GpisExplorerLogic::default_parameters(),
                                                        [](const tactile_common::ParamMap& m) { GpisExplorerLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 9u);  // gpis.max_points, gpis.leaf_points, gpis.label_neighbours ... max_updates
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
  auto m = GpisExplorerLogic::default_parameters();
  m.set("variance_cells", int64_t{1});  // in [0, 5000], but not 0 or 2..5000: validate()'s message
  try {
    GpisExplorerLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("variance_cells: must be 0 (every grid node) or in [2, 5000], got 1"),
              std::string::npos) << e.what();
  }
}


// Every key carries a description, a unit and the range params_from()/validate() accept
// for it alone (never wider: a value just outside each end is refused); all read at start.
TEST(GpisExplorerLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const tactile_common::ParamMap d = GpisExplorerLogic::default_parameters();
  EXPECT_EQ(tactile_common::undescribed(d), std::vector<std::string>{});
  for (const auto& leak : tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) {
         GpisExplorerLogic::params_from(m);
       })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  // An unbounded range means every finite value: infinity itself is refused.
  for (const auto& leak : tactile_common::infinities_accepted(d, [](const tactile_common::ParamMap& m) {
         GpisExplorerLogic::params_from(m);
       })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is accepted";
  }
  ASSERT_NE(d.info("grid_cells"), nullptr);
  EXPECT_EQ(d.info("grid_cells")->range->text(), "[2, 5000]");
  ASSERT_NE(d.info("corner_curvature"), nullptr);
  EXPECT_EQ(d.info("corner_curvature")->range->text(), "(-inf, 0)");  // q < 0 (000 eq. 41)
  EXPECT_EQ(d.info("corner_curvature")->unit, "1/m");
  ASSERT_NE(d.info("slow_fraction"), nullptr);
  EXPECT_EQ(d.info("slow_fraction")->range->text(), "(0, 1]");
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}
TEST(GpisExplorerLogic, DropsBadInputAndHoversWithoutOdometry) {
  GpisExplorerLogic logic(GpisExplorerLogic::params_from(GpisExplorerLogic::default_parameters()));
  auto out = logic.on_timer(0);
  EXPECT_EQ(out.setpoint.vx, 0.0);
  EXPECT_TRUE(out.state.has_value());
  EXPECT_EQ(out.state->behaviour, "gpis_exploration");
  EXPECT_EQ(logic.stats().stale_ticks, 1u);
  auto bad = odom(10, NAN, 0);
  logic.on_odometry(bad);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 1u);
  logic.on_odometry(odom(20, 0, 0));
  logic.on_odometry(odom(10, 0, 0));
  EXPECT_EQ(logic.stats().dropped_out_of_order, 1u);
  tactile_msgs::msg::TactileDepth d;
  d.contact_left = true;
  d.depth_left = NAN;
  logic.on_depth(d);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 2u);
}

TEST(GpisExplorerLogic, OpenSpacePublishesMapAndTarget) {
  GpisExplorerLogic logic(GpisExplorerLogic::params_from(GpisExplorerLogic::default_parameters()));
  // Free flight: integrate the setpoints, no contact ever.
  double x = 0, y = 0, yaw = 0;
  int maps = 0;
  bool landed = false;
  for (int64_t k = 0; k < 50 * 400 && !landed; ++k) {  // 4 probes, then the 4 diagonals (diagonal_probes)
    const int64_t ns = k * GpisExplorerLogic::kTimerPeriodNs;
    auto o = odom(ns, x, y);
    o.pose.pose.orientation.z = std::sin(yaw / 2);
    o.pose.pose.orientation.w = std::cos(yaw / 2);
    o.header.frame_id = "cf1/odom";  // a prefixed vehicle: the outputs follow its frames
    o.child_frame_id = "cf1/base_link";
    logic.on_odometry(o);
    tactile_msgs::msg::TactileDepth d;
    tactile_common::to_stamp(ns, d.header.stamp);
    logic.on_depth(d);
    const auto out = logic.on_timer(ns);
    x += 0.02 * (out.setpoint.vx * std::cos(yaw) - out.setpoint.vy * std::sin(yaw));
    y += 0.02 * (out.setpoint.vx * std::sin(yaw) + out.setpoint.vy * std::cos(yaw));
    yaw += 0.02 * out.setpoint.yaw_rate;
    if (out.map) {
      ++maps;
      EXPECT_EQ(out.map->width, 10u);
      EXPECT_EQ(out.map->mean.size(), 100u);
      EXPECT_EQ(out.map->training_points.size(), out.map->training_labels.size());
      EXPECT_EQ(out.map->header.frame_id, "cf1/odom");  // the frame of the odometry's positions
      EXPECT_EQ(out.setpoint.header.frame_id, "cf1/base_link");  // body-frame velocities
      ASSERT_TRUE(out.target.has_value());
      EXPECT_EQ(out.target->header.frame_id, "cf1/odom");
      EXPECT_FALSE(out.target->exit_found);
      EXPECT_EQ(out.target->gpis_update, 1u);
    }
    landed = out.setpoint.land;
  }
  EXPECT_EQ(maps, 1);
  EXPECT_TRUE(landed);
  EXPECT_EQ(logic.sequencer().outcome(), gpis_explorer::Outcome::kOpenSpace);
}

namespace {
// Free flight of the node logic (setpoints integrated, no wall): odometry
// every tick; depth (no contact) while depth_on(t). `on_tick(t, out)` sees
// every output. Returns when the logic asks to land, or after max_t.
template <class DepthOn, class OnTick>
void fly_free(GpisExplorerLogic& logic, double max_t, DepthOn depth_on, OnTick on_tick) {
  double x = 0, y = 0, yaw = 0;
  for (int64_t k = 0;; ++k) {
    const int64_t ns = k * GpisExplorerLogic::kTimerPeriodNs;
    const double t = tactile_common::to_seconds(ns);
    if (t >= max_t) return;
    auto o = odom(ns, x, y);
    o.pose.pose.orientation.z = std::sin(yaw / 2);
    o.pose.pose.orientation.w = std::cos(yaw / 2);
    logic.on_odometry(o);
    if (depth_on(t)) {
      tactile_msgs::msg::TactileDepth d;
      tactile_common::to_stamp(ns, d.header.stamp);
      logic.on_depth(d);
    }
    const auto out = logic.on_timer(ns);
    on_tick(t, out);
    x += 0.02 * (out.setpoint.vx * std::cos(yaw) - out.setpoint.vy * std::sin(yaw));
    y += 0.02 * (out.setpoint.vx * std::sin(yaw) + out.setpoint.vy * std::cos(yaw));
    yaw += 0.02 * out.setpoint.yaw_rate;
    if (out.setpoint.land) return;
  }
}
}  // namespace

// FsmState.reason_code carries the sequencer's SequencerReason (REASON_GPIS_*,
// 50-79): free flight (every probe open, then the diagonals, open space) and
// depth stopping in the first probe (FAILSAFE_HOVER, then landing). The codes
// are published in the order of the transitions, 0 only before the first.
TEST(GpisExplorerLogic, PublishesTheSequencersReasonCodes) {
  using tactile_msgs::msg::FsmState;
  auto codes_of = [](double depth_until) {
    GpisExplorerLogic logic(GpisExplorerLogic::params_from(GpisExplorerLogic::default_parameters()));
    std::vector<uint8_t> codes;  // one per transition (consecutive duplicates dropped)
    uint32_t transitions = 0;
    fly_free(
        logic, 600.0, [&](double t) { return t < depth_until; },
        [&](double, const GpisExplorerLogic::Outputs& out) {
          if (!out.state) return;
          EXPECT_EQ(out.state->reason_code, static_cast<uint8_t>(logic.sequencer().reason_code()));
          if (codes.empty() || out.state->transitions != transitions) codes.push_back(out.state->reason_code);
          transitions = out.state->transitions;
        });
    return codes;
  };
  const std::vector<uint8_t> open = codes_of(1e9);
  ASSERT_GE(open.size(), 5u);
  EXPECT_EQ(open.front(), FsmState::REASON_NONE);
  EXPECT_EQ(open[1], FsmState::REASON_GPIS_HOVER_DONE);
  EXPECT_EQ(open[2], FsmState::REASON_GPIS_ALIGNED);
  EXPECT_EQ(open[3], FsmState::REASON_GPIS_PROBE_FOUND_NO_WALL);
  EXPECT_EQ(open[4], FsmState::REASON_GPIS_NEXT_PROBE);
  EXPECT_EQ(open.back(), FsmState::REASON_GPIS_OPEN_SPACE);
  for (std::size_t i = 1; i < open.size(); ++i) {
    EXPECT_GE(open[i], 50u) << i;
    EXPECT_LE(open[i], 79u) << i;
  }
  const std::vector<uint8_t> stale = codes_of(3.0);
  ASSERT_GE(stale.size(), 3u);
  // The shared fail-safe's codes, as every behaviour publishes them.
  EXPECT_EQ(stale[stale.size() - 2], FsmState::REASON_FAILSAFE_DEPTH_STALE);
  EXPECT_EQ(stale.back(), FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
  EXPECT_STREQ(gpis_explorer::to_string(gpis_explorer::SequencerReason::kFailsafeStaleTooLong),
               "failsafe_stale_too_long");
}

// Issue 33: odometry fresh, tactile depth stopped at t = 3 s in the first
// probe. The whisker wall follower hovers 0.2 s later (max_input_age_s);
// gpis_explorer flew its 2 m probe on blind and recorded it as "no wall".
// Now: zero motion from the first tick after the threshold (3.2 s + one
// tick), FAILSAFE_HOVER with the reason in the state message, no probe result,
// landing after failsafe_land_after_s.
TEST(GpisExplorerLogic, StaleDepthStopsTheProbeWithinTheThresholdAndOneTick) {
  GpisExplorerLogic logic(GpisExplorerLogic::params_from(GpisExplorerLogic::default_parameters()));
  const double last_depth = 3.0;
  const double age = logic.params().sequencer.wall.max_input_age_s;
  bool flew_before = false, moved_after = false, no_wall = false, landed = false;
  double failsafe_at = NAN, land_at = NAN;
  std::string failsafe_reason;
  fly_free(
      logic, 60.0, [&](double t) { return t <= last_depth + 1e-9; },
      [&](double t, const GpisExplorerLogic::Outputs& out) {
        const bool moving = out.setpoint.vx != 0.0 || out.setpoint.vy != 0.0 || out.setpoint.yaw_rate != 0.0;
        if (t > 2.5 && t <= last_depth + age + 1e-9) flew_before = flew_before || moving;
        if (t >= last_depth + age + 0.02 - 1e-9) moved_after = moved_after || moving;
        if (out.state && out.state->state == "FAILSAFE_HOVER" && !std::isfinite(failsafe_at)) {
          failsafe_at = t;
          failsafe_reason = out.state->reason;
        }
        if (out.state && out.state->reason == "probe found no wall") no_wall = true;
        if (out.setpoint.land && !std::isfinite(land_at)) land_at = t;
        landed = landed || out.setpoint.land;
      });
  EXPECT_TRUE(flew_before);  // the probe was under way, and still is while the depth is within the threshold
  EXPECT_FALSE(moved_after) << "moved with the tactile depth older than max_input_age_s";
  EXPECT_NEAR(failsafe_at, last_depth + age + 0.02, 1e-6);
  EXPECT_EQ(failsafe_reason, "tactile depth stale");
  EXPECT_FALSE(no_wall) << "a probe flown blind was recorded as no wall";
  EXPECT_EQ(logic.sequencer().explorer().gpis().size(), 0u);
  EXPECT_TRUE(landed);
  EXPECT_NEAR(land_at, failsafe_at + logic.params().sequencer.wall.failsafe_land_after_s, 1e-6);
  EXPECT_EQ(std::string(gpis_explorer::to_string(logic.sequencer().outcome())), "inputs_stale");
  EXPECT_GT(logic.stats().stale_ticks, 0u);
}

// Depth back after 1 s: the probe resumes ("inputs fresh again") and moves;
// the two parameters are the wall follower's keys with its defaults.
TEST(GpisExplorerLogic, StaleDepthResumesWhenFreshAgain) {
  const auto defaults = GpisExplorerLogic::default_parameters();
  EXPECT_EQ(defaults.get_double("max_input_age_s"), tactile_fsm::WallFollowerParams{}.max_input_age_s);
  EXPECT_EQ(defaults.get_double("failsafe_land_after_s"), tactile_fsm::WallFollowerParams{}.failsafe_land_after_s);
  GpisExplorerLogic logic(GpisExplorerLogic::params_from(defaults));
  std::vector<std::string> reasons;
  bool moved_after_resume = false, moved_while_held = false;
  fly_free(
      logic, 6.0, [](double t) { return t <= 3.0 + 1e-9 || t >= 4.0 - 1e-9; },
      [&](double t, const GpisExplorerLogic::Outputs& out) {
        const bool moving = out.setpoint.vx != 0.0 || out.setpoint.vy != 0.0 || out.setpoint.yaw_rate != 0.0;
        if (out.state) reasons.push_back(out.state->state + ": " + out.state->reason);
        if (t > 3.22 - 1e-9 && t < 4.0 - 1e-9) moved_while_held = moved_while_held || moving;
        if (t >= 4.0 - 1e-9) moved_after_resume = moved_after_resume || moving;
      });
  EXPECT_FALSE(moved_while_held);
  EXPECT_TRUE(moved_after_resume);
  EXPECT_NE(std::find(reasons.begin(), reasons.end(), "FAILSAFE_HOVER: tactile depth stale"), reasons.end());
  EXPECT_NE(std::find(reasons.begin(), reasons.end(), "PROBE: inputs fresh again"), reasons.end());
  EXPECT_EQ(logic.sequencer().phase(), gpis_explorer::Phase::kProbe);
}

TEST(GpisPlot, WritesAPictureOfARoomUpdate) {
  gpis_explorer::ExplorerParams p = gpis_explorer::ExplorerParams::onboard();
  p.grid_cells = 40;
  gpis_explorer::GpisExplorer ex(p);
  for (double s = -1.0; s <= 1.0; s += 0.25) {
    ex.add_point({s, -1.0}, 0.0);
    ex.add_point({-1.0, s}, 0.0);
    ex.add_point({1.0, s}, 0.0);
  }
  ex.add_point({0, 0}, -1.0);
  ex.update();
  gpis_explorer::GpisPicture pic;
  pic.map = GpisExplorerLogic::make_map(ex, 0, "odom");
  EXPECT_EQ(pic.map.contour_starts.size(), ex.last().contours.size());
  EXPECT_EQ(pic.map.corners.size(), ex.last().corners.size());
  pic.trajectory = {{0, 0}, {0.5, 0}, {0.5, 0.5}};
  pic.target = ex.last().target;
  pic.drone = std::make_pair(Eigen::Vector2d(0.5, 0.5), 0.3);
  pic.title = "test";
  const auto path = std::filesystem::temp_directory_path() / "gpis_plot_test.png";
  gpis_explorer::write_gpis_png(path.string(), pic, 300);
  const cv::Mat img = cv::imread(path.string());
  ASSERT_FALSE(img.empty());
  EXPECT_GE(img.cols, 300);
  // The target ring is drawn in its colour (BGR 255, 80, 0) somewhere.
  bool ring = false;
  for (int r = 0; r < img.rows && !ring; ++r) {
    for (int c = 0; c < img.cols && !ring; ++c) ring = img.at<cv::Vec3b>(r, c) == cv::Vec3b(255, 80, 0);
  }
  EXPECT_TRUE(ring);
  std::filesystem::remove(path);
  pic.map.mean.pop_back();
  EXPECT_THROW(gpis_explorer::write_gpis_png(path.string(), pic), std::invalid_argument);
}
