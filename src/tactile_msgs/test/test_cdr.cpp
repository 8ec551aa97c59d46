// Hand-computed CDR bytes, round trips, error reporting and robustness against bad input.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "tactile_msgs/cdr/serialization.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "std_msgs/msg/header.hpp"

using tactile_msgs::cdr::DecodeError;
using tactile_msgs::cdr::deserialize;
using tactile_msgs::cdr::MessageTraits;
using tactile_msgs::cdr::serialize;

namespace
{

std_msgs::msg::Header make_header(int32_t sec, uint32_t nanosec, const std::string & frame)
{
  std_msgs::msg::Header h;
  h.stamp.sec = sec;
  h.stamp.nanosec = nanosec;
  h.frame_id = frame;
  return h;
}

}  // namespace

TEST(CdrBytes, HeaderHandComputed)
{
  // encapsulation | sec=1 | nanosec=2 | len=3 ("ab" + NUL) | 'a' 'b' NUL
  const std::vector<uint8_t> expected = {
    0x00, 0x01, 0x00, 0x00,
    0x01, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00,
    0x03, 0x00, 0x00, 0x00,
    0x61, 0x62, 0x00};
  EXPECT_EQ(serialize(make_header(1, 2, "ab")), expected);
  std_msgs::msg::Header back;
  deserialize(expected.data(), expected.size(), back);
  EXPECT_EQ(back, make_header(1, 2, "ab"));
}

TEST(CdrBytes, WhiskerPressureHandComputed)
{
  tactile_msgs::msg::WhiskerPressure m;
  m.header = make_header(1, 2, "abc");
  m.whisker_id = tactile_msgs::msg::WhiskerPressure::WHISKER_RIGHT;
  m.pressure = {1.0, -2.0, 0.5};
  m.temperature = {0.0, 2.0, -0.5};
  m.sequence = 0x01020304u;
  // Payload offsets (counted after the 4-byte encapsulation): stamp 0..8, frame_id
  // length 8..12, "abc\0" 12..16, whisker_id 16, padding 17..24 (float64 aligns to 8),
  // pressure 24..48, temperature 48..72, sequence 72..76.
  const std::vector<uint8_t> expected = {
    0x00, 0x01, 0x00, 0x00,
    0x01, 0x00, 0x00, 0x00,  // sec
    0x02, 0x00, 0x00, 0x00,  // nanosec
    0x04, 0x00, 0x00, 0x00,  // frame_id length incl. NUL
    0x61, 0x62, 0x63, 0x00,  // "abc\0"
    0x01,  // whisker_id
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // pad to payload offset 24
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F,  // 1.0
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xC0,  // -2.0
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE0, 0x3F,  // 0.5
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 0.0
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40,  // 2.0
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE0, 0xBF,  // -0.5
    0x04, 0x03, 0x02, 0x01};  // sequence
  const auto bytes = serialize(m);
  EXPECT_EQ(bytes, expected);
  tactile_msgs::msg::WhiskerPressure back;
  deserialize(bytes.data(), bytes.size(), back);
  EXPECT_EQ(back, m);
}

TEST(CdrTraits, TypeNameAndDefinition)
{
  using T = MessageTraits<tactile_msgs::msg::WhiskerPressure>;
  EXPECT_STREQ(T::type_name, "tactile_msgs/msg/WhiskerPressure");
  const std::string sep(80, '=');
  const std::string & def = T::definition();
  EXPECT_NE(def.find("\n" + sep + "\nMSG: std_msgs/Header\n"), std::string::npos);
  EXPECT_NE(def.find("\n" + sep + "\nMSG: builtin_interfaces/Time\n"), std::string::npos);
  EXPECT_EQ(def.rfind("# Raw barometer readings", 0), 0u);
}

TEST(CdrRegistry, FindType)
{
  const auto * info = tactile_msgs::cdr::find_type("tactile_msgs/msg/WhiskerPressure");
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->definition, MessageTraits<tactile_msgs::msg::WhiskerPressure>::definition());
  EXPECT_EQ(tactile_msgs::cdr::find_type("tactile_msgs/WhiskerPressure"), info);
  EXPECT_EQ(tactile_msgs::cdr::find_type("tactile_msgs/msg/Nope"), nullptr);
  EXPECT_NE(tactile_msgs::cdr::find_type("geometry_msgs/msg/PoseStamped"), nullptr);
}
