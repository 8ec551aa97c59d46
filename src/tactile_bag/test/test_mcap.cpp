// mcap storage and distro layouts: round trips through Writer/Reader, checked against
// independent expectations (order, counts, bytes, Humble's Range layout).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "sensor_msgs/msg/range.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_bag/distro.hpp"
#include "tactile_bag/typed.hpp"

namespace fs = std::filesystem;
using tactile_bag::BagError;
using tactile_bag::Reader;
using tactile_bag::SerializedMessage;
using tactile_bag::Writer;
using tactile_bag::WriterOptions;

namespace {

std::string temp_bag(const char* tag) {
  std::random_device rd;
  return (fs::temp_directory_path() / ("tactile_bag_mcap_" + std::string(tag) + "_" +
                                       std::to_string(::getpid()) + "_" + std::to_string(rd())))
      .string();
}

WriterOptions mcap_options(const std::string& compression, uint64_t chunk_size) {
  WriterOptions o;
  o.storage = "mcap";
  o.compression = compression;
  o.chunk_size = chunk_size;
  o.ros_distro = "kilted";
  return o;
}

class McapRoundTrip : public ::testing::TestWithParam<std::string> {};

// Out-of-order timestamps across many small chunks and two topics: read back in timestamp
// order, ties in write order, bytes intact; the topic filter keeps only its topic.
TEST_P(McapRoundTrip, OrderCountsBytesAndFilter) {
  const std::string dir = temp_bag("rt");
  std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>> written;
  {
    Writer w(mcap_options(GetParam(), 256));
    w.open(dir);
    for (const char* t : {"/a", "/b"}) {
      tactile_bag::TopicInfo info;
      info.name = t;
      info.type = "std_msgs/msg/String";
      info.type_definition = "string data\n";
      w.create_topic(info);
    }
    std::mt19937 rng(3);
    for (int i = 0; i < 500; ++i) {
      const int64_t ts = 1000 + (i % 7 == 0 ? i * 10 - 300 : i * 10) - (i % 5 == 0 ? 10 : 0);  // ties too
      std::vector<uint8_t> data(8 + rng() % 40);
      for (auto& b : data) b = static_cast<uint8_t>(rng());
      const std::string topic = i % 3 == 0 ? "/b" : "/a";
      w.write(topic, ts, data);
      written.emplace_back(ts, topic, data);
    }
    w.close();
  }
  std::stable_sort(written.begin(), written.end(),
                   [](const auto& x, const auto& y) { return std::get<0>(x) < std::get<0>(y); });
  Reader r(dir);
  EXPECT_EQ(r.storage_identifier(), "mcap");
  EXPECT_TRUE(r.metadata_complete()) << r.recovery_note();
  EXPECT_EQ(r.message_count(), 500u);
  EXPECT_EQ(r.message_count("/b"), 167u);
  EXPECT_EQ(r.start_time_ns(), std::get<0>(written.front()));
  SerializedMessage m;
  size_t i = 0;
  while (r.read_next(m)) {
    ASSERT_LT(i, written.size());
    EXPECT_EQ(m.timestamp_ns, std::get<0>(written[i])) << i;
    EXPECT_EQ(m.topic, std::get<1>(written[i])) << i;
    EXPECT_EQ(m.data, std::get<2>(written[i])) << i;
    ++i;
  }
  EXPECT_EQ(i, 500u);
  r.set_topic_filter({"/b"});
  size_t nb = 0;
  while (r.read_next(m)) {
    EXPECT_EQ(m.topic, "/b");
    ++nb;
  }
  EXPECT_EQ(nb, 167u);
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Compression, McapRoundTrip, ::testing::Values("", "zstd", "lz4"));

sensor_msgs::msg::Range range(int i) {
  sensor_msgs::msg::Range m;
  m.header.stamp.sec = 1;
  m.header.stamp.nanosec = static_cast<uint32_t>(i);
  m.header.frame_id = i % 2 == 0 ? "tof_down" : "tof";  // both string paddings
  m.radiation_type = sensor_msgs::msg::Range::INFRARED;
  m.field_of_view = 0.47F;
  m.min_range = 0.01F;
  m.max_range = 4.0F;
  m.range = 0.5F + 0.01F * static_cast<float>(i);
  m.variance = 4e-6F;
  return m;
}

// Humble bag: definition without variance, payload 4 bytes shorter, no hashes, metadata v5;
// read back, the variance is 0 (unknown) and everything else intact.
TEST(Distro, HumbleRangeLayoutWrittenAndUpgradedOnRead) {
  for (const std::string storage : {"mcap", "sqlite3"}) {
    const std::string dir = temp_bag("humble");
    {
      WriterOptions o;
      o.storage = storage;
      o.ros_distro = "humble";
      Writer w(o);
      w.open(dir);
      for (int i = 0; i < 4; ++i) w.write("/tof", 1000000000LL + i, range(i));
      w.close();
    }
    std::ifstream meta(dir + "/metadata.yaml");
    const std::string text((std::istreambuf_iterator<char>(meta)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("version: 5"), std::string::npos) << text;
    Reader r(dir);
    const auto* t = r.find_topic("/tof");
    ASSERT_NE(t, nullptr);
    EXPECT_EQ(t->type_definition.find("variance"), std::string::npos) << t->type_definition;
    EXPECT_TRUE(t->type_description_hash.empty());
    ASSERT_EQ(r.upgraded_range_topics(), std::vector<std::string>{"/tof"});
    SerializedMessage m;
    int i = 0;
    while (r.read_next(m)) {
      const auto full = tactile_msgs::cdr::serialize(range(i));
      // Humble payload on disk = ours without the trailing 4 bytes; read back with variance 0.
      auto want = range(i);
      want.variance = 0.0F;
      EXPECT_EQ(m.data, tactile_msgs::cdr::serialize(want)) << storage << " " << i;
      EXPECT_EQ(tactile_bag::range_payload_size_without_variance(full.data(), full.size()) + 4, full.size());
      ++i;
    }
    EXPECT_EQ(i, 4);
    fs::remove_all(dir);
  }
}

// A bag recorded before FsmState gained reason_code, contact_direction and move_direction
// (its stored definition lacks them; each payload ends at `transitions`) reads back as the
// current type with the three fields 0; a bag with the current definition is read as is.
TEST(Distro, FsmStateWithoutReasonCodeIsUpgradedOnRead) {
  const auto state = [](int i) {
    tactile_msgs::msg::FsmState m;
    m.header.stamp.sec = i;
    m.header.frame_id = "odom";
    m.behaviour = "xplorer_exploration";
    m.state = "tactile_traversal";
    m.previous_state = "exploration";
    m.reason = "contact: averaged body force above delta_0";
    m.time_in_state = 0.25 * i;
    m.transitions = static_cast<uint32_t>(3 + i);
    return m;
  };
  std::string old_definition = tactile_msgs::cdr::MessageTraits<tactile_msgs::msg::FsmState>::definition();
  for (const char* field : {"reason_code", "contact_direction", "move_direction"}) {
    old_definition = tactile_bag::remove_field_from_definition(old_definition, "tactile_msgs/msg/FsmState",
                                                               "tactile_msgs/msg/FsmState", field);
  }
  ASSERT_FALSE(tactile_bag::definition_has_field(old_definition, "tactile_msgs/msg/FsmState",
                                                 "tactile_msgs/msg/FsmState", "reason_code"));
  for (const std::string storage : {"mcap", "sqlite3"}) {
    const std::string dir = temp_bag("fsm_old");
    {
      WriterOptions o;
      o.storage = storage;
      Writer w(o);
      w.open(dir);
      tactile_bag::TopicInfo t;
      t.name = "/xplorer/fsm_state";
      t.type = "tactile_msgs/msg/FsmState";
      t.type_definition = old_definition;
      w.create_topic(t);
      for (int i = 0; i < 3; ++i) {
        auto bytes = tactile_msgs::cdr::serialize(state(i));
        bytes.resize(bytes.size() - 3);  // the old layout: nothing after `transitions`
        w.write("/xplorer/fsm_state", 1000000000LL + i, bytes);
      }
      // The current layout on another topic is not touched (mcap: a schema per channel;
      // sqlite3 stores one definition per type, as rosbag2 does).
      if (storage == "mcap") {
        auto now = state(7);
        now.reason_code = tactile_msgs::msg::FsmState::REASON_XPLORER_CONTACT;
        now.contact_direction = tactile_msgs::msg::FsmState::DIRECTION_PLUS_X;
        now.move_direction = tactile_msgs::msg::FsmState::DIRECTION_PLUS_Y;
        w.write("/fsm_state", 2000000000LL, now);
      }
      w.close();
    }
    Reader r(dir);
    EXPECT_EQ(r.upgraded_fsm_state_topics(), std::vector<std::string>{"/xplorer/fsm_state"}) << storage;
    SerializedMessage m;
    int i = 0;
    while (r.read_next(m)) {
      const auto got = tactile_bag::decode<tactile_msgs::msg::FsmState>(m);
      if (m.topic == "/fsm_state") {
        EXPECT_EQ(got.reason_code, tactile_msgs::msg::FsmState::REASON_XPLORER_CONTACT);
        EXPECT_EQ(got.move_direction, tactile_msgs::msg::FsmState::DIRECTION_PLUS_Y);
        continue;
      }
      EXPECT_EQ(m.data, tactile_msgs::cdr::serialize(state(i))) << storage << " " << i;
      EXPECT_EQ(got.transitions, static_cast<uint32_t>(3 + i));
      EXPECT_EQ(got.reason_code, tactile_msgs::msg::FsmState::REASON_NONE);
      ++i;
    }
    EXPECT_EQ(i, 3) << storage;
    fs::remove_all(dir);
  }
}

// Jazzy/Kilted bags keep the variance and carry the RIHS01 hash of the layout.
TEST(Distro, KiltedRangeKeepsVarianceAndHash) {
  const std::string dir = temp_bag("kilted");
  {
    Writer w(mcap_options("", 1 << 20));
    w.open(dir);
    w.write("/tof", 5, range(1));
  }
  Reader r(dir);
  const auto* t = r.find_topic("/tof");
  ASSERT_NE(t, nullptr);
  // sensor_msgs/msg/Range of Kilted (share/sensor_msgs/msg/Range.json of the toolchain).
  EXPECT_EQ(t->type_description_hash,
            "RIHS01_b42b62562e93cbfe9d42b82fe5994dfa3d63d7d5c90a317981703f7388adff3a");
  EXPECT_TRUE(r.upgraded_range_topics().empty());
  SerializedMessage m;
  ASSERT_TRUE(r.read_next(m));
  EXPECT_EQ(tactile_bag::decode<sensor_msgs::msg::Range>(m).variance, 4e-6F);
  fs::remove_all(dir);
}

// A killed mcap recording (no footer) is read up to its last complete chunk, with a note.
TEST(McapErrors, TruncatedFileIsRecoveredWithANote) {
  const std::string dir = temp_bag("cut");
  std::string file;
  {
    Writer w(mcap_options("zstd", 200));
    w.open(dir);
    for (int i = 0; i < 100; ++i) w.write("/tof", 1000 + i, range(i));
    file = w.db_path();
  }
  const auto size = fs::file_size(file);
  fs::resize_file(file, size / 2);  // inside the data section
  Reader r(dir);
  EXPECT_FALSE(r.metadata_complete());
  EXPECT_NE(r.recovery_note().find("no mcap footer"), std::string::npos) << r.recovery_note();
  EXPECT_GT(r.message_count(), 0u);
  EXPECT_LT(r.message_count(), 100u);
  SerializedMessage m;
  uint64_t n = 0;
  while (r.read_next(m)) ++n;
  EXPECT_EQ(n, r.message_count());
  fs::remove_all(dir);
}

TEST(McapErrors, WriterOptionsAreChecked) {
  WriterOptions o;
  o.storage = "rosbag_v1";
  EXPECT_THROW(Writer{o}, BagError);
  o.storage = "sqlite3";
  o.compression = "zstd";
  EXPECT_THROW(Writer{o}, BagError);
  o.storage = "mcap";
  o.compression = "bz2";
  EXPECT_THROW(Writer{o}, BagError);
  o.compression = "";
  o.ros_distro = "rolling";
  EXPECT_THROW(Writer{o}, BagError);
}

// flush_interval 0 (what `tactile sim` records with): the file depends on the messages
// alone. A writer that pauses longer than the flush interval in the middle of a recording
// writes the same bytes as one that does not; with the default interval (250 ms, live
// recordings) the pause commits a chunk early and the files differ, which is what made a
// simulated trial's bag depend on the machine's speed and on --jobs.
TEST(Reproducible, ZeroFlushIntervalFileDependsOnTheMessagesNotTheTiming) {
  // One directory name for every recording: the storage file and the metadata inside it are
  // named after it.
  const std::string dir = temp_bag("repro");
  auto record = [&dir](const std::string& storage, std::chrono::milliseconds interval, bool pause) {
    WriterOptions o;
    o.storage = storage;
    o.ros_distro = "kilted";
    o.flush_interval = interval;
    o.chunk_size = 800;  // 400 messages: commits by size in the middle of the recording
    {
      Writer w(o);
      w.open(dir);
      tactile_bag::TopicInfo t;
      t.name = "/counter";
      t.type = "std_msgs/msg/UInt64";
      w.create_topic(t);
      for (uint64_t i = 0; i < 400; ++i) {
        if (pause && i == 100) std::this_thread::sleep_for(std::chrono::milliseconds(400));
        uint8_t payload[8];
        std::memcpy(payload, &i, 8);
        w.write("/counter", static_cast<int64_t>(1000 + i), payload, 8);
      }
      w.close();
    }
    std::map<std::string, std::string> files;  // by extension
    for (const auto& e : fs::directory_iterator(dir)) {
      std::ifstream in(e.path(), std::ios::binary);
      files[e.path().extension().string()] = std::string(std::istreambuf_iterator<char>(in), {});
    }
    Reader r(dir);
    EXPECT_EQ(r.message_count(), 400u);
    fs::remove_all(dir);
    return files;
  };
  auto expect_same = [](const std::map<std::string, std::string>& a, const std::map<std::string, std::string>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [ext, bytes] : a) {
      SCOPED_TRACE(ext);
      ASSERT_EQ(b.count(ext), 1u);
      if (ext == ".yaml") {
        EXPECT_EQ(bytes, b.at(ext));
      } else {
        EXPECT_TRUE(bytes == b.at(ext)) << bytes.size() << " vs " << b.at(ext).size() << " bytes";
      }
    }
  };
  const auto zero = std::chrono::milliseconds(0);
  const auto steady = record("mcap", zero, false);
  ASSERT_EQ(steady.count(".mcap"), 1u);
  expect_same(steady, record("mcap", zero, true));
  const auto live = std::chrono::milliseconds(250);
  EXPECT_NE(record("mcap", live, false).at(".mcap"), record("mcap", live, true).at(".mcap"))
      << "a 400 ms pause no longer commits a chunk with the 250 ms interval: this test cannot fail";
  // sqlite3: transactions by size, so the same commits and the same database file.
  const auto db = record("sqlite3", zero, false);
  ASSERT_EQ(db.count(".db3"), 1u);
  expect_same(db, record("sqlite3", zero, true));
  // Out of range.
  WriterOptions bad;
  bad.flush_interval = std::chrono::milliseconds(-1);
  EXPECT_THROW(Writer{bad}, BagError);
  bad.flush_interval = std::chrono::milliseconds(1001);
  EXPECT_THROW(Writer{bad}, BagError);
}

}  // namespace
