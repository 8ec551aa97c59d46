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

// ---------------------------------------------------------------------------
// Error reporting

TEST(CdrErrors, StringLengthPastEndNamesFieldAndOffset)
{
  auto bytes = serialize(make_header(1, 2, "ab"));
  bytes[12] = 0xFF;  // frame_id length (payload offset 8, buffer offset 12) = 255
  std_msgs::msg::Header h;
  try {
    deserialize(bytes.data(), bytes.size(), h);
    FAIL() << "no DecodeError";
  } catch (const DecodeError & e) {
    EXPECT_EQ(e.type_name(), "std_msgs/msg/Header");
    EXPECT_EQ(e.field(), "frame_id");
    EXPECT_EQ(e.offset(), 12u);
    EXPECT_NE(std::string(e.what()).find("std_msgs/msg/Header"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("frame_id"), std::string::npos);
  }
}

TEST(CdrErrors, MissingNulTerminator)
{
  auto bytes = serialize(make_header(1, 2, "ab"));
  bytes.back() = 'c';
  std_msgs::msg::Header h;
  try {
    deserialize(bytes.data(), bytes.size(), h);
    FAIL() << "no DecodeError";
  } catch (const DecodeError & e) {
    EXPECT_EQ(e.field(), "frame_id");
    EXPECT_NE(std::string(e.what()).find("NUL"), std::string::npos);
  }
}

TEST(CdrErrors, NestedFieldPathWithIndex)
{
  geometry_msgs::msg::PoseArray pa;
  pa.header = make_header(0, 0, "");
  pa.poses.resize(2);
  auto bytes = serialize(pa);
  // Payload: header = stamp 8 + frame_id length 4 + "\0" 1 = 13 bytes; count at 16..20;
  // poses from 24 (float64 alignment), 56 bytes each: poses[1] at 80, its orientation.w
  // at 80 + 48 = 128..136, i.e. buffer offsets 132..140 (140 bytes in all). The count
  // check (2 poses need >= 112 bytes after the count) passes for any cut >= 136.
  ASSERT_EQ(bytes.size(), 140u);
  const std::size_t cut = 136;
  geometry_msgs::msg::PoseArray back;
  try {
    deserialize(bytes.data(), cut, back);
    FAIL() << "no DecodeError";
  } catch (const DecodeError & e) {
    EXPECT_EQ(e.type_name(), "geometry_msgs/msg/PoseArray");
    EXPECT_EQ(e.field(), "poses[1].orientation.w");
    EXPECT_EQ(e.offset(), 132u);
  }
  // A cut before that trips the count check, reported at the count field.
  try {
    deserialize(bytes.data(), 100, back);
    FAIL() << "no DecodeError";
  } catch (const DecodeError & e) {
    EXPECT_EQ(e.field(), "poses");
    EXPECT_EQ(e.offset(), 20u);
  }
}

TEST(CdrErrors, HugeSequenceCountRejectedBeforeAllocation)
{
  tactile_msgs::msg::GpisMap m;
  auto bytes = serialize(m);
  // header (13) -> origin_x at 16, origin_y 24, resolution 32, width 40, height 44,
  // mean count at payload 48 = buffer 52.
  bytes[52] = 0xFF; bytes[53] = 0xFF; bytes[54] = 0xFF; bytes[55] = 0x7F;
  tactile_msgs::msg::GpisMap back;
  try {
    deserialize(bytes.data(), bytes.size(), back);
    FAIL() << "no DecodeError";
  } catch (const DecodeError & e) {
    EXPECT_EQ(e.field(), "mean");
    EXPECT_EQ(e.offset(), 52u);
  }
  EXPECT_EQ(back.mean.capacity(), 0u);
}

TEST(CdrErrors, BadEncapsulationAndShortInput)
{
  std_msgs::msg::Header h;
  const uint8_t be[] = {0x00, 0x00, 0x00, 0x00, 0, 0, 0, 0};
  EXPECT_THROW(deserialize(be, sizeof(be), h), DecodeError);
  const uint8_t shorty[] = {0x00, 0x01};
  EXPECT_THROW(deserialize(shorty, sizeof(shorty), h), DecodeError);
  EXPECT_THROW(deserialize(static_cast<const uint8_t *>(nullptr), 0, h), DecodeError);
}

TEST(CdrErrors, BoundsEnforcedWhenWriting)
{
  tactile_msgs::cdr::CdrWriter w;
  EXPECT_THROW(w.write_string("abcd", 3), std::length_error);
  EXPECT_THROW(w.write_count(5, 4), std::length_error);
  EXPECT_NO_THROW(w.write_string("abc", 3));
}
