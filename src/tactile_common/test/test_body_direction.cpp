// The body directions of 001 Sec. IV-A shared by the XPLORER FSM and its mapper.
#include "tactile_common/body_direction.hpp"

#include <gtest/gtest.h>

#include <limits>

using tactile_common::BodyDirection;
using tactile_common::contact_direction;
using tactile_common::right_hand;
using tactile_common::unit;

TEST(BodyDirection, UnitVectorsAndNames) {
  EXPECT_EQ(unit(BodyDirection::kPlusX), Eigen::Vector2d(1, 0));
  EXPECT_EQ(unit(BodyDirection::kMinusX), Eigen::Vector2d(-1, 0));
  EXPECT_EQ(unit(BodyDirection::kPlusY), Eigen::Vector2d(0, 1));
  EXPECT_EQ(unit(BodyDirection::kMinusY), Eigen::Vector2d(0, -1));
  EXPECT_EQ(unit(BodyDirection::kNone), Eigen::Vector2d(0, 0));
  EXPECT_STREQ(to_string(BodyDirection::kPlusX), "+X");
  EXPECT_STREQ(to_string(BodyDirection::kMinusY), "-Y");
  EXPECT_STREQ(to_string(BodyDirection::kNone), "none");
}

// 001 Sec. IV-A right-hand traversal: lambda = C_n turned by -90 deg.
TEST(BodyDirection, RightHandMoveIsTheContactTurnedClockwise) {
  for (auto c : {BodyDirection::kPlusX, BodyDirection::kMinusX, BodyDirection::kPlusY, BodyDirection::kMinusY}) {
    const Eigen::Vector2d n = unit(c), m = unit(right_hand(c));
    EXPECT_DOUBLE_EQ(m.x(), n.y()) << to_string(c);  // (x, y) turned by -90 deg: (y, -x)
    EXPECT_DOUBLE_EQ(m.y(), -n.x()) << to_string(c);
  }
  EXPECT_EQ(right_hand(BodyDirection::kPlusX), BodyDirection::kMinusY);  // obstacle ahead: move right
  EXPECT_EQ(right_hand(BodyDirection::kNone), BodyDirection::kNone);
}

// The obstacle lies opposite to the force it exerts; the larger component decides; at or
// below the threshold, or non-finite: none.
TEST(BodyDirection, ContactDirectionFromTheBodyForce) {
  EXPECT_EQ(contact_direction({-2.0, 0.5}, 1.5), BodyDirection::kPlusX);  // pushed back: obstacle ahead
  EXPECT_EQ(contact_direction({2.0, 0.5}, 1.5), BodyDirection::kMinusX);
  EXPECT_EQ(contact_direction({0.3, 1.6}, 1.5), BodyDirection::kMinusY);  // pushed left: obstacle right
  EXPECT_EQ(contact_direction({0.3, -1.6}, 1.5), BodyDirection::kPlusY);
  EXPECT_EQ(contact_direction({1.4, -1.4}, 1.5), BodyDirection::kNone);
  EXPECT_EQ(contact_direction({-1.5, 0.0}, 1.5), BodyDirection::kNone);  // at the threshold: not above it
  EXPECT_EQ(contact_direction({-2.0, 2.0}, 1.5), BodyDirection::kPlusX);  // a tie goes to x
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(contact_direction({nan, 0.0}, 1.5), BodyDirection::kNone);
  EXPECT_EQ(contact_direction({-2.0, std::numeric_limits<double>::infinity()}, 0.0), BodyDirection::kNone);
}
