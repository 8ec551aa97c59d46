// Typed layer: tactile_msgs types written and decoded through the bag.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "sample.hpp"
#include "std_msgs/msg/string.hpp"
#include "tactile_bag/typed.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"

namespace fs = std::filesystem;

namespace {

std::string temp_bag() {
  std::random_device rd;
  return (fs::temp_directory_path() /
          ("tactile_bag_typed_" + std::to_string(::getpid()) + "_" + std::to_string(rd())))
      .string();
}

tactile_msgs::msg::WhiskerPressure make(int i) {
  tactile_msgs::msg::WhiskerPressure m;
  const int64_t t = 1000000000LL + i * 20000000LL;
  m.header.stamp.sec = static_cast<int32_t>(t / 1000000000);
  m.header.stamp.nanosec = static_cast<uint32_t>(t % 1000000000);
  m.header.frame_id = "whisker_left";
  m.whisker_id = tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT;
  for (int k = 0; k < 3; ++k) {
    m.pressure[k] = 101325.0 + 10 * i + k;
    m.temperature[k] = 25.0 + 0.5 * k;
  }
  m.sequence = static_cast<uint32_t>(i);
  return m;
}

}  // namespace

TEST(Typed, WriteCreatesTopicAndDecodeRoundTrips) {
  const std::string dir = temp_bag();
  {
    tactile_bag::Writer w;
    w.open(dir);
    for (int i = 0; i < 3; ++i) {
      w.write("/whisker/left/pressure", 1000000000LL + i * 20000000LL, make(i));
    }
    std_msgs::msg::String s;
    s.data = "typed";
    w.write("/chatter", 5, s);
    EXPECT_THROW(w.write("/chatter", 6, make(0)), tactile_bag::BagError);  // type mismatch
  }
  tactile_bag::Reader r(dir);
  const auto* t = r.find_topic("/whisker/left/pressure");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->type, "tactile_msgs/msg/WhiskerPressure");
  EXPECT_EQ(t->type_definition,
            tactile_msgs::cdr::MessageTraits<tactile_msgs::msg::WhiskerPressure>::definition());
  EXPECT_EQ(t->definition_encoding, "ros2msg");
  EXPECT_EQ(r.find_topic("/chatter")->type, "std_msgs/msg/String");
  tactile_bag::SerializedMessage m;
  ASSERT_TRUE(r.read_next(m));
  EXPECT_EQ(m.topic, "/chatter");
  EXPECT_EQ(tactile_bag::decode<std_msgs::msg::String>(m).data, "typed");
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(r.read_next(m));
    const auto got = tactile_bag::decode<tactile_msgs::msg::WhiskerPressure>(m);
    EXPECT_EQ(got, make(i));
    // Independent check: the hand-written CDR encoder of the sample gives the same bytes.
    const auto ref = make(i);
    const int64_t stamp = 1000000000LL + i * 20000000LL;
    EXPECT_EQ(m.data, tactile_bag::sample::whisker_pressure(stamp, "whisker_left", 0,
                                                            ref.pressure.data(),
                                                            ref.temperature.data(), ref.sequence));
  }
  EXPECT_FALSE(r.read_next(m));
  fs::remove_all(dir);
}

TEST(Typed, DecodeErrorNamesTopicAndTimestamp) {
  tactile_bag::SerializedMessage m;
  m.topic = "/whisker/left/pressure";
  m.timestamp_ns = 42;
  m.data = tactile_msgs::cdr::serialize(make(1));
  m.data.resize(m.data.size() / 2);  // truncated
  try {
    tactile_bag::decode<tactile_msgs::msg::WhiskerPressure>(m);
    FAIL() << "expected BagError";
  } catch (const tactile_bag::BagError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("/whisker/left/pressure"), std::string::npos) << msg;
    EXPECT_NE(msg.find("42"), std::string::npos) << msg;
    EXPECT_NE(msg.find("WhiskerPressure"), std::string::npos) << msg;
  }
}
