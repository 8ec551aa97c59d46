// Round trip, ordering, metadata content and error reporting of tactile_bag.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "bag_test_files.hpp"
#include "sample.hpp"
#include "tactile_bag/bag.hpp"

namespace fs = std::filesystem;
using tactile_bag::BagError;
using tactile_bag::Reader;
using tactile_bag::SerializedMessage;
using tactile_bag::TopicInfo;
using tactile_bag::Writer;
using tactile_bag::test::read_file;
using tactile_bag::test::TempDir;
using tactile_bag::test::write_file;

namespace {


std::vector<uint8_t> bytes(std::initializer_list<int> v) {
  std::vector<uint8_t> out;
  for (int b : v) out.push_back(static_cast<uint8_t>(b));
  return out;
}

TopicInfo topic(const std::string& name, const std::string& type = "std_msgs/msg/String") {
  TopicInfo t;
  t.name = name;
  t.type = type;
  t.type_definition = "string data\n";
  return t;
}

std::vector<SerializedMessage> read_all(Reader& r) {
  std::vector<SerializedMessage> out;
  SerializedMessage m;
  while (r.read_next(m)) out.push_back(m);
  return out;
}

// Expect `fn` to throw BagError whose message contains every fragment.
template <class F>
void expect_error(F fn, const std::vector<std::string>& fragments) {
  try {
    fn();
    FAIL() << "expected BagError";
  } catch (const BagError& e) {
    const std::string msg = e.what();
    for (const auto& f : fragments) {
      EXPECT_NE(msg.find(f), std::string::npos) << "message '" << msg << "' lacks '" << f << "'";
    }
  }
}

std::string write_sample_bag(const TempDir& tmp, const std::string& name = "sample") {
  const std::string dir = tmp.sub(name);
  Writer w;
  w.open(dir);
  tactile_bag::sample::write_sample(w);
  w.close();
  return dir;
}

/// Writes `text` to `path` with its first `from` replaced by `to` (a test failure if
/// `text` has no `from`).
void write_replaced(const std::string& path, const std::string& text, const std::string& from, const std::string& to) {
  std::string t = text;
  const auto pos = t.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  t.replace(pos, from.size(), to);
  write_file(path, t);
}

}  // namespace

TEST(Bag, RoundTripInterleavedTopicsSortedByTimestamp) {
  TempDir tmp;
  const std::string dir = tmp.sub("rt");
  {
    Writer w;
    w.open(dir);
    w.create_topic(topic("/a"));
    w.create_topic(topic("/b", "geometry_msgs/msg/Vector3"));
    w.create_topic(topic("/c"));
    // Written out of time order; equal timestamps keep write order.
    w.write("/a", 300, bytes({3}));
    w.write("/b", 100, bytes({1, 1}));
    w.write("/c", 200, bytes({2, 2, 2}));
    w.write("/a", 100, bytes({9}));
    w.write("/b", 400, bytes({4}));
    w.write("/c", 50, std::vector<uint8_t>{});  // empty payload
    EXPECT_EQ(w.message_count(), 6u);
  }  // destructor closes
  Reader r(dir);
  EXPECT_TRUE(r.metadata_complete()) << r.recovery_note();
  EXPECT_EQ(r.metadata_version(), 9);
  ASSERT_EQ(r.topics().size(), 3u);
  EXPECT_EQ(r.topics()[0].name, "/a");
  EXPECT_EQ(r.topics()[1].type, "geometry_msgs/msg/Vector3");
  EXPECT_EQ(r.topics()[2].type_definition, "string data\n");
  EXPECT_EQ(r.message_count(), 6u);
  EXPECT_EQ(r.message_count("/a"), 2u);
  EXPECT_EQ(r.message_count("/b"), 2u);
  EXPECT_EQ(r.message_count("/c"), 2u);
  EXPECT_EQ(r.start_time_ns(), 50);
  EXPECT_EQ(r.duration_ns(), 350);
  const auto all = read_all(r);
  ASSERT_EQ(all.size(), 6u);
  const std::vector<std::pair<std::string, int64_t>> expected{
      {"/c", 50}, {"/b", 100}, {"/a", 100}, {"/c", 200}, {"/a", 300}, {"/b", 400}};
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].topic, expected[i].first) << i;
    EXPECT_EQ(all[i].timestamp_ns, expected[i].second) << i;
  }
  EXPECT_EQ(all[0].data.size(), 0u);
  EXPECT_EQ(all[1].data, bytes({1, 1}));
  EXPECT_EQ(all[2].data, bytes({9}));
  EXPECT_EQ(all[3].data, bytes({2, 2, 2}));
  // reset restarts; a filter restricts.
  r.reset();
  EXPECT_EQ(read_all(r).size(), 6u);
  r.set_topic_filter({"/a", "/c"});
  const auto ac = read_all(r);
  ASSERT_EQ(ac.size(), 4u);
  for (const auto& m : ac) EXPECT_NE(m.topic, "/b");
  EXPECT_THROW(r.set_topic_filter({"/nope"}), BagError);
}

// Writes by topic number (the recorder's path) equal writes by name, in both storages;
// numbers follow creation order and a second create_topic returns the same number.
TEST(Bag, WriteByTopicNumberEqualsWriteByName) {
  for (const std::string storage : {"sqlite3", "mcap"}) {
    TempDir tmp;
    tactile_bag::WriterOptions o;
    o.storage = storage;
    const std::string dir = tmp.sub("ids_" + storage);
    {
      Writer w(o);
      w.open(dir);
      EXPECT_EQ(w.create_topic(topic("/a")), 0u);
      EXPECT_EQ(w.create_topic(topic("/b", "geometry_msgs/msg/Vector3")), 1u);
      EXPECT_EQ(w.create_topic(topic("/a")), 0u);
      EXPECT_EQ(w.topic_id("/b"), 1u);
      expect_error([&] { w.topic_id("/zz"); }, {"/zz", "has not been created"});
      expect_error([&] { w.write(Writer::TopicId{2}, 1, nullptr, 0); }, {"topic number 2", "2 topics"});
      w.write(Writer::TopicId{1}, 10, bytes({1, 2}).data(), 2);
      w.write("/a", 20, bytes({3}));
      w.write(w.topic_id("/a"), 30, bytes({4, 5, 6}).data(), 3);
      w.close();
    }
    Reader r(dir);
    const auto all = read_all(r);
    ASSERT_EQ(all.size(), 3u) << storage;
    EXPECT_EQ(all[0].topic, "/b");
    EXPECT_EQ(all[0].data, bytes({1, 2}));
    EXPECT_EQ(all[1].topic, "/a");
    EXPECT_EQ(all[2].timestamp_ns, 30);
    EXPECT_EQ(all[2].data, bytes({4, 5, 6}));
  }
}

TEST(Bag, EmptyBagAndTopicWithoutMessages) {
  TempDir tmp;
  {
    Writer w;
    w.open(tmp.sub("empty"));
  }
  Reader r(tmp.sub("empty"));
  EXPECT_TRUE(r.topics().empty());
  EXPECT_EQ(r.message_count(), 0u);
  EXPECT_EQ(r.duration_ns(), 0);
  SerializedMessage m;
  EXPECT_FALSE(r.read_next(m));

  {
    Writer w;
    w.open(tmp.sub("silent"));
    w.create_topic(topic("/silent"));
  }
  Reader s(tmp.sub("silent"));
  ASSERT_EQ(s.topics().size(), 1u);
  EXPECT_EQ(s.message_count("/silent"), 0u);
  EXPECT_TRUE(s.metadata_complete());
  EXPECT_FALSE(s.read_next(m));
}

TEST(Bag, LargeMessage) {
  TempDir tmp;
  std::vector<uint8_t> big(16 * 1024 * 1024 + 7);
  std::mt19937 gen(42);
  for (auto& b : big) b = static_cast<uint8_t>(gen());
  {
    Writer w;
    w.open(tmp.sub("big"));
    w.create_topic(topic("/big"));
    w.write("/big", 1, big);
    w.write("/big", 2, bytes({5}));
  }
  Reader r(tmp.sub("big"));
  const auto all = read_all(r);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_TRUE(all[0].data == big);
  EXPECT_EQ(all[1].data, bytes({5}));
}

TEST(Bag, MetadataYamlVersion9Content) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  const YAML::Node m = YAML::LoadFile(dir + "/metadata.yaml")["rosbag2_bagfile_information"];
  EXPECT_EQ(m["version"].as<int>(), 9);
  EXPECT_EQ(m["storage_identifier"].as<std::string>(), "sqlite3");
  EXPECT_EQ(m["message_count"].as<uint64_t>(), 15u);
  // first message: /whisker/left at 1e9; last: /whisker/right i=4 at 1e9 + 90 ms
  EXPECT_EQ(m["starting_time"]["nanoseconds_since_epoch"].as<int64_t>(), 1000000000);
  EXPECT_EQ(m["duration"]["nanoseconds"].as<int64_t>(), 90000000);
  ASSERT_EQ(m["relative_file_paths"].size(), 1u);
  EXPECT_EQ(m["relative_file_paths"][0].as<std::string>(), "sample_0.db3");
  EXPECT_TRUE(fs::exists(dir + "/sample_0.db3"));
  EXPECT_EQ(m["files"][0]["path"].as<std::string>(), "sample_0.db3");
  EXPECT_EQ(m["files"][0]["message_count"].as<uint64_t>(), 15u);
  EXPECT_EQ(m["ros_distro"].as<std::string>(), "jazzy");
  EXPECT_TRUE(m["custom_data"].IsMap());
  EXPECT_EQ(m["compression_mode"].as<std::string>(), "");
  const YAML::Node topics = m["topics_with_message_count"];
  ASSERT_EQ(topics.size(), 5u);
  EXPECT_EQ(topics[0]["topic_metadata"]["name"].as<std::string>(), "/whisker/left/pressure");
  EXPECT_EQ(topics[0]["message_count"].as<uint64_t>(), 5u);
  EXPECT_EQ(topics[3]["topic_metadata"]["name"].as<std::string>(), "/silent");
  EXPECT_EQ(topics[3]["message_count"].as<uint64_t>(), 0u);
  const YAML::Node qos = topics[0]["topic_metadata"]["offered_qos_profiles"];
  ASSERT_TRUE(qos.IsSequence());  // v9: a YAML list, not a string
  EXPECT_EQ(qos[0]["reliability"].as<std::string>(), "reliable");
  EXPECT_EQ(qos[0]["durability"].as<std::string>(), "volatile");
  EXPECT_EQ(qos[0]["history"].as<std::string>(), "unknown");
  EXPECT_EQ(qos[0]["liveliness"].as<std::string>(), "automatic");
  EXPECT_EQ(qos[0]["deadline"]["sec"].as<int64_t>(), 9223372036LL);
  EXPECT_EQ(qos[0]["deadline"]["nsec"].as<int64_t>(), 854775807LL);
  EXPECT_TRUE(topics[0]["topic_metadata"]["type_description_hash"].IsScalar());

  // Database: schema version 4, metadata row, definitions.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2((dir + "/sample_0.db3").c_str(), &db, SQLITE_OPEN_READONLY, nullptr),
            SQLITE_OK);
  auto one_int = [&](const char* sql) {
    sqlite3_stmt* s = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, sql, -1, &s, nullptr), SQLITE_OK) << sql;
    EXPECT_EQ(sqlite3_step(s), SQLITE_ROW) << sql;
    const int64_t v = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
    return v;
  };
  EXPECT_EQ(one_int("SELECT schema_version FROM schema"), 4);
  EXPECT_EQ(one_int("SELECT metadata_version FROM metadata ORDER BY id DESC LIMIT 1"), 9);
  EXPECT_EQ(one_int("SELECT COUNT(*) FROM message_definitions"), 3);
  EXPECT_EQ(one_int("SELECT COUNT(*) FROM messages"), 15);
  sqlite3_close(db);
  // After close the WAL is checkpointed: no side files remain.
  EXPECT_FALSE(fs::exists(dir + "/sample_0.db3-wal"));
}

// metadata.yaml is composed from parts the writer emits at different times (each topic's
// block when the topic is created): the text must be exactly what yaml-cpp emits for the whole
// node tree it reads as, for every metadata version, storage, with no topic, with topics whose
// QoS strings are multi-line (v5, v8) or lists (v9), while open and after close.
TEST(Bag, MetadataYamlIsTheEmittersTextOfItsTree) {
  // The tree read back, with every collection in the default (block) style a tree built in
  // code has ("[]" reads as a flow sequence), emitted whole.
  std::function<void(YAML::Node)> default_style = [&](YAML::Node n) {
    if (!n.IsMap() && !n.IsSequence()) return;
    n.SetStyle(YAML::EmitterStyle::Default);
    for (auto it = n.begin(); it != n.end(); ++it) default_style(n.IsMap() ? it->second : *it);
  };
  auto canonical = [&](const std::string& text) {
    YAML::Node tree = YAML::Load(text);
    default_style(tree);
    YAML::Emitter e;
    e << tree;
    return std::string(e.c_str()) + "\n";
  };
  auto file = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  TempDir tmp;
  for (const std::string storage : {"sqlite3", "mcap"}) {
    for (const int version : {5, 8, 9}) {
      for (int topics = 0; topics <= 3; topics += 3) {
        SCOPED_TRACE(storage + " v" + std::to_string(version) + " topics " + std::to_string(topics));
        tactile_bag::WriterOptions opt;
        opt.storage = storage;
        opt.metadata_version = version;
        const std::string dir = tmp.sub(storage + std::to_string(version) + "_" + std::to_string(topics));
        {
          Writer w(opt);
          w.open(dir);
          const std::string at_open = file(dir + "/metadata.yaml");
          EXPECT_EQ(at_open, canonical(at_open));
          for (int t = 0; t < topics; ++t) {
            tactile_bag::TopicInfo info = topic("/t" + std::to_string(t));
            if (t == 1) {
              info.offered_qos_profiles =
                  "- history: keep_last\n  depth: 10\n  reliability: best_effort\n  durability: volatile\n"
                  "  deadline:\n    sec: 1\n    nsec: 500\n  lifespan:\n    sec: 0\n    nsec: 0\n"
                  "  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 2\n    nsec: 0\n"
                  "  avoid_ros_namespace_conventions: false\n";
            }
            w.create_topic(info);
            for (int k = 0; k <= t; ++k) w.write(info.name, 100 * (k + 1) + t, bytes({1, 2}));
          }
        }
        const std::string text = file(dir + "/metadata.yaml");
        EXPECT_EQ(text, canonical(text));
        const YAML::Node m = YAML::Load(text)["rosbag2_bagfile_information"];
        EXPECT_EQ(m["version"].as<int>(), version);
        EXPECT_EQ(m["topics_with_message_count"].size(), static_cast<size_t>(topics));
        EXPECT_EQ(m["message_count"].as<int>(), topics == 3 ? 6 : 0);
        if (topics == 3) {
          EXPECT_EQ(m["topics_with_message_count"][2]["message_count"].as<int>(), 3);
        }
      }
    }
  }
}

TEST(Bag, HumbleVersion5UsesIntegerQosString) {
  TempDir tmp;
  tactile_bag::WriterOptions opt;
  opt.metadata_version = 5;
  {
    Writer w(opt);
    w.open(tmp.sub("humble"));
    w.create_topic(topic("/a"));
    w.write("/a", 7, bytes({1}));
  }
  const YAML::Node m =
      YAML::LoadFile(tmp.sub("humble") + "/metadata.yaml")["rosbag2_bagfile_information"];
  EXPECT_EQ(m["version"].as<int>(), 5);
  EXPECT_FALSE(m["ros_distro"]);
  EXPECT_FALSE(m["custom_data"]);
  const YAML::Node tm = m["topics_with_message_count"][0]["topic_metadata"];
  ASSERT_TRUE(tm["offered_qos_profiles"].IsScalar());  // Humble: a string
  const YAML::Node q = YAML::Load(tm["offered_qos_profiles"].as<std::string>());
  EXPECT_EQ(q[0]["history"].as<int>(), 3);
  EXPECT_EQ(q[0]["reliability"].as<int>(), 1);
  EXPECT_EQ(q[0]["durability"].as<int>(), 2);
  EXPECT_EQ(q[0]["liveliness"].as<int>(), 1);
  Reader r(tmp.sub("humble"));
  EXPECT_EQ(r.metadata_version(), 5);
  ASSERT_EQ(r.topics().size(), 1u);
  // normalised back to names
  const auto p = tactile_bag::parse_qos_profiles(r.topics()[0].offered_qos_profiles);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].reliability, "reliable");
  EXPECT_EQ(p[0].durability, "volatile");
  tactile_bag::WriterOptions bad;
  bad.metadata_version = 7;
  EXPECT_THROW(Writer{bad}, BagError);
}

TEST(Bag, QosParsingBothSpellingsAndErrors) {
  const std::string ints =
      "- history: 1\n  depth: 10\n  reliability: 2\n  durability: 1\n"
      "  deadline: {sec: 0, nsec: 0}\n  lifespan: {sec: 1, nsec: 5}\n  liveliness: 3\n"
      "  liveliness_lease_duration: {sec: 0, nsec: 0}\n  avoid_ros_namespace_conventions: true\n";
  const auto a = tactile_bag::parse_qos_profiles(ints);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].history, "keep_last");
  EXPECT_EQ(a[0].depth, 10);
  EXPECT_EQ(a[0].reliability, "best_effort");
  EXPECT_EQ(a[0].durability, "transient_local");
  EXPECT_EQ(a[0].liveliness, "manual_by_topic");
  EXPECT_EQ(a[0].lifespan.nsec, 5);
  EXPECT_TRUE(a[0].avoid_ros_namespace_conventions);
  const auto b = tactile_bag::parse_qos_profiles(tactile_bag::dump_qos_profiles(a, 9));
  EXPECT_EQ(b[0].reliability, "best_effort");
  EXPECT_EQ(tactile_bag::dump_qos_profiles(b, 8), tactile_bag::dump_qos_profiles(a, 8));
  EXPECT_TRUE(tactile_bag::parse_qos_profiles("").empty());
  expect_error([] { tactile_bag::parse_qos_profiles("- history: 9\n", "ctx"); },
               {"ctx[0].history", "unknown enum value 9"});
  expect_error([] { tactile_bag::parse_qos_profiles("[1, 2", "ctx"); }, {"ctx", "not valid YAML"});
  expect_error([] { tactile_bag::parse_qos_profiles("a: 1", "ctx"); }, {"expected a sequence"});
  std::string no_depth = ints;
  no_depth.replace(no_depth.find("depth: 10"), 9, "deep: 10");
  expect_error([&] { tactile_bag::parse_qos_profiles(no_depth, "ctx"); }, {"ctx[0].depth"});
}

TEST(Bag, WriterRefusesNonEmptyDirectoryAndBadUse) {
  TempDir tmp;
  fs::create_directories(tmp.sub("full"));
  write_file(tmp.sub("full") + "/x.txt", "x");
  Writer w;
  expect_error([&] { w.open(tmp.sub("full")); }, {"full", "not empty"});
  fs::create_directories(tmp.sub("emptydir"));
  w.open(tmp.sub("emptydir"));  // existing empty directory is fine
  EXPECT_TRUE(fs::exists(tmp.sub("emptydir") + "/emptydir_0.db3"));
  EXPECT_TRUE(fs::exists(tmp.sub("emptydir") + "/metadata.yaml"));  // written at open
  expect_error([&] { w.write("/nope", 1, bytes({1})); }, {"/nope", "has not been created"});
  w.create_topic(topic("/a"));
  w.create_topic(topic("/a"));  // same type: no-op
  expect_error([&] { w.create_topic(topic("/a", "std_msgs/msg/Int32")); }, {"/a", "already exists"});
  TopicInfo bad = topic("/q");
  bad.offered_qos_profiles = "- history: banana\n";
  expect_error([&] { w.create_topic(bad); }, {"/q", "history", "banana"});
  w.close();
  w.close();  // idempotent
  expect_error([&] { w.write("/a", 1, bytes({1})); }, {"not open"});
}

TEST(Bag, SampleBagContents) {
  TempDir tmp;
  Reader r(write_sample_bag(tmp));
  EXPECT_EQ(r.message_count(), 15u);
  EXPECT_EQ(r.message_count("/whisker/left/pressure"), 5u);
  EXPECT_EQ(r.message_count("/whisker/right/pressure"), 5u);
  EXPECT_EQ(r.message_count("/chatter"), 3u);
  EXPECT_EQ(r.message_count("/vector"), 2u);
  EXPECT_EQ(r.message_count("/silent"), 0u);
  const auto all = read_all(r);
  ASSERT_EQ(all.size(), 15u);
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.timestamp_ns < b.timestamp_ns;
  }));
  // /chatter i=1: CDR header, length 8 ("hello 1" + NUL), text.
  auto it = std::find_if(all.begin(), all.end(), [](const auto& m) {
    return m.topic == "/chatter" && m.timestamp_ns == 1035000000;
  });
  ASSERT_NE(it, all.end());
  EXPECT_EQ(it->data, bytes({0, 1, 0, 0, 8, 0, 0, 0, 'h', 'e', 'l', 'l', 'o', ' ', '1', 0}));
  // WhiskerPressure: 4 + 8 (stamp) + 4 + 13 ("whisker_left\0") + 1 (id) + pad to 8
  // (offset 30 -> 32) + 48 + 4 = 88 bytes.
  EXPECT_EQ(all[0].topic, "/whisker/left/pressure");
  EXPECT_EQ(all[0].data.size(), 88u);
}

TEST(Bag, MissingMetadataIsReconstructedFromDatabase) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  fs::remove(dir + "/metadata.yaml");
  Reader r(dir);
  EXPECT_FALSE(r.metadata_complete());
  EXPECT_NE(r.recovery_note().find("no metadata.yaml"), std::string::npos);
  EXPECT_EQ(r.metadata_version(), 0);
  EXPECT_EQ(r.message_count(), 15u);
  EXPECT_EQ(r.topics().size(), 5u);
  EXPECT_EQ(r.message_count("/chatter"), 3u);
  const TopicInfo* wp = r.find_topic("/whisker/left/pressure");
  ASSERT_NE(wp, nullptr);
  EXPECT_EQ(wp->type_definition, tactile_bag::sample::kWhiskerPressureDef);
  EXPECT_EQ(read_all(r).size(), 15u);
}

TEST(Bag, StaleMetadataIsDetected) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  std::string text = read_file(dir + "/metadata.yaml");
  const std::string key = "message_count: 15";
  ASSERT_NE(text.find(key), std::string::npos);
  text.replace(text.find(key), key.size(), "message_count: 0");
  write_file(dir + "/metadata.yaml", text);
  Reader r(dir);
  EXPECT_FALSE(r.metadata_complete());
  EXPECT_NE(r.recovery_note().find("lists 0 messages but the database holds 15"),
            std::string::npos)
      << r.recovery_note();
  EXPECT_EQ(r.message_count(), 15u);
}

TEST(BagErrors, MissingDirectoryAndDatabase) {
  TempDir tmp;
  expect_error([&] { Reader r(tmp.sub("nothere")); }, {"nothere", "does not exist"});
  fs::create_directories(tmp.sub("nodb"));
  expect_error([&] { Reader r(tmp.sub("nodb")); }, {"nodb", "no .db3 file"});
  const std::string dir = write_sample_bag(tmp);
  fs::remove(dir + "/sample_0.db3");
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "does not exist", "metadata.yaml"});
  write_file(tmp.sub("nodb") + "/x.mcap", "mcap");
  expect_error([&] { Reader r(tmp.sub("nodb")); }, {"x.mcap", "byte 0", "not an mcap file", "bad magic"});
}

TEST(BagErrors, CorruptAndTruncatedDatabase) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  const std::string db = dir + "/sample_0.db3";
  const std::string good = read_file(db);

  std::string garbage(4096, '\0');
  std::mt19937 gen(1);
  for (auto& c : garbage) c = static_cast<char>(gen());
  write_file(db, garbage);
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "file is not a database"});

  write_file(db, "");
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "empty", "not a database"});

  write_file(db, good.substr(0, 50));
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "not a database"});

  write_file(db, good.substr(0, good.size() / 2));
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "truncated"});

  // Header intact but a page in the middle overwritten: sqlite's own corruption report.
  std::string damaged = good;
  for (size_t i = 4096; i < 8192 && i < damaged.size(); ++i) damaged[i] = static_cast<char>(0xA5);
  write_file(db, damaged);
  try {
    Reader r(dir);
    read_all(r);
    // Some pages (e.g. free pages) may be unused; then the bag still reads.
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("sample_0.db3"), std::string::npos) << e.what();
  }

  // A valid sqlite file that is not a bag.
  fs::remove(db);
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &other), SQLITE_OK);
  sqlite3_exec(other, "CREATE TABLE foo(x INTEGER); INSERT INTO foo VALUES(1);", nullptr, nullptr,
               nullptr);
  sqlite3_close(other);
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "not a rosbag2 database", "topics"});
}

// metadata.yaml that declares what the reader cannot honour (a newer version, another
// storage or compression) is an error naming the key.
TEST(BagErrors, UnsupportedMetadata) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  const std::string meta = dir + "/metadata.yaml";
  const std::string good = read_file(meta);
  auto with = [&](const std::string& from, const std::string& to) { write_replaced(meta, good, from, to); };
  with("version: 9", "version: 10");
  expect_error([&] { Reader r(dir); }, {"metadata.yaml", "version", "unsupported version 10"});
  with("storage_identifier: sqlite3", "storage_identifier: rosbag_v1");
  expect_error([&] { Reader r(dir); }, {"metadata.yaml", "storage_identifier", "rosbag_v1", "not supported"});
  with("storage_identifier: sqlite3", "storage_identifier: mcap");  // but names a .db3
  expect_error([&] { Reader r(dir); }, {"sample_0.db3", "byte 0", "not an mcap file"});
  with("compression_mode: \"\"", "compression_mode: FILE");
  expect_error([&] { Reader r(dir); }, {"metadata.yaml", "compression_format", "not supported"});
}

// A garbage metadata.yaml beside an intact database is treated as a missing one: the bag is
// read from the database, and the recovery note says why metadata.yaml was not used (issue
// 32: it refused the whole bag, while a deleted metadata.yaml did not). Without a data file
// it stays an error naming both.
TEST(BagErrors, GarbageMetadataIsReadLikeAMissingOne) {
  TempDir tmp;
  const std::string dir = write_sample_bag(tmp);
  const std::string meta = dir + "/metadata.yaml";
  const std::string good = read_file(meta);
  auto with = [&](const std::string& from, const std::string& to) { write_replaced(meta, good, from, to); };
  auto expect_read = [&](const std::vector<std::string>& fragments) {
    Reader r(dir);
    EXPECT_EQ(r.message_count(), 15u);
    EXPECT_FALSE(r.metadata_complete());
    EXPECT_FALSE(r.damaged());
    EXPECT_NE(r.recovery_note().find("metadata.yaml not used"), std::string::npos) << r.recovery_note();
    for (const auto& f : fragments) EXPECT_NE(r.recovery_note().find(f), std::string::npos) << f << " in " << r.recovery_note();
    SerializedMessage m;
    uint64_t n = 0;
    while (r.read_next(m)) ++n;
    EXPECT_EQ(n, 15u);
  };
  write_file(meta, "rosbag2_bagfile_information: [unclosed\n");
  expect_read({"metadata.yaml", "not valid YAML"});
  write_file(meta, "hello: 1\n");
  expect_read({"rosbag2_bagfile_information", "missing"});
  with("version: 9", "versio: 9");
  expect_read({"rosbag2_bagfile_information.version", "missing"});
  with("version: 9", "version: nine");
  expect_read({"version", "expected an integer"});
  with("message_count: 15", "message_count: lots");
  expect_read({"message_count", "unsigned integer"});
  with("reliability: reliable", "reliability: sometimes");
  expect_read({"topics_with_message_count[0].topic_metadata.offered_qos_profiles", "reliability", "sometimes"});
  // Oversized random garbage.
  std::string junk(1 << 20, 'x');
  std::mt19937 gen(3);
  for (auto& c : junk) c = static_cast<char>(gen() % 95 + 32);
  write_file(meta, junk);
  expect_read({"metadata.yaml"});
  // Binary garbage.
  std::string bin(4096, '\0');
  for (auto& c : bin) c = static_cast<char>(gen());
  write_file(meta, bin);
  expect_read({"metadata.yaml"});
  // Without a data file beside it: an error naming both.
  fs::remove(dir + "/sample_0.db3");
  expect_error([&] { Reader r(dir); }, {"metadata.yaml", "no .db3 or .mcap file beside it"});
}

TEST(Bag, ReadsRos2HumbleStyleBag) {
  // A database as ROS 2 Humble's sqlite3 plugin writes it (schema 3: no message_definitions,
  // no type_description_hash) with a version-5 metadata.yaml whose QoS is an integer string.
  TempDir tmp;
  const std::string dir = tmp.sub("humble_bag");
  fs::create_directories(dir);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir + "/humble_bag_0.db3").c_str(), &db), SQLITE_OK);
  const char* sql =
      "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
      "INSERT INTO schema VALUES(3, 'humble');"
      "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
      " metadata TEXT NOT NULL);"
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
      " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
      " timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
      "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
      "INSERT INTO topics VALUES(1, '/chatter', 'std_msgs/msg/String', 'cdr', '');"
      "INSERT INTO topics VALUES(2, '/rosout', 'rcl_interfaces/msg/Log', 'cdr', '');"
      "INSERT INTO messages(topic_id, timestamp, data) VALUES(1, 20, x'000100000200000041000000');"
      "INSERT INTO messages(topic_id, timestamp, data) VALUES(2, 10, x'00010000');"
      "INSERT INTO messages(topic_id, timestamp, data) VALUES(1, 30, x'000100000200000042000000');";
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
  write_file(dir + "/metadata.yaml",
             "rosbag2_bagfile_information:\n"
             "  version: 5\n"
             "  storage_identifier: sqlite3\n"
             "  duration:\n    nanoseconds: 20\n"
             "  starting_time:\n    nanoseconds_since_epoch: 10\n"
             "  message_count: 3\n"
             "  topics_with_message_count:\n"
             "    - topic_metadata:\n"
             "        name: /chatter\n"
             "        type: std_msgs/msg/String\n"
             "        serialization_format: cdr\n"
             "        offered_qos_profiles: \"- history: 3\\n  depth: 0\\n  reliability: 1\\n"
             "  durability: 2\\n  deadline:\\n    sec: 9223372036\\n    nsec: 854775807\\n"
             "  lifespan:\\n    sec: 9223372036\\n    nsec: 854775807\\n  liveliness: 1\\n"
             "  liveliness_lease_duration:\\n    sec: 9223372036\\n    nsec: 854775807\\n"
             "  avoid_ros_namespace_conventions: false\"\n"
             "      message_count: 2\n"
             "    - topic_metadata:\n"
             "        name: /rosout\n"
             "        type: rcl_interfaces/msg/Log\n"
             "        serialization_format: cdr\n"
             "        offered_qos_profiles: \"\"\n"
             "      message_count: 1\n"
             "  compression_format: \"\"\n"
             "  compression_mode: \"\"\n"
             "  relative_file_paths:\n    - humble_bag_0.db3\n"
             "  files:\n    - path: humble_bag_0.db3\n      starting_time:\n"
             "        nanoseconds_since_epoch: 10\n      duration:\n        nanoseconds: 20\n"
             "      message_count: 3\n");
  Reader r(dir);
  EXPECT_TRUE(r.metadata_complete()) << r.recovery_note();
  EXPECT_EQ(r.metadata_version(), 5);
  ASSERT_EQ(r.topics().size(), 2u);
  const auto q = tactile_bag::parse_qos_profiles(r.find_topic("/chatter")->offered_qos_profiles);
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].reliability, "reliable");
  EXPECT_EQ(q[0].history, "unknown");
  const auto all = read_all(r);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].topic, "/rosout");
  EXPECT_EQ(all[1].data, bytes({0, 1, 0, 0, 2, 0, 0, 0, 'A', 0, 0, 0}));
  EXPECT_EQ(all[2].timestamp_ns, 30);
}

TEST(Bag, SplitBagFilesAreMergedInTimestampOrder) {
  // ros2 bag record --max-bag-size produces <name>_0.db3, <name>_1.db3, ...
  TempDir tmp;
  Writer a, b;
  a.open(tmp.sub("part0"));
  a.create_topic(topic("/t"));
  a.write("/t", 10, bytes({1}));
  a.write("/t", 30, bytes({3}));
  a.close();
  b.open(tmp.sub("part1"));
  b.create_topic(topic("/t"));
  b.write("/t", 20, bytes({2}));
  b.write("/t", 40, bytes({4}));
  b.close();
  const std::string dir = tmp.sub("split");
  fs::create_directories(dir);
  fs::copy_file(tmp.sub("part0") + "/part0_0.db3", dir + "/split_0.db3");
  fs::copy_file(tmp.sub("part1") + "/part1_0.db3", dir + "/split_1.db3");
  Reader r(dir);  // no metadata.yaml: both files found
  EXPECT_EQ(r.files().size(), 2u);
  EXPECT_EQ(r.message_count("/t"), 4u);
  const auto all = read_all(r);
  ASSERT_EQ(all.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(all[i].data, bytes({static_cast<int>(i + 1)}));
}
