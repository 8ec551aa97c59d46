// The message contract proven against rosidl: for every tactile_msgs type and every
// standard type the workspace uses, the ROS-free CDR bytes (tactile_msgs::cdr, the code
// the standalone host and its bags use) equal rclcpp::Serialization<T>'s bytes (the
// rosidl type support of the installed distro over its rmw), and each side reads the
// other's bytes back to an equal message. Values: the deterministic filler and
// pseudo-random ones with empty and long (100-300 element) sequences and strings.
// Padding: see rclcpp_bytes().
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "rclcpp/serialization.hpp"
#include "rclcpp/serialized_message.hpp"
#include "tactile_msgs/cdr/serialization.hpp"
#include "tactile_msgs/cdr/testing.hpp"

namespace {

using tactile_msgs::cdr::testing::make_filled;
using tactile_msgs::cdr::testing::make_random;

template<class Tuple>
struct ToTestTypes;
template<class ... Ts>
struct ToTestTypes<std::tuple<Ts...>>
{
  using type = ::testing::Types<Ts...>;
};
using AllTypes = ToTestTypes<tactile_msgs::cdr::testing::AllTypes>::type;

// Fast CDR writes alignment padding by skipping bytes, so they keep whatever the buffer
// held (CDR leaves the padding's value open; ours is zero). The buffer is therefore
// allocated large enough for the message up front and zeroed, which makes the padding
// comparable; rmw grows a buffer only when it is too small for the message.
template<class T>
std::vector<uint8_t> rclcpp_bytes(const T & msg)
{
  rclcpp::Serialization<T> serialization;
  const std::size_t capacity = 2 * tactile_msgs::cdr::serialize(msg).size() + 4096;
  rclcpp::SerializedMessage serialized(capacity);
  auto & buffer = serialized.get_rcl_serialized_message();
  std::memset(buffer.buffer, 0, buffer.buffer_capacity);
  serialization.serialize_message(&msg, &serialized);
  const auto & raw = serialized.get_rcl_serialized_message();
  return std::vector<uint8_t>(raw.buffer, raw.buffer + raw.buffer_length);
}

template<class T>
T rclcpp_read(const std::vector<uint8_t> & bytes)
{
  rclcpp::SerializedMessage serialized(bytes.size());
  auto & raw = serialized.get_rcl_serialized_message();
  std::memcpy(raw.buffer, bytes.data(), bytes.size());
  raw.buffer_length = bytes.size();
  T msg{};
  rclcpp::Serialization<T>().deserialize_message(&serialized, &msg);
  return msg;
}

std::string first_difference(const std::vector<uint8_t> & a, const std::vector<uint8_t> & b)
{
  std::ostringstream os;
  os << "sizes " << a.size() << " (ours) vs " << b.size() << " (rclcpp)";
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (a[i] != b[i]) {
      os << ", first difference at byte " << i << ": " << int(a[i]) << " vs " << int(b[i]);
      break;
    }
  }
  return os.str();
}

template<class T>
void expect_same_both_ways(const T & msg, const std::string & what)
{
  const std::vector<uint8_t> ours = tactile_msgs::cdr::serialize(msg);
  const std::vector<uint8_t> theirs = rclcpp_bytes(msg);
  // rmw_fastrtps ends some messages with up to 7 zero bytes after the last field
  // (std_msgs/Bool: 5 -> 8 bytes; ThrustCommand with an empty float64[] last: 40 -> 44,
  // the alignment of the empty sequence's elements); readers ignore bytes after the message.
  const bool end_padded = theirs.size() > ours.size() && theirs.size() % 4 == 0 &&
                          theirs.size() - ours.size() < 8 &&
                          std::all_of(theirs.begin() + static_cast<std::ptrdiff_t>(ours.size()), theirs.end(),
                                      [](uint8_t b) {return b == 0;});
  const std::vector<uint8_t> compared =
    end_padded ? std::vector<uint8_t>(theirs.begin(), theirs.begin() + static_cast<std::ptrdiff_t>(ours.size())) : theirs;
  EXPECT_EQ(ours, compared) << what << ": " << first_difference(ours, theirs);
  // rclcpp reads our bytes ...
  EXPECT_TRUE(rclcpp_read<T>(ours) == msg) << what << ": rclcpp read our bytes to another message";
  // ... and we read rclcpp's.
  T back{};
  tactile_msgs::cdr::deserialize(theirs.data(), theirs.size(), back);
  EXPECT_TRUE(back == msg) << what << ": our decoder read rclcpp's bytes to another message";
}

template<class T>
class CdrVsRclcpp : public ::testing::Test {};
TYPED_TEST_SUITE(CdrVsRclcpp, AllTypes);

TYPED_TEST(CdrVsRclcpp, DefaultMessage)
{
  expect_same_both_ways(TypeParam{}, "default-constructed");
}

TYPED_TEST(CdrVsRclcpp, FilledMessage)
{
  expect_same_both_ways(make_filled<TypeParam>(), "filled");
}

TYPED_TEST(CdrVsRclcpp, RandomMessages)
{
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    expect_same_both_ways(make_random<TypeParam>(seed), "random seed " + std::to_string(seed));
    if (::testing::Test::HasFailure()) {
      break;  // one seed's messages say enough
    }
  }
}

TEST(CdrVsRclcpp, RandomFillerReachesEmptyAndLongSequences)
{
  // The generator the tests above rely on: over 60 seeds a PointCloud2 gets both an empty
  // and a >= 100 element data field, and its strings both empty and long.
  bool empty = false;
  bool long_seq = false;
  bool empty_str = false;
  bool long_str = false;
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    const auto m = make_random<sensor_msgs::msg::PointCloud2>(seed);
    empty = empty || m.data.empty();
    long_seq = long_seq || m.data.size() >= 100;
    empty_str = empty_str || m.header.frame_id.empty();
    long_str = long_str || m.header.frame_id.size() >= 100;
  }
  EXPECT_TRUE(empty && long_seq && empty_str && long_str);
}

}  // namespace
