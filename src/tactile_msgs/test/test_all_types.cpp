// Every generated type: round trip with non-trivial values, every truncation throws
// DecodeError, and random or corrupted input never crashes.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"
#include "tactile_msgs/cdr/testing.hpp"

using tactile_msgs::cdr::DecodeError;
using tactile_msgs::cdr::deserialize;
using tactile_msgs::cdr::MessageTraits;
using tactile_msgs::cdr::serialize;
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

template<class T>
class AllTypesTest : public ::testing::Test {};
TYPED_TEST_SUITE(AllTypesTest, AllTypes);

TYPED_TEST(AllTypesTest, RoundTripNonTrivial)
{
  const TypeParam msg = make_filled<TypeParam>();
  ASSERT_FALSE(msg == TypeParam{}) << "filled message equals the default";
  const auto bytes = serialize(msg);
  ASSERT_GE(bytes.size(), 5u);
  EXPECT_EQ(bytes[0], 0x00);
  EXPECT_EQ(bytes[1], 0x01);
  EXPECT_EQ(bytes[2], 0x00);
  EXPECT_EQ(bytes[3], 0x00);
  EXPECT_GE(bytes.size() - 4, MessageTraits<TypeParam>::min_serialized_size);
  TypeParam back{};
  deserialize(bytes.data(), bytes.size(), back);
  EXPECT_TRUE(back == msg);
  EXPECT_EQ(serialize(back), bytes);
  // Default-constructed messages round-trip too.
  TypeParam empty_back = msg;
  const auto empty_bytes = serialize(TypeParam{});
  deserialize(empty_bytes.data(), empty_bytes.size(), empty_back);
  EXPECT_TRUE(empty_back == TypeParam{});
}

TYPED_TEST(AllTypesTest, RandomValuesRoundTrip)
{
  // Pseudo-random values, empty and long sequences and strings (the same generator the
  // ROS 2 stage uses to compare these bytes with rclcpp's).
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const TypeParam msg = make_random<TypeParam>(seed);
    const auto bytes = serialize(msg);
    TypeParam back{};
    deserialize(bytes.data(), bytes.size(), back);
    EXPECT_TRUE(back == msg) << "seed " << seed;
    EXPECT_EQ(serialize(back), bytes) << "seed " << seed;
  }
}

TYPED_TEST(AllTypesTest, EveryTruncationThrowsDecodeError)
{
  const auto bytes = serialize(make_filled<TypeParam>());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    TypeParam out{};
    EXPECT_THROW(deserialize(prefix.data(), prefix.size(), out), DecodeError) << "prefix " << n;
  }
}

TYPED_TEST(AllTypesTest, RandomGarbageNeverCrashes)
{
  std::mt19937_64 rng(12345);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> len(0, 300);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<uint8_t> buf(len(rng));
    for (auto & b : buf) {b = static_cast<uint8_t>(byte(rng));}
    if (buf.size() >= 4 && trial % 2 == 0) {buf[0] = 0; buf[1] = 1;}  // pass the header check
    TypeParam out{};
    try {
      deserialize(buf.data(), buf.size(), out);
    } catch (const DecodeError &) {
    }
  }
}

TYPED_TEST(AllTypesTest, CorruptedBytesNeverCrash)
{
  const auto good = serialize(make_filled<TypeParam>());
  std::mt19937_64 rng(777);
  std::uniform_int_distribution<std::size_t> pos(4, good.size() - 1);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int trial = 0; trial < 300; ++trial) {
    auto buf = good;
    for (int k = 0; k < 1 + trial % 4; ++k) {buf[pos(rng)] = static_cast<uint8_t>(byte(rng));}
    TypeParam out{};
    try {
      deserialize(buf.data(), buf.size(), out);
    } catch (const DecodeError &) {
    }
  }
}

TEST(Registry, AllTypesListedWithDefinitions)
{
  const auto & types = tactile_msgs::cdr::all_types();
  EXPECT_EQ(types.size(), std::tuple_size<tactile_msgs::cdr::testing::AllTypes>::value);
  for (std::size_t i = 0; i < types.size(); ++i) {
    EXPECT_NE(types[i].name.find("/msg/"), std::string_view::npos);
    EXPECT_FALSE(types[i].definition.empty());
    EXPECT_EQ(tactile_msgs::cdr::find_type(types[i].name), &types[i]);
    if (i > 0) {EXPECT_LT(types[i - 1].name, types[i].name);}
  }
}
