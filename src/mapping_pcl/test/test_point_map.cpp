// Generic PointMap: insertion, PCL filters, footprint measurement, PLY bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>

#include "mapping_pcl/point_map.hpp"

using namespace mapping_pcl;

TEST(PointMap, InsertBoxCountAndBoundsByHand) {
  PointMap m;
  Box b;
  b.center = Vec3(1.0, 2.0, 0.7);
  b.size = Vec3(0.25, 0.08, 0.5);
  // Per axis: ceil(size / 0.02) + 1 points = 14, 5, 26.
  EXPECT_EQ(m.insert_box(b, 0.02), 14u * 5u * 26u);
  const MapMeasurement r = m.measure();
  EXPECT_EQ(r.points, 1820u);
  EXPECT_NEAR(r.min.x(), 0.875, 1e-6);
  EXPECT_NEAR(r.max.x(), 1.125, 1e-6);
  EXPECT_NEAR(r.min.y(), 1.96, 1e-6);
  EXPECT_NEAR(r.max.z(), 0.95, 1e-6);
  EXPECT_NEAR(r.length, 0.25, 1e-6);
  EXPECT_NEAR(r.width, 0.08, 1e-6);
  EXPECT_NEAR(r.height, 0.5, 1e-6);
  EXPECT_NEAR(r.obb_area, 0.02, 1e-6);
  EXPECT_THROW(m.insert_box(b, 0.0), std::invalid_argument);
  EXPECT_THROW(m.insert(Vec3(std::nan(""), 0, 0)), std::invalid_argument);
}

TEST(PointMap, VoxelFilterMergesWithinALeafAndKeepsSeparatePoints) {
  MapParams p;
  p.auto_filter_growth = 0.0;
  PointMap m(p);
  m.insert({Vec3(0.0012, 0.0012, 0.0012), Vec3(0.0052, 0.0052, 0.0052), Vec3(0.0512, 0.0012, 0.0012)});
  m.voxel_filter(0.01);
  ASSERT_EQ(m.size(), 2u);
  // Centroid of the two points in the first voxel.
  bool found = false;
  for (const auto& q : m.cloud()) {
    if (std::abs(q.x - 0.0032f) < 1e-6f) found = true;
  }
  EXPECT_TRUE(found);
}

TEST(PointMap, StatisticalOutlierRemovalDropsIsolatedPoints) {
  PointMap m;
  Box b;
  b.size = Vec3(0.3, 0.3, 0.3);
  m.insert_box(b, 0.02);
  const std::size_t n = m.size();
  m.insert({Vec3(3, 3, 3), Vec3(-4, 2, 0), Vec3(0, 5, 1)});
  EXPECT_EQ(m.remove_outliers(), 3u);
  EXPECT_EQ(m.size(), n);
}

TEST(PointMap, AutoFilterBoundsGrowth) {
  MapParams p;
  p.auto_filter_min_points = 1000;
  PointMap m(p);
  Box b;
  b.size = Vec3(0.25, 0.08, 0.5);
  for (int i = 0; i < 50; ++i) m.insert_box(b, 0.005);  // same slab again and again
  EXPECT_GT(m.auto_filters(), 0u);
  EXPECT_LT(m.size(), 2u * 26u * 9u * 51u + 51u * 17u * 101u);
}

TEST(MinAreaRectangle, RotatedRectanglePerimeter) {
  const double L = 1.22, W = 1.0, yaw = 30.0 * M_PI / 180.0;
  std::vector<Eigen::Vector2d> pts;
  const Eigen::Rotation2Dd R(yaw);
  for (int i = 0; i <= 100; ++i) {
    const double s = i / 100.0;
    pts.push_back(Eigen::Vector2d(2, 1) + R * Eigen::Vector2d(-L / 2 + L * s, -W / 2));
    pts.push_back(Eigen::Vector2d(2, 1) + R * Eigen::Vector2d(-L / 2 + L * s, W / 2));
    pts.push_back(Eigen::Vector2d(2, 1) + R * Eigen::Vector2d(-L / 2, -W / 2 + W * s));
    pts.push_back(Eigen::Vector2d(2, 1) + R * Eigen::Vector2d(L / 2, -W / 2 + W * s));
  }
  const Rect2 r = min_area_rectangle(pts);
  EXPECT_NEAR(r.length, L, 1e-9);
  EXPECT_NEAR(r.width, W, 1e-9);
  EXPECT_NEAR(r.yaw, yaw, 1e-9);
  EXPECT_NEAR(r.cx, 2.0, 1e-9);
  EXPECT_NEAR(r.cy, 1.0, 1e-9);
  EXPECT_NEAR(r.hull_area, L * W, 1e-9);
}

TEST(MinAreaRectangle, DegenerateInputs) {
  EXPECT_EQ(min_area_rectangle({}).length, 0.0);
  const Rect2 one = min_area_rectangle({Eigen::Vector2d(1, 2)});
  EXPECT_EQ(one.cx, 1.0);
  const Rect2 line = min_area_rectangle({Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(2, 0)});
  EXPECT_NEAR(line.length, 2.0, 1e-12);
  EXPECT_NEAR(line.width, 0.0, 1e-12);
}

TEST(Ply, AsciiHeaderAndValues) {
  Cloud c;
  c.push_back(pcl::PointXYZ(1.0f, -2.5f, 0.125f));
  c.push_back(pcl::PointXYZ(0.1f, 0.2f, 0.3f));
  PlyInfo info;
  info.frame = "map";
  info.comment = "two\npoints";
  const std::string s = ply_bytes(c, PlyFormat::kAscii, info);
  const std::string header =
      "ply\nformat ascii 1.0\ncomment generator mapping_pcl\ncomment frame map\ncomment units m\n"
      "comment two points\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  ASSERT_EQ(s.substr(0, header.size()), header);
  EXPECT_EQ(s.substr(header.size()), "1 -2.5 0.125\n0.100000001 0.200000003 0.300000012\n");
}

TEST(Ply, BinaryLittleEndianBytes) {
  Cloud c;
  c.push_back(pcl::PointXYZ(1.0f, -2.0f, 0.5f));
  const std::string s = ply_bytes(c, PlyFormat::kBinaryLittleEndian);
  const auto end = s.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(s.find("format binary_little_endian 1.0\n"), std::string::npos);
  const std::string body = s.substr(end + 11);
  ASSERT_EQ(body.size(), 12u);
  // 1.0f = 0x3F800000, -2.0f = 0xC0000000, 0.5f = 0x3F000000, least significant byte first.
  const unsigned char expect[12] = {0, 0, 0x80, 0x3F, 0, 0, 0, 0xC0, 0, 0, 0, 0x3F};
  EXPECT_EQ(std::memcmp(body.data(), expect, 12), 0);
}

TEST(Ply, WriteErrorNamesThePath) {
  Cloud c;
  try {
    write_ply("/nonexistent-dir/x.ply", c, PlyFormat::kAscii);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.ply"), std::string::npos);
  }
}

namespace {
/// validate() of the default MapParams with `set` applied throws, naming MapParams.<field>.
void expect_rejected(const std::function<void(MapParams&)>& set, const std::string& field) {
  MapParams p;
  set(p);
  try {
    p.validate();
    ADD_FAILURE() << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MapParams." + field), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(MapParams, ValidateNamesTheField) {
  expect_rejected([](MapParams& p) { p.voxel_leaf = 0; }, "voxel_leaf");
  MapParams p;
  p.auto_filter_growth = 0.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// README "Outlier removal at the slab spacing" (rule 17): a face mapped by
// overlapping 2 cm slabs (every 1 cm voxel filled) with one slab at its end
// (one point per 2 x 2 x 2 cm): at 1 cm the end's points have twice the mean
// neighbour distance of the bulk and the removal takes them; judged at 2 cm
// they stay. A stray cluster of three points 3 m off is removed with the rule.
namespace {
PointMap face_with_single_slab_end(double outlier_leaf, bool stray) {
  MapParams mp;
  mp.outlier_leaf = outlier_leaf;
  mp.auto_filter_growth = 0.0;
  PointMap m(mp);
  for (int dx = 0; dx < 2; ++dx)
    for (int dy = 0; dy < 2; ++dy)
      for (int dz = 0; dz < 2; ++dz) {  // mid-face: slabs at every 1 cm offset
        Box b;
        b.center = Vec3(0.5 + 0.01 * dx + 0.003, 0.04 + 0.01 * dy + 0.003, 0.7 + 0.01 * dz + 0.003);
        b.size = Vec3(1.0, 0.08, 0.5);
        m.insert_box(b, 0.02);
      }
  Box end;  // the face's last slab, alone: x 1.0 .. 1.25
  end.center = Vec3(1.125 + 0.003, 0.04 + 0.003, 0.7 + 0.003);
  end.size = Vec3(0.25, 0.08, 0.5);
  m.insert_box(end, 0.02);
  if (stray) m.insert({Vec3(3.0, 2.0, 0.7), Vec3(3.01, 2.0, 0.7), Vec3(3.0, 2.01, 0.7)});
  m.voxel_filter();
  return m;
}
double max_x(const PointMap& m) {
  double x = -1e9;
  for (const auto& p : m.cloud()) x = std::max(x, static_cast<double>(p.x));
  return x;
}
double max_z(const PointMap& m) {
  double z = -1e9;
  for (const auto& p : m.cloud()) z = std::max(z, static_cast<double>(p.z));
  return z;
}
}  // namespace

TEST(PointMap, OutlierRemovalAtTheSlabSpacingKeepsAFacesSingleSlabEnd) {
  PointMap off = face_with_single_slab_end(0.0, false);
  ASSERT_GT(max_x(off), 1.23);
  off.remove_outliers();
  EXPECT_LT(max_x(off), 1.05);  // the end slab taken as outliers (before rule 17)

  PointMap on = face_with_single_slab_end(0.02, false);
  const std::size_t before = on.size();
  const std::size_t removed = on.remove_outliers();
  EXPECT_EQ(before - removed, on.size());
  EXPECT_GT(max_x(on), 1.23);  // the end slab kept

  PointMap stray = face_with_single_slab_end(0.02, true);
  ASSERT_GT(max_x(stray), 2.9);
  stray.remove_outliers();
  EXPECT_GT(max_x(stray), 1.23);  // the end slab kept
  EXPECT_LT(max_x(stray), 2.0);   // the stray cluster removed
}

TEST(MapParams, OutlierLeafMustBeFiniteAndNotNegative) {
  expect_rejected([](MapParams& p) { p.outlier_leaf = -0.01; }, "outlier_leaf");
  MapParams p;
  p.outlier_leaf = std::nan("");
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.outlier_leaf = 0.02;
  EXPECT_NO_THROW(p.validate());
}

// README "Face ends kept by the faces' lines" (rule 18): a right-angled corner
// at (1.25, 0) between face A (outer side y = 0, the object at y > 0) and face
// B (outer side x = 1.25, the object at x < 1.25), each mapped by overlapping
// slabs (every 1 cm voxel filled) up to 0.25 m short of the corner and by one
// slab alone from there to the corner (one point per 2 x 2 x 2 cm). A slab's
// remnant lies past the corner on A's line, outside B (the tilted end of a
// slab past a polygon's corner). The statistical outlier removal takes both
// single-slab ends and the remnant; the kept points' hull cuts the corner with an edge 0.34 m long that
// is supported at its two ends only (not a face). With the rule the two ends
// come back (the map reaches the corner again) and the remnant stays removed;
// so does a stray cluster 3 m off (which alone widens the removal's
// threshold so much that it takes none of the single slabs).
namespace {
PointMap corner_with_single_slab_ends(double face_length, bool stray, double b_length = 1.0, double bound_length = 0.05,
                                      const std::vector<Vec3>& extra = {}) {
  MapParams mp;
  mp.outlier_face_length = face_length;
  mp.outlier_face_bound_length = bound_length;
  mp.auto_filter_growth = 0.0;
  PointMap m(mp);
  const double o = 0.003;  // off the 1 cm voxel boundaries
  for (int du = 0; du < 2; ++du)
    for (int dv = 0; dv < 2; ++dv)
      for (int dz = 0; dz < 2; ++dz) {  // mid-face: slabs at every 1 cm offset
        Box a;  // face A: x 0 .. 1.0, y 0 .. 0.08
        a.center = Vec3(0.5 + 0.01 * du + o, 0.04 + 0.01 * dv + o, 0.7 + 0.01 * dz + o);
        a.size = Vec3(1.0, 0.08, 0.5);
        m.insert_box(a, 0.02);
        Box b;  // face B: x 1.17 .. 1.25, y 0.25 .. 0.25 + b_length
        b.center = Vec3(1.21 - 0.01 * du - o, 0.25 + 0.5 * b_length + 0.01 * dv + o, 0.7 + 0.01 * dz + o);
        b.size = Vec3(0.08, b_length, 0.5);
        m.insert_box(b, 0.02);
      }
  Box end_a;  // A's last slab, alone: x 1.0 .. 1.25
  end_a.center = Vec3(1.125 + o, 0.04 + o, 0.7 + o);
  end_a.size = Vec3(0.25, 0.08, 0.5);
  m.insert_box(end_a, 0.02);
  Box end_b;  // B's first slab, alone: y 0 .. 0.25
  end_b.center = Vec3(1.21 - o, 0.125 + o, 0.7 + o);
  end_b.size = Vec3(0.08, 0.25, 0.5);
  m.insert_box(end_b, 0.02);
  Box remnant;  // past the corner on A's line: x 1.29 .. 1.45, outside B
  remnant.center = Vec3(1.37 + o, 0.04 + o, 0.7 + o);
  remnant.size = Vec3(0.16, 0.08, 0.5);
  m.insert_box(remnant, 0.02);
  if (stray) m.insert({Vec3(3.0, 2.0, 0.7), Vec3(3.01, 2.0, 0.7), Vec3(3.0, 2.01, 0.7)});
  if (!extra.empty()) m.insert(extra);
  m.voxel_filter();
  return m;
}
bool has_point_in(const PointMap& m, double x0, double x1, double y0, double y1) {
  for (const auto& p : m.cloud())
    if (p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1) return true;
  return false;
}
}  // namespace

TEST(PointMap, FaceEndsKeptByTheFacesLinesOutliersOffTheFacesRemoved) {
  PointMap off = corner_with_single_slab_ends(0.0, false);
  ASSERT_TRUE(has_point_in(off, 1.2, 1.26, -0.01, 0.05));  // the corner is mapped
  ASSERT_TRUE(has_point_in(off, 1.3, 1.46, 0.0, 0.09));    // the remnant
  off.remove_outliers();
  EXPECT_FALSE(has_point_in(off, 1.08, 1.26, -0.01, 0.09));  // A's end taken (before rule 18)
  EXPECT_FALSE(has_point_in(off, 1.16, 1.26, -0.01, 0.18));  // B's end taken
  EXPECT_FALSE(has_point_in(off, 1.3, 1.46, 0.0, 0.09));     // the remnant taken

  PointMap on = corner_with_single_slab_ends(0.2, false);
  const std::size_t before = on.size();
  const std::size_t removed = on.remove_outliers();
  EXPECT_EQ(before - removed, on.size());
  EXPECT_TRUE(has_point_in(on, 1.2, 1.26, -0.01, 0.05));  // the corner mapped again: both ends kept
  EXPECT_TRUE(has_point_in(on, 1.08, 1.12, 0.0, 0.01));   // A's end on A's line
  EXPECT_TRUE(has_point_in(on, 1.24, 1.26, 0.1, 0.14));   // B's end on B's line
  EXPECT_FALSE(has_point_in(on, 1.27, 1.46, -0.1, 0.2));  // the remnant outside B stays removed

  PointMap stray = corner_with_single_slab_ends(0.2, true);
  ASSERT_GT(max_x(stray), 2.9);
  stray.remove_outliers();
  EXPECT_LT(max_x(stray), 2.0);  // the stray cluster removed
}

TEST(MapParams, OutlierFaceParametersAreChecked) {
  expect_rejected([](MapParams& p) { p.outlier_face_length = -0.1; }, "outlier_face_length");
  expect_rejected([](MapParams& p) { p.outlier_face_length = std::nan(""); }, "outlier_face_length");
  expect_rejected([](MapParams& p) { p.outlier_face_tolerance = 0.0; }, "outlier_face_tolerance");
  expect_rejected([](MapParams& p) { p.outlier_face_tolerance = 1e-9; }, "outlier_face_tolerance");  // 1e8 bins per metre
  expect_rejected([](MapParams& p) { p.outlier_face_outside = std::numeric_limits<double>::infinity(); }, "outlier_face_outside");
  expect_rejected([](MapParams& p) { p.outlier_face_bound_length = 0.0; }, "outlier_face_bound_length");
  expect_rejected([](MapParams& p) { p.outlier_face_depth = -0.01; }, "outlier_face_depth");
  expect_rejected([](MapParams& p) { p.outlier_face_reach = -0.01; }, "outlier_face_reach");
  expect_rejected([](MapParams& p) { p.outlier_face_support = 0.0; }, "outlier_face_support");
  expect_rejected([](MapParams& p) { p.outlier_face_support = 1.5; }, "outlier_face_support");
  MapParams p;
  p.outlier_face_length = 0.2;
  p.outlier_face_outside = -0.005;
  EXPECT_NO_THROW(p.validate());
}

// Rule 18's bound (outlier_face_bound_length): the corner above with face B
// mapped densely over 0.15 m only, so its hull edge is shorter than
// outlier_face_length. B does not extend, but its short supported edge still
// bounds A's extension: the remnant past the corner stays removed. Without
// the bound (a bound length as long as the face length) the remnant comes
// back with A's end.
TEST(PointMap, FaceEndsKeptOnlyInsideShortSupportedHullEdgesToo) {
  PointMap off = corner_with_single_slab_ends(0.0, false, 0.15);
  off.remove_outliers();
  ASSERT_FALSE(has_point_in(off, 1.08, 1.12, 0.0, 0.01));  // A's end taken
  ASSERT_FALSE(has_point_in(off, 1.3, 1.46, 0.0, 0.09));   // the remnant taken

  PointMap on = corner_with_single_slab_ends(0.2, false, 0.15);
  on.remove_outliers();
  EXPECT_TRUE(has_point_in(on, 1.08, 1.12, 0.0, 0.01));   // A's end kept
  EXPECT_FALSE(has_point_in(on, 1.27, 1.46, -0.1, 0.2));  // the remnant outside B stays removed

  PointMap unbounded = corner_with_single_slab_ends(0.2, false, 0.15, 0.2);
  unbounded.remove_outliers();
  EXPECT_TRUE(has_point_in(unbounded, 1.3, 1.46, 0.0, 0.09));  // without the bound: the remnant back
}

// Rule 18's other limits, each on a lone point the removal takes and only that
// limit keeps out (the corner above; the hull's 8 cm end edge at x = 0 not a
// bound, outlier_face_bound_length 0.2): 0.25 m inside face A (deeper than
// outlier_face_depth), on A's line 0.6 m before its start (beyond
// outlier_face_reach; 0.3 m before it comes back), on A's line 1.8 m above the
// map (off the kept points' height range); and with face B mapped densely
// over 0.15 m only, B's single-slab end stays removed (B bounds but does not
// extend).
TEST(PointMap, FaceEndsKeptOnlyNearAFaceWithinItsReachAndTheMapsHeight) {
  const std::vector<Vec3> lone = {Vec3(0.5, 0.25, 0.7), Vec3(-0.6, 0.04, 0.7), Vec3(-0.3, 0.04, 0.7),
                                  Vec3(0.5, 0.04, 2.5)};
  PointMap off = corner_with_single_slab_ends(0.0, false, 1.0, 0.2, lone);
  off.remove_outliers();
  ASSERT_FALSE(has_point_in(off, 0.49, 0.51, 0.24, 0.26));  // each lone point taken by the removal
  ASSERT_FALSE(has_point_in(off, -0.61, -0.59, 0.03, 0.05));
  ASSERT_FALSE(has_point_in(off, -0.31, -0.29, 0.03, 0.05));
  ASSERT_LT(max_z(off), 2.0);

  PointMap on = corner_with_single_slab_ends(0.2, false, 1.0, 0.2, lone);
  on.remove_outliers();
  EXPECT_TRUE(has_point_in(on, 1.08, 1.12, 0.0, 0.01));       // A's end kept (the rule acts)
  EXPECT_FALSE(has_point_in(on, 0.49, 0.51, 0.24, 0.26));     // deeper than outlier_face_depth
  EXPECT_FALSE(has_point_in(on, -0.61, -0.59, 0.03, 0.05));   // beyond outlier_face_reach
  EXPECT_TRUE(has_point_in(on, -0.31, -0.29, 0.03, 0.05));    // within it
  EXPECT_LT(max_z(on), 2.0);                                   // off the map's height range

  PointMap short_b = corner_with_single_slab_ends(0.2, false, 0.15);
  short_b.remove_outliers();
  EXPECT_TRUE(has_point_in(short_b, 1.08, 1.12, 0.0, 0.01));   // A's end kept
  EXPECT_FALSE(has_point_in(short_b, 1.24, 1.26, 0.1, 0.14));  // B's single-slab end: B too short to extend
}
