#include "tactile_cli/xplorer_export.hpp"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <fstream>
#include <stdexcept>

#include "graphs/xplorer_nodes.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/typed.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/warnings.hpp"
#include "tactile_common/time.hpp"

namespace tactile_cli {

nlohmann::json run_export(const ExportOptions& o) {
  using xplorer_force_est::XplorerForceEstLogic;
  using MapLogic = mapping_pcl::XplorerMapLogic;
  // The bag's topic names: the host records at the root namespace (executor.hpp
  // root_topic); a launch's bag in its namespace (--namespace). Each is published on the
  // host's bus under its root name.
  std::string ns = o.ns;
  while (!ns.empty() && ns.front() == '/') ns.erase(ns.begin());
  while (!ns.empty() && ns.back() == '/') ns.pop_back();
  auto bag_topic = [&ns](const char* topic) { return resolve_topic(ns, topic); };
  const std::string odom_topic = bag_topic(MapLogic::kOdometryTopic);
  const std::string wrench_topic = bag_topic(MapLogic::kWrenchBodyTopic);
  const std::string state_topic = bag_topic(MapLogic::kFsmStateTopic);
  const std::string map_arm_topic = bag_topic(MapLogic::kArmImuTopic);
  const std::string arm_topic = bag_topic(XplorerForceEstLogic::kArmImuTopic);
  const std::string imu_topic = bag_topic(XplorerForceEstLogic::kImuTopic);
  const std::string thrust_topic = bag_topic(XplorerForceEstLogic::kThrustTopic);
  const std::map<std::string, std::string> bus_topic = {
      {odom_topic, root_topic(MapLogic::kOdometryTopic)},
      {wrench_topic, root_topic(MapLogic::kWrenchBodyTopic)},
      {state_topic, root_topic(MapLogic::kFsmStateTopic)},
      {map_arm_topic, root_topic(MapLogic::kArmImuTopic)},
      {arm_topic, root_topic(XplorerForceEstLogic::kArmImuTopic)},
      {imu_topic, root_topic(XplorerForceEstLogic::kImuTopic)},
      {thrust_topic, root_topic(XplorerForceEstLogic::kThrustTopic)}};
  tactile_bag::Reader reader(o.bag);
  Warnings warnings;
  warnings.add_bag_metadata(o.bag, reader);
  const bool have_odom = reader.find_topic(odom_topic) != nullptr;
  if (!have_odom) {
    // A bag of a namespaced launch has /<ns>/odom: name the namespaces it has.
    std::string hint;
    const std::string suffix = "/" + std::string(MapLogic::kOdometryTopic);
    for (const auto& t : reader.topics()) {
      if (t.type == "nav_msgs/msg/Odometry" && t.name.size() > suffix.size() &&
          t.name.compare(t.name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
          t.name.rfind("/ground_truth/", 0) != 0) {
        hint += (hint.empty() ? "; the bag has " : ", ") + t.name + " (--namespace " +
                t.name.substr(1, t.name.size() - suffix.size() - 1) + ")";
      }
    }
    throw std::runtime_error(o.bag + ": no " + std::string(odom_topic) + " topic (the map needs the pose)" + hint);
  }
  const bool have_wrench = reader.find_topic(wrench_topic) != nullptr;
  if (!have_wrench && (!reader.find_topic(arm_topic) || !reader.find_topic(imu_topic) ||
                       !reader.find_topic(thrust_topic))) {
    throw std::runtime_error(o.bag + ": neither " + std::string(wrench_topic) + " nor the force-estimator inputs (" +
                             arm_topic + ", " + imu_topic + ", " +
                             thrust_topic + ")");
  }
  Host host(o.config_dir);
  // The nodes start (their timers' phase) at the replay clock's first time: the bag's
  // first timestamp, or at the stamps the first stamp; started before the first message
  // is delivered (or at the end if none decoded), so a bad parameter file still stops the
  // export before anything is written.
  std::shared_ptr<MapLogic> map;
  std::shared_ptr<XplorerForceEstLogic> force;
  auto start_nodes = [&](int64_t t0) {
    host.executor().set_time(t0);
    auto over = overrides({{"publish_rate_hz", 0.0}});
    if (!ns.empty()) {
      const std::string frame = host.load_parameters("", MapLogic::kNodeName, MapLogic::default_parameters(), {})
                                    .get_string("frame_id");
      over.set("frame_id", ns + "/" + frame);
    }
    map = add_xplorer_mapping(host, over);
    if (!have_wrench) force = add_xplorer_force_est(host, {});
  };
  std::vector<std::string> topics = {odom_topic};
  if (reader.find_topic(state_topic)) topics.push_back(state_topic);
  if (have_wrench) {
    topics.push_back(wrench_topic);
    // The arm angles place the slabs at the deflected outline (mapping edge_from_arms).
    if (reader.find_topic(map_arm_topic)) topics.push_back(map_arm_topic);
  } else {
    topics.insert(topics.end(), {arm_topic, imu_topic, thrust_topic});
  }
  reader.set_topic_filter(topics);
  tactile_bag::SerializedMessage m;
  uint64_t used = 0;
  uint64_t undecodable = 0;
  std::string first_error;
  // Messages decoded and waiting for their replay time (ExportOptions::Time): ordered by
  // (time, read order); only a window of bag time is held, so memory is bounded by the
  // topics' rates, not by the bag.
  struct Pending {
    int64_t t;
    uint64_t order;
    std::function<void(int64_t)> publish;
    bool operator>(const Pending& o) const { return t != o.t ? t > o.t : order > o.order; }
  };
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> pending;
  uint64_t read_order = 0, late = 0, off_clock = 0;
  int64_t replayed_ns = std::numeric_limits<int64_t>::min();
  auto replay_until = [&](int64_t t_ns) {
    while (!pending.empty() && pending.top().t <= t_ns) {
      if (!map) start_nodes(o.time == ExportOptions::Time::kReceive ? reader.start_time_ns() : pending.top().t);
      const int64_t t = std::max(pending.top().t, replayed_ns);
      host.executor().run_until(t);  // mapping timer ticks up to this message
      replayed_ns = t;
      const auto publish = pending.top().publish;
      pending.pop();
      publish(t);
      ++used;
    }
  };
  auto hold = [&](const auto& msg, const std::string& topic) {
    int64_t t = m.timestamp_ns;
    if (o.time == ExportOptions::Time::kHeader) {
      const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
      // A stamp far from the bag's time (unset, another clock, corrupt) is not a time to
      // replay at: the bag's time is, and the hold stays bounded by kMaxStampSkewNs.
      const bool skewed = stamp < m.timestamp_ns - ExportOptions::kMaxStampSkewNs ||
                          stamp > m.timestamp_ns + ExportOptions::kMaxStampSkewNs;
      if (skewed) ++off_clock;
      t = skewed ? m.timestamp_ns : stamp;
      if (t < replayed_ns) {
        if (!skewed) ++late;
        t = replayed_ns;
      }
    }
    pending.push(Pending{t, read_order++, [&host, topic = bus_topic.at(topic), msg](int64_t now) {
                           host.bus().publish(topic, msg, now);
                         }});
  };
  while (reader.read_next(m)) {
    try {
      if (m.topic == odom_topic) {
        hold(tactile_bag::decode<nav_msgs::msg::Odometry>(m), m.topic);
      } else if (m.topic == state_topic) {
        hold(tactile_bag::decode<tactile_msgs::msg::FsmState>(m), m.topic);
      } else if (m.topic == wrench_topic) {
        hold(tactile_bag::decode<geometry_msgs::msg::WrenchStamped>(m), m.topic);
      } else if (m.topic == arm_topic) {
        hold(tactile_bag::decode<tactile_msgs::msg::ArmImuArray>(m), m.topic);
      } else if (m.topic == imu_topic) {
        hold(tactile_bag::decode<sensor_msgs::msg::Imu>(m), m.topic);
      } else if (m.topic == thrust_topic) {
        hold(tactile_bag::decode<tactile_msgs::msg::ThrustCommand>(m), m.topic);
      }
    } catch (const tactile_bag::BagError& e) {
      // A corrupt message is dropped, counted and said (the map keeps the rest).
      if (undecodable++ == 0) first_error = e.what();
      continue;
    }
    // In bag order (receive): everything read so far; at the stamps: what is a window older
    // than the bag's time, which no later message's stamp should precede.
    replay_until(o.time == ExportOptions::Time::kReceive ? m.timestamp_ns
                                                        : m.timestamp_ns - ExportOptions::kReorderWindowNs);
  }
  replay_until(std::numeric_limits<int64_t>::max());
  if (!map) start_nodes(reader.start_time_ns());  // nothing decoded: an empty map, said below
  warnings.add("corrupt_messages_dropped", undecodable,
               std::to_string(undecodable) + " message(s) that did not decode dropped (first: " + first_error + ")");
  warnings.add("stamps_off_the_bag_clock_replayed_at_bag_time", off_clock,
               std::to_string(off_clock) + " message(s) stamped more than " +
                   std::to_string(ExportOptions::kMaxStampSkewNs / 1'000'000'000) +
                   " s from the bag's time (unset, another clock): replayed at the bag's timestamp");
  warnings.add("late_stamps_replayed_at_the_current_time", late,
               std::to_string(late) + " message(s) stamped before what was already replayed (more than " +
                   std::to_string(ExportOptions::kReorderWindowNs / 1'000'000) +
                   " ms behind the bag's time): replayed at the current time");
  warnings.add_node_counters(host.reports());
  const auto r = map->finalize();
  mapping_pcl::PlyInfo info;
  info.frame = map->params().frame_id;
  info.comment = "XPLORER contact map rebuilt from a bag (paper 001 Sec. IV-B)";
  mapping_pcl::write_ply(o.ply, map->map().cloud(),
                         o.binary ? mapping_pcl::PlyFormat::kBinaryLittleEndian : mapping_pcl::PlyFormat::kAscii, info);
  nlohmann::json s;
  s["bag"] = o.bag;
  s["ply"] = o.ply;
  s["format"] = o.binary ? "binary_little_endian" : "ascii";
  s["wrench_source"] = have_wrench ? wrench_topic : "xplorer_force_est (re-run)";
  s["messages"] = used;
  s["time"] = o.time == ExportOptions::Time::kHeader ? "header" : "receive";
  s["slabs"] = map->mapper().stats().slabs;
  s["points"] = r.points;
  s["map_length_m"] = r.length;
  s["map_width_m"] = r.width;
  s["map_area_m2"] = r.obb_area;
  s["warnings"] = warnings.to_json();
  warnings.print("export");
  // The summary beside the map, so repairs, skips and drops are on record (issue 16).
  std::filesystem::path metrics = o.metrics;
  if (metrics.empty()) metrics = std::filesystem::path(o.ply).replace_extension(".metrics.json");
  {
    std::ofstream out(metrics);
    if (!out || !(out << s.dump(2) << '\n')) throw std::runtime_error(metrics.string() + ": cannot write");
  }
  s["metrics_file"] = metrics.string();
  return s;
}

}  // namespace tactile_cli
