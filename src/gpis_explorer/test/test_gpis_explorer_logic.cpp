// gpis_explorer node logic: parameters (defaults = repository config), input
// validation counters, message outputs.
#include <cmath>
#include <filesystem>

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
}

// The integer parameters were clamped before they were checked (grid_cells,
// probe_directions, max_updates, ...: min(value, cap)), so 2^32 + 4
// surface points per follow ran as 1000 and grid_cells 2^32 + 10 was reported
// as 1000000. Now every integer parameter set to its default + 2^32 is
// rejected with its key and the value as given.
TEST(GpisExplorerLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(GpisExplorerLogic::default_parameters(),
                                                        [](const tactile_common::ParamMap& m) { GpisExplorerLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 7u);  // gpis.max_points ... max_updates
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
      EXPECT_EQ(out.map->header.frame_id, "odom");
      ASSERT_TRUE(out.target.has_value());
      EXPECT_FALSE(out.target->exit_found);
      EXPECT_EQ(out.target->gpis_update, 1u);
    }
    landed = out.setpoint.land;
  }
  EXPECT_EQ(maps, 1);
  EXPECT_TRUE(landed);
  EXPECT_EQ(logic.sequencer().outcome(), gpis_explorer::Outcome::kOpenSpace);
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
  pic.map = GpisExplorerLogic::make_map(ex, 0);
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
