#include <gtest/gtest.h>

#include <cstdint>

#include "tactile_common/ports.hpp"

namespace {

struct Msg {
  int value = 0;
};

// The receive time is read only for a handler that takes it (rclcpp now() is not free).
TEST(Ports, DeliverReadsTheClockOnlyForAHandlerTakingTheReceiveTime) {
  int clock_reads = 0;
  auto now = [&clock_reads] {
    ++clock_reads;
    return int64_t{42};
  };
  int got = 0;
  auto without_time = [&got](const Msg& m) { got = m.value; };
  tactile_common::ports::deliver(without_time, Msg{3}, now);
  EXPECT_EQ(got, 3);
  EXPECT_EQ(clock_reads, 0);

  int64_t at = 0;
  auto with_time = [&got, &at](const Msg& m, int64_t receive_ns) {
    got = m.value;
    at = receive_ns;
  };
  tactile_common::ports::deliver(with_time, Msg{5}, now);
  EXPECT_EQ(got, 5);
  EXPECT_EQ(at, 42);
  EXPECT_EQ(clock_reads, 1);
}

}  // namespace
