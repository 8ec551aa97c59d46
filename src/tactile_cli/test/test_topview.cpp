// Top view PNG: layout (equal scale, everything inside), pixels of walls,
// collisions and trajectory where the layout puts them, errors naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tactile_cli/topview.hpp"

using tactile_cli::TopView;
using tactile_sim::Arena;
using tactile_sim::Vec2;

namespace {

const std::string kArenaDir = std::string(TACTILE_CONFIG_DIR) + "/scenarios/arenas/";

std::string tmp_png(const std::string& name) {
  return testing::TempDir() + "/topview_" + name + ".png";
}

// True if any pixel within r of (x, y) matches the BGR colour within tol.
bool colour_near(const cv::Mat& img, double x, double y, cv::Vec3b bgr, int r = 2, int tol = 40) {
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const int px = static_cast<int>(std::lround(x)) + dx, py = static_cast<int>(std::lround(y)) + dy;
      if (px < 0 || py < 0 || px >= img.cols || py >= img.rows) continue;
      const cv::Vec3b c = img.at<cv::Vec3b>(py, px);
      if (std::abs(c[0] - bgr[0]) <= tol && std::abs(c[1] - bgr[1]) <= tol && std::abs(c[2] - bgr[2]) <= tol) return true;
    }
  }
  return false;
}

}  // namespace

TEST(TopView, LayoutFitsEverythingWithEqualScale) {
  const Arena a = Arena::load(kArenaDir + "room_exit.yaml");
  TopView v;
  v.arena = &a;
  v.trajectory = {{0, 0}, {1.8, 0.1}};  // leaves through the exit
  const auto l = tactile_cli::topview_layout(v, 900);
  // Every point inside the plot area.
  for (const Vec2& p : {Vec2(-1, -1), Vec2(1, 1), Vec2(1.8, 0.1)}) {
    EXPECT_GT(l.px(p.x()), l.left);
    EXPECT_LT(l.px(p.x()), l.left + l.plot_width);
    EXPECT_GT(l.py(p.y()), l.top);
    EXPECT_LT(l.py(p.y()), l.top + l.plot_height);
  }
  // Equal scale: the 2 m square room is square in pixels.
  EXPECT_NEAR(l.px(1) - l.px(-1), l.py(-1) - l.py(1), 1e-9);
  EXPECT_EQ(l.width, 900);
  // A very tall scene is limited in height.
  TopView tall;
  tall.trajectory = {{0, 0}, {0, 100}};
  EXPECT_LE(tactile_cli::topview_layout(tall, 600).plot_height, 900 + 1);
}

TEST(TopView, PixelsWhereTheLayoutPutsThem) {
  const Arena a = Arena::load(kArenaDir + "room_exit.yaml");  // glass walls
  TopView v;
  v.arena = &a;
  v.trajectory = {{0, 0}, {0.5, 0.2}, {0.9, 0.0}};
  v.estimate_trajectory = {{0, 0.05}, {0.9, 0.1}};
  v.whisker_contacts = {{0.95, 0.6}};
  v.collisions = {{-0.5, -0.95}};
  v.poses = {{{0, 0}, 0.0}, {{0.9, 0.0}, 1.0}};
  v.title = "room_exit";
  const std::string path = tmp_png("room");
  std::remove(path.c_str());
  tactile_cli::write_topview_png(path, v, 900);
  const cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const auto l = tactile_cli::topview_layout(v, 900);
  EXPECT_EQ(img.cols, l.width);
  EXPECT_EQ(img.rows, l.height);
  // West wall (x = -1) at y = -0.5 in the glass colour; the exit (x = 1, y = 0) is not.
  const cv::Vec3b glass(230, 160, 60);
  EXPECT_TRUE(colour_near(img, l.px(-1.0), l.py(-0.5), glass));
  EXPECT_TRUE(colour_near(img, l.px(1.0), l.py(0.7), glass));
  EXPECT_FALSE(colour_near(img, l.px(1.0), l.py(0.0), glass, 1));
  // Collision: red cross centre.
  EXPECT_TRUE(colour_near(img, l.px(-0.5), l.py(-0.95), cv::Vec3b(0, 0, 230), 1));
  // Trajectory start is blue (time ramp), end red-ish.
  EXPECT_TRUE(colour_near(img, l.px(0.25), l.py(0.1), cv::Vec3b(255, 128, 0), 2, 130));
  // Empty space inside the room stays white.
  EXPECT_TRUE(colour_near(img, l.px(-0.5), l.py(0.5), cv::Vec3b(255, 255, 255), 0, 20));
}

TEST(TopView, CylindersAndNoArena) {
  const Arena a = Arena::load(kArenaDir + "xplorer_pipe.yaml");
  TopView v;
  v.arena = &a;
  const std::string path = tmp_png("pipe");
  tactile_cli::write_topview_png(path, v);
  const cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const auto l = tactile_cli::topview_layout(v, 900);
  // Rim of the pipe in the rigid colour at (1.15, 0).
  EXPECT_TRUE(colour_near(img, l.px(1.15), l.py(0.0), cv::Vec3b(60, 60, 60), 2));
  // No arena, no data: still a valid picture.
  TopView empty;
  const std::string p2 = tmp_png("empty");
  tactile_cli::write_topview_png(p2, empty);
  EXPECT_FALSE(cv::imread(p2).empty());
  // Non-finite points are skipped.
  TopView nan;
  nan.trajectory = {{0, 0}, {std::nan(""), 1}, {1, 1}};
  EXPECT_NO_THROW(tactile_cli::write_topview_png(tmp_png("nan"), nan));
}

TEST(TopView, ErrorsNameTheFile) {
  TopView v;
  try {
    tactile_cli::write_topview_png("/nonexistent_dir_for_test/x.png", v);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir_for_test/x.png"), std::string::npos);
  }
  try {
    tactile_cli::write_topview_png("narrow.png", v, 100);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("narrow.png"), std::string::npos);
  }
}
