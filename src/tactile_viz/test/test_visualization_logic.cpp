// VisualizationLogic against hand-computed markers: positions, ids, namespaces, colours,
// frames and stamps taken from the input, DELETE / DELETEALL, the ring buffers, the grid
// scaling, bad input and bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "tactile_common/parameters.hpp"
#include "tactile_viz/visualization_logic.hpp"

using tactile_viz::InputError;
using tactile_viz::VisualizationLogic;
using visualization_msgs::msg::Marker;

namespace {

VisualizationLogic::Params no_throttle() {
  VisualizationLogic::Params p;
  p.min_interval_s = 0.0;
  return p;
}

builtin_interfaces::msg::Time at(double t) {
  builtin_interfaces::msg::Time s;
  s.sec = static_cast<int32_t>(std::floor(t));
  s.nanosec = static_cast<uint32_t>(std::llround((t - std::floor(t)) * 1e9));
  return s;
}

geometry_msgs::msg::Point pt(double x, double y, double z = 0.0) {
  geometry_msgs::msg::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

tactile_msgs::msg::TactileDepth depth(double t, bool left, bool right, double lx, double rx) {
  tactile_msgs::msg::TactileDepth d;
  d.header.stamp = at(t);
  d.header.frame_id = "base_link";
  d.contact_frame_id = "odom";
  d.contact_left = left;
  d.contact_right = right;
  d.contact_point_left = pt(lx, 0.1);
  d.contact_point_right = pt(rx, -0.1);
  return d;
}

tactile_msgs::msg::GpisMap gpis(uint32_t w, uint32_t h) {
  tactile_msgs::msg::GpisMap m;
  m.header.stamp = at(3.0);
  m.header.frame_id = "odom";
  m.origin_x = -1.0;
  m.origin_y = 2.0;
  m.resolution = 0.05;
  m.width = w;
  m.height = h;
  m.mean.assign(static_cast<size_t>(w) * h, 0.0f);
  m.variance.assign(static_cast<size_t>(w) * h, 0.0f);
  return m;
}

const Marker* find(const VisualizationLogic::MarkerArray& a, const std::string& ns, int id, int action = Marker::ADD) {
  for (const auto& m : a.markers)
    if (m.ns == ns && m.id == id && m.action == action) return &m;
  return nullptr;
}

void expect_point(const geometry_msgs::msg::Point& p, double x, double y, double z) {
  EXPECT_NEAR(p.x, x, 1e-12);
  EXPECT_NEAR(p.y, y, 1e-12);
  EXPECT_NEAR(p.z, z, 1e-12);
}

}  // namespace

TEST(VisualizationParams, DefaultsValidateAndRepoConfigEqualsThem) {
  const auto d = VisualizationLogic::default_parameters();
  const auto p = VisualizationLogic::params_from(d);
  EXPECT_EQ(p.max_markers, 500);
  for (const auto& kv : d.values()) EXPECT_NE(d.info(kv.first), nullptr) << kv.first << " has no ParamInfo";
  const auto f = tactile_common::load_node_parameters("../../config/visualization.yaml", "visualization", d);
  for (const auto& kv : d.values()) EXPECT_TRUE(f.values().at(kv.first) == kv.second) << kv.first;
}

TEST(VisualizationParams, BadValuesNameTheKey) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, tactile_common::ParamValue>>{
           {"max_markers", int64_t{0}}, {"min_interval_s", -0.1}, {"mean_range", 0.0},
           {"variance_max", std::numeric_limits<double>::infinity()}, {"line_width", -1.0}}) {
    auto m = VisualizationLogic::default_parameters();
    m.set(key, value);
    try {
      VisualizationLogic::params_from(m);
      ADD_FAILURE() << key << " accepted";
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  VisualizationLogic::Params p;
  p.contact_diameter = std::nan("");
  EXPECT_THROW(VisualizationLogic{p}, std::invalid_argument);
}

TEST(VisualizationLogic, WhiskerContactsFirstDeleteAllThenSphereListsInTheContactFrame) {
  VisualizationLogic v(no_throttle());
  auto out = v.on_tactile_depth(depth(1.0, true, false, 0.5, 0.0));
  ASSERT_EQ(out.markers.size(), 2u);
  EXPECT_EQ(out.markers[0].action, Marker::DELETEALL);
  EXPECT_EQ(out.markers[0].ns, "whisker_contacts");
  const Marker& left = out.markers[1];
  EXPECT_EQ(left.ns, "whisker_contacts");
  EXPECT_EQ(left.id, 0);
  EXPECT_EQ(left.type, Marker::SPHERE_LIST);
  EXPECT_EQ(left.header.frame_id, "odom");  // contact_frame_id, not the body header frame
  EXPECT_EQ(left.header.stamp.sec, 1);
  EXPECT_DOUBLE_EQ(left.scale.x, 0.02);
  EXPECT_FLOAT_EQ(left.color.g, 0.8f);  // left: green
  ASSERT_EQ(left.points.size(), 1u);
  expect_point(left.points[0], 0.5, 0.1, 0.0);
  // Second message: no DELETEALL again; the right whisker gets id 1 (blue).
  out = v.on_tactile_depth(depth(1.02, true, true, 0.6, 0.7));
  ASSERT_EQ(out.markers.size(), 2u);
  const Marker* l = find(out, "whisker_contacts", 0);
  const Marker* r = find(out, "whisker_contacts", 1);
  ASSERT_TRUE(l && r);
  ASSERT_EQ(l->points.size(), 2u);
  expect_point(l->points[1], 0.6, 0.1, 0.0);
  ASSERT_EQ(r->points.size(), 1u);
  expect_point(r->points[0], 0.7, -0.1, 0.0);
  EXPECT_FLOAT_EQ(r->color.b, 1.0f);
  // No contact: nothing to publish.
  EXPECT_TRUE(v.on_tactile_depth(depth(1.04, false, false, 0, 0)).markers.empty());
  // Contact before the first odometry (no contact frame): not drawn, counted.
  auto d = depth(1.06, true, false, 0.1, 0);
  d.contact_frame_id = "";
  EXPECT_TRUE(v.on_tactile_depth(d).markers.empty());
  EXPECT_EQ(v.stats().contacts_without_frame, 1u);
}

TEST(VisualizationLogic, ContactHistoryIsARingBufferOfMaxMarkers) {
  auto p = no_throttle();
  p.max_markers = 3;
  VisualizationLogic v(p);
  VisualizationLogic::MarkerArray out;
  for (int i = 0; i < 5; ++i) out = v.on_tactile_depth(depth(1.0 + 0.1 * i, true, false, i, 0));
  const Marker* l = find(out, "whisker_contacts", 0);
  ASSERT_TRUE(l);
  ASSERT_EQ(l->points.size(), 3u);  // the oldest two dropped
  EXPECT_DOUBLE_EQ(l->points[0].x, 2.0);
  EXPECT_DOUBLE_EQ(l->points[2].x, 4.0);
}

TEST(VisualizationLogic, MinIntervalThrottlesByInputStamps) {
  VisualizationLogic v(VisualizationLogic::Params{});  // 0.1 s
  EXPECT_FALSE(v.on_tactile_depth(depth(1.00, true, false, 0.1, 0)).markers.empty());
  EXPECT_TRUE(v.on_tactile_depth(depth(1.05, true, false, 0.2, 0)).markers.empty());
  auto out = v.on_tactile_depth(depth(1.10, true, false, 0.3, 0));
  const Marker* l = find(out, "whisker_contacts", 0);
  ASSERT_TRUE(l);
  EXPECT_EQ(l->points.size(), 3u);  // the held-back point is in the history
  EXPECT_EQ(v.stats().throttled, 1u);
  // Time going back (a new run) publishes at once.
  EXPECT_FALSE(v.on_tactile_depth(depth(0.5, true, false, 0.4, 0)).markers.empty());
}

TEST(VisualizationLogic, WallEstimateLineAndArrowInTheBodyFrameDeletedWhenLost) {
  VisualizationLogic v(no_throttle());
  tactile_msgs::msg::WallEstimate w;
  w.header.stamp = at(2.0);
  w.header.frame_id = "base_link";
  w.wall_detected = true;
  w.distance = 0.5;
  w.direction = -M_PI / 2;  // wall on the right
  auto out = v.on_wall_estimate(w);
  ASSERT_EQ(out.markers.size(), 3u);  // DELETEALL, wall, arrow
  const Marker* wall = find(out, "wall_estimate", 0);
  const Marker* arrow = find(out, "wall_estimate", 1);
  ASSERT_TRUE(wall && arrow);
  EXPECT_EQ(wall->type, Marker::LINE_STRIP);
  EXPECT_EQ(wall->header.frame_id, "base_link");
  // Foot (0, -0.5); the wall runs along x, 1 m long: (-0.5, -0.5) .. (0.5, -0.5).
  ASSERT_EQ(wall->points.size(), 2u);
  expect_point(wall->points[0], -0.5, -0.5, 0.0);
  expect_point(wall->points[1], 0.5, -0.5, 0.0);
  EXPECT_EQ(arrow->type, Marker::ARROW);
  expect_point(arrow->points[0], 0.0, 0.0, 0.0);
  expect_point(arrow->points[1], 0.0, -0.5, 0.0);
  EXPECT_FLOAT_EQ(wall->color.r, 1.0f);
  EXPECT_FLOAT_EQ(wall->color.g, 0.5f);
  // Lost: both ids deleted once, then nothing.
  w.wall_detected = false;
  out = v.on_wall_estimate(w);
  ASSERT_EQ(out.markers.size(), 2u);
  EXPECT_TRUE(find(out, "wall_estimate", 0, Marker::DELETE));
  EXPECT_TRUE(find(out, "wall_estimate", 1, Marker::DELETE));
  EXPECT_TRUE(v.on_wall_estimate(w).markers.empty());
  // A detected wall with a NaN distance is not drawn.
  w.wall_detected = true;
  w.distance = std::nan("");
  EXPECT_TRUE(v.on_wall_estimate(w).markers.empty());
  EXPECT_EQ(v.stats().nonfinite_dropped, 1u);
}

TEST(VisualizationLogic, GpisContoursTrainingCornersAndStaleContoursDeleted) {
  VisualizationLogic v(no_throttle());
  auto m = gpis(2, 1);
  m.contour = {pt(0, 0), pt(1, 0), pt(1, 1), pt(2, 2), pt(3, 2)};
  m.contour_starts = {0, 3};
  m.training_points = {pt(0, 0), pt(0.5, 0.5)};
  m.training_labels = {0, -1};
  m.corners = {pt(1, 0)};
  auto out = v.on_gpis_map(m);
  const Marker* c0 = find(out, "gpis_contour", 0);
  const Marker* c1 = find(out, "gpis_contour", 1);
  ASSERT_TRUE(c0 && c1);
  EXPECT_EQ(c0->type, Marker::LINE_STRIP);
  EXPECT_EQ(c0->header.frame_id, "odom");
  EXPECT_EQ(c0->header.stamp.sec, 3);
  ASSERT_EQ(c0->points.size(), 3u);
  ASSERT_EQ(c1->points.size(), 2u);
  expect_point(c1->points[0], 2, 2, 0);
  const Marker* tp = find(out, "gpis_training", 0);
  ASSERT_TRUE(tp);
  EXPECT_EQ(tp->type, Marker::POINTS);
  ASSERT_EQ(tp->colors.size(), 2u);
  EXPECT_FLOAT_EQ(tp->colors[0].r, 1.0f);  // surface: red
  EXPECT_FLOAT_EQ(tp->colors[1].b, 1.0f);  // interior: blue
  const Marker* corners = find(out, "gpis_corners", 0);
  ASSERT_TRUE(corners);
  ASSERT_EQ(corners->points.size(), 1u);
  // Three DELETEALLs (one per namespace) in the first map only.
  int deleteall = 0;
  for (const auto& mk : out.markers) deleteall += mk.action == Marker::DELETEALL;
  EXPECT_EQ(deleteall, 3);
  // The next map has one contour and no corners: contour 1 and the corners deleted.
  m.contour = {pt(0, 0), pt(1, 0)};
  m.contour_starts = {0};
  m.corners.clear();
  out = v.on_gpis_map(m);
  EXPECT_TRUE(find(out, "gpis_contour", 0));
  EXPECT_TRUE(find(out, "gpis_contour", 1, Marker::DELETE));
  EXPECT_TRUE(find(out, "gpis_corners", 0, Marker::DELETE));
  for (const auto& mk : out.markers) EXPECT_NE(mk.action, Marker::DELETEALL);
}

TEST(VisualizationLogic, BadGpisMapIsAClearError) {
  VisualizationLogic v(no_throttle());
  auto m = gpis(3, 2);
  m.mean.resize(5);
  try {
    v.on_gpis_map(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("GpisMap: mean: has 5 values, width * height = 3 * 2 = 6"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(v.mean_grid(m), InputError);
  m = gpis(1, 1);
  m.contour = {pt(0, 0), pt(1, 0)};
  m.contour_starts = {0, 2};
  try {
    v.on_gpis_map(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contour_starts[1]"), std::string::npos) << e.what();
  }
  m.contour_starts = {0};
  m.training_points = {pt(0, 0)};
  m.training_labels = {1};
  EXPECT_THROW(v.on_gpis_map(m), InputError);
}

TEST(VisualizationLogic, GpisGridsScaleMetresAndSquareMetresTo0To100) {
  VisualizationLogic v(no_throttle());  // mean_range 0.5 m, variance_max 1 m^2
  auto m = gpis(4, 2);
  m.mean = {-1.0f, -0.5f, -0.25f, 0.0f, 0.1f, 0.5f, 2.0f, std::nanf("")};
  m.variance = {0.0f, 0.25f, 0.5f, 1.0f, 3.0f, -0.1f, 0.004f, 0.006f};
  const auto g = v.mean_grid(m);
  EXPECT_EQ(g.header.frame_id, "odom");
  EXPECT_EQ(g.header.stamp.sec, 3);
  EXPECT_EQ(g.info.width, 4u);
  EXPECT_EQ(g.info.height, 2u);
  EXPECT_FLOAT_EQ(g.info.resolution, 0.05f);
  EXPECT_DOUBLE_EQ(g.info.origin.position.x, -1.0);
  EXPECT_DOUBLE_EQ(g.info.origin.position.y, 2.0);
  EXPECT_DOUBLE_EQ(g.info.origin.orientation.w, 1.0);
  // 50 + 50 clamp(mean / 0.5, -1, 1); NaN -> -1 (unknown)
  const std::vector<int8_t> mean_cells = {0, 0, 25, 50, 60, 100, 100, -1};
  EXPECT_EQ(g.data, mean_cells);
  // 100 clamp(variance / 1, 0, 1), rounded to nearest
  const std::vector<int8_t> var_cells = {0, 25, 50, 100, 100, 0, 0, 1};
  EXPECT_EQ(v.variance_grid(m).data, var_cells);
  EXPECT_EQ(v.stats().grid_cells_unknown, 1u);
}

TEST(VisualizationLogic, TargetCollisionsAndLocalization) {
  auto p = no_throttle();
  p.max_markers = 2;
  VisualizationLogic v(p);
  tactile_msgs::msg::ExplorationTarget t;
  t.header.stamp = at(4.0);
  t.header.frame_id = "odom";
  t.target = pt(1, 2);
  auto out = v.on_exploration_target(t);
  const Marker* s = find(out, "gpis_target", 0);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->type, Marker::SPHERE);
  expect_point(s->pose.position, 1, 2, 0);
  EXPECT_FLOAT_EQ(s->color.r, 1.0f);  // magenta
  t.exit_found = true;
  out = v.on_exploration_target(t);
  ASSERT_TRUE(find(out, "gpis_target", 0));
  EXPECT_FLOAT_EQ(find(out, "gpis_target", 0)->color.r, 0.0f);  // green: through an opening

  tactile_msgs::msg::CollisionEvent c;
  c.header.stamp = at(5.0);
  c.header.frame_id = "ground_truth/odom";
  c.normal.x = 1.0;
  for (const char* part : {"body", "guard", "arm2"}) {
    c.part = part;
    c.point.x += 1.0;
    out = v.on_collision(c);
  }
  const Marker* spheres = find(out, "collisions", 0);
  const Marker* normals = find(out, "collisions", 1);
  ASSERT_TRUE(spheres && normals);
  EXPECT_EQ(spheres->header.frame_id, "ground_truth/odom");
  ASSERT_EQ(spheres->points.size(), 2u);  // max_markers 2: "body" dropped
  EXPECT_DOUBLE_EQ(spheres->points[0].x, 2.0);
  EXPECT_FLOAT_EQ(spheres->colors[0].g, 0.5f);  // guard: orange
  EXPECT_FLOAT_EQ(spheres->colors[1].g, 1.0f);  // arm: yellow
  ASSERT_EQ(normals->points.size(), 4u);
  expect_point(normals->points[3], 3.1, 0, 0);  // 0.1 m along the normal
  ASSERT_EQ(normals->colors.size(), 4u);

  tactile_msgs::msg::LocalizationResult r;
  r.header.stamp = at(6.0);
  r.header.frame_id = "map";
  r.contact_valid = true;
  r.contact_frame_id = "whisker_base";
  r.contact_point = pt(0.1, 0.0);
  r.pose_set.poses.resize(2);
  r.pose_set.poses[1].position = pt(0.2, 0.3);
  r.best_estimate.orientation.w = 1.0;
  out = v.on_localization(r);
  const Marker* contact = find(out, "localization", 0);
  ASSERT_TRUE(contact);
  EXPECT_EQ(contact->header.frame_id, "whisker_base");
  const Marker* set = find(out, "localization", 1);
  ASSERT_TRUE(set);
  EXPECT_EQ(set->header.frame_id, "map");
  ASSERT_EQ(set->points.size(), 2u);
  ASSERT_TRUE(find(out, "localization", 2));
  r.contact_valid = false;
  out = v.on_localization(r);
  EXPECT_TRUE(find(out, "localization", 0, Marker::DELETE));
}

TEST(VisualizationLogic, ResetDeletesAllNamespacesAndHistories) {
  VisualizationLogic v(no_throttle());
  v.on_tactile_depth(depth(1.0, true, false, 0.5, 0));
  const auto out = v.reset();
  ASSERT_EQ(out.markers.size(), 8u);
  for (const auto& m : out.markers) EXPECT_EQ(m.action, Marker::DELETEALL);
  const auto next = v.on_tactile_depth(depth(1.1, true, false, 0.6, 0));
  ASSERT_EQ(next.markers.size(), 1u);  // no second DELETEALL
  EXPECT_EQ(next.markers[0].points.size(), 1u);
}
