// Marching squares and segment chaining (000 Fig. S4f).
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "gpis_explorer/contour.hpp"

using gpis_explorer::Contour;
using gpis_explorer::GridSpec;
using gpis_explorer::marching_squares;

namespace {
std::vector<double> sample(const GridSpec& g, double (*f)(double, double)) {
  std::vector<double> v(g.count());
  for (uint32_t j = 0; j < g.height; ++j) {
    for (uint32_t i = 0; i < g.width; ++i) {
      const auto p = g.node(i, j);
      v[j * g.width + i] = f(p.x(), p.y());
    }
  }
  return v;
}
}  // namespace

TEST(GridSpec, CentredAndValidate) {
  const GridSpec g = GridSpec::centred(1.0, -1.0, 4.0, 10);
  EXPECT_DOUBLE_EQ(g.origin_x, -1.0);
  EXPECT_DOUBLE_EQ(g.origin_y, -3.0);
  EXPECT_NEAR(g.node(9, 9).x(), 3.0, 1e-12);
  EXPECT_NEAR(g.node(9, 9).y(), 1.0, 1e-12);
  EXPECT_EQ(g.nodes().cols(), 100);
  EXPECT_TRUE(g.contains({1.0, -1.0}));
  EXPECT_FALSE(g.contains({3.5, -1.0}));
  GridSpec bad = g;
  bad.width = 1;
  try {
    bad.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GridSpec.width"), std::string::npos);
  }
}

TEST(MarchingSquares, CircleIsOneClosedOrderedContour) {
  const GridSpec g = GridSpec::centred(0, 0, 4.0, 41);
  const auto v = sample(g, [](double x, double y) { return std::hypot(x, y) - 1.0; });
  const auto cs = marching_squares(g, v);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_TRUE(cs[0].closed);
  const auto& P = cs[0].points;
  ASSERT_GT(P.size(), 20u);
  for (std::size_t k = 0; k < P.size(); ++k) {
    EXPECT_NEAR(P[k].norm(), 1.0, 0.01);
    // ordered: consecutive points are neighbours (at most one cell diagonal apart)
    const auto& nxt = P[(k + 1) % P.size()];
    EXPECT_LT((nxt - P[k]).norm(), g.resolution * 1.5);
  }
  // Monotone angle (one way round).
  double turn = 0;
  for (std::size_t k = 0; k < P.size(); ++k) {
    const auto& a = P[k];
    const auto& b = P[(k + 1) % P.size()];
    turn += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  }
  EXPECT_NEAR(std::abs(turn), 2 * M_PI, 1e-9);
}

TEST(MarchingSquares, LineIsOneOpenContourEndingOnTheBorder) {
  const GridSpec g = GridSpec::centred(0, 0, 2.0, 11);
  const auto v = sample(g, [](double x, double y) { return x + 0.5 * y - 0.13; });
  const auto cs = marching_squares(g, v);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_FALSE(cs[0].closed);
  for (const auto& p : cs[0].points) EXPECT_NEAR(p.x() + 0.5 * p.y(), 0.13, 1e-12);  // linear: exact
  auto on_border = [&](const Eigen::Vector2d& p) {
    return std::abs(std::abs(p.x()) - 1.0) < 1e-12 || std::abs(std::abs(p.y()) - 1.0) < 1e-12;
  };
  EXPECT_TRUE(on_border(cs[0].points.front()));
  EXPECT_TRUE(on_border(cs[0].points.back()));
}

TEST(MarchingSquares, TwoCirclesAndSaddle) {
  const GridSpec g = GridSpec::centred(0, 0, 6.0, 61);
  const auto v = sample(g, [](double x, double y) {
    return std::min(std::hypot(x - 1.5, y) - 0.8, std::hypot(x + 1.5, y) - 0.8);
  });
  const auto cs = marching_squares(g, v);
  ASSERT_EQ(cs.size(), 2u);
  EXPECT_TRUE(cs[0].closed && cs[1].closed);
  // Saddle cell: corners (+,-,+,-) with centre mean >= 0 join a and c.
  GridSpec s;
  s.origin_x = 0;
  s.origin_y = 0;
  s.resolution = 1;
  s.width = 2;
  s.height = 2;
  const auto sad = marching_squares(s, {1.0, -1.0, -1.0, 2.0});  // a=1, b=-1, d=-1, c=2: case 5
  ASSERT_EQ(sad.size(), 2u);
  for (const auto& c : sad) {
    EXPECT_FALSE(c.closed);
    EXPECT_EQ(c.points.size(), 2u);
  }
}

TEST(MarchingSquares, DegenerateGrids) {
  const GridSpec g = GridSpec::centred(0, 0, 2.0, 5);
  EXPECT_TRUE(marching_squares(g, std::vector<double>(25, -1.0)).empty());  // no level set
  EXPECT_TRUE(marching_squares(g, std::vector<double>(25, 0.5)).empty());
  EXPECT_THROW(marching_squares(g, std::vector<double>(24, 0.0)), std::invalid_argument);
  std::vector<double> nan(25, NAN);
  nan[12] = 1.0;  // an isolated above node surrounded by NaN (treated below)
  const auto cs = marching_squares(g, nan);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_TRUE(cs[0].closed);
  EXPECT_EQ(cs[0].points.size(), 4u);
  for (const auto& p : cs[0].points) EXPECT_TRUE(p.allFinite());
}
