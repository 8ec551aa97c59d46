// Time helpers and the staleness rule of every fail-safe (tactile_common/time.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tactile_common/time.hpp"

using tactile_common::age_is_fresh;
using tactile_common::input_is_fresh;

TEST(Freshness, AnInputIsFreshWhenStampedAndAtMostMaxAgeOld) {
  EXPECT_TRUE(input_is_fresh(1.0, 0.8, 0.2));   // exactly max age
  EXPECT_FALSE(input_is_fresh(1.0, 0.79, 0.2));
  EXPECT_FALSE(input_is_fresh(1.0, NAN, 0.2));  // never received
  EXPECT_FALSE(input_is_fresh(1.0, -std::numeric_limits<double>::infinity(), 0.2));
  EXPECT_TRUE(input_is_fresh(1.0, 1.5, 0.2));   // stamped ahead: not stale
}

TEST(Freshness, AnAgeFromIntegerNanosecondsAtMaxAgeIsFresh) {
  // 0.3 s as integer nanoseconds is a little more than the double 0.3: the 1 ns of
  // tolerance keeps an input exactly max_age old fresh; 2 ns more is stale.
  ASSERT_GT(tactile_common::to_seconds(300000000), 0.3);
  EXPECT_TRUE(age_is_fresh(tactile_common::to_seconds(300000000), 0.3));
  EXPECT_FALSE(age_is_fresh(tactile_common::to_seconds(300000002), 0.3));
  EXPECT_FALSE(age_is_fresh(NAN, 0.3));
  EXPECT_TRUE(age_is_fresh(-0.1, 0.3));
}

TEST(Time, StampRoundTrip) {
  struct Stamp {
    int32_t sec = 0;
    uint32_t nanosec = 0;
  } s;
  tactile_common::to_stamp(3'250'000'001LL, s);
  EXPECT_EQ(s.sec, 3);
  EXPECT_EQ(s.nanosec, 250'000'001u);
  EXPECT_EQ(tactile_common::from_stamp(s), 3'250'000'001LL);
  tactile_common::to_stamp(-1, s);  // before the epoch: the nanoseconds stay in [0, 1e9)
  EXPECT_EQ(s.sec, -1);
  EXPECT_EQ(s.nanosec, 999'999'999u);
  EXPECT_EQ(tactile_common::from_stamp(s), -1);
  EXPECT_EQ(tactile_common::from_seconds(0.02), 20'000'000LL);
}
