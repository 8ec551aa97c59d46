#include "tactile_cli/xplorer_export.hpp"

#include <filesystem>
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
  // The bag's topic names: the host records at the root namespace (executor.hpp root_topic).
  const std::string odom_topic = root_topic(MapLogic::kOdometryTopic);
  const std::string wrench_topic = root_topic(MapLogic::kWrenchBodyTopic);
  const std::string state_topic = root_topic(MapLogic::kFsmStateTopic);
  const std::string map_arm_topic = root_topic(MapLogic::kArmImuTopic);
  const std::string arm_topic = root_topic(XplorerForceEstLogic::kArmImuTopic);
  const std::string imu_topic = root_topic(XplorerForceEstLogic::kImuTopic);
  const std::string thrust_topic = root_topic(XplorerForceEstLogic::kThrustTopic);
  tactile_bag::Reader reader(o.bag);
  Warnings warnings;
  warnings.add_bag_metadata(o.bag, reader);
  const bool have_odom = reader.find_topic(odom_topic) != nullptr;
  if (!have_odom) throw std::runtime_error(o.bag + ": no " + std::string(odom_topic) + " topic (the map needs the pose)");
  const bool have_wrench = reader.find_topic(wrench_topic) != nullptr;
  if (!have_wrench && (!reader.find_topic(arm_topic) || !reader.find_topic(imu_topic) ||
                       !reader.find_topic(thrust_topic))) {
    throw std::runtime_error(o.bag + ": neither " + std::string(wrench_topic) + " nor the force-estimator inputs (" +
                             arm_topic + ", " + imu_topic + ", " +
                             thrust_topic + ")");
  }
  Host host(o.config_dir);
  host.executor().set_time(reader.start_time_ns());  // timers start at the bag's first message
  auto map = add_xplorer_mapping(host, overrides({{"publish_rate_hz", 0.0}}));
  std::shared_ptr<XplorerForceEstLogic> force;
  std::vector<std::string> topics = {odom_topic};
  if (reader.find_topic(state_topic)) topics.push_back(state_topic);
  if (have_wrench) {
    topics.push_back(wrench_topic);
    // The arm angles place the slabs at the deflected outline (mapping edge_from_arms).
    if (reader.find_topic(map_arm_topic)) topics.push_back(map_arm_topic);
  } else {
    force = add_xplorer_force_est(host, {});
    topics.insert(topics.end(), {arm_topic, imu_topic,
                                 thrust_topic});
  }
  reader.set_topic_filter(topics);
  tactile_bag::SerializedMessage m;
  uint64_t used = 0;
  uint64_t undecodable = 0;
  std::string first_error;
  while (reader.read_next(m)) {
    host.executor().run_until(m.timestamp_ns);  // mapping timer ticks up to this message
    const int64_t now = m.timestamp_ns;
    try {
      if (m.topic == odom_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<nav_msgs::msg::Odometry>(m), now);
      } else if (m.topic == state_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<tactile_msgs::msg::FsmState>(m), now);
      } else if (m.topic == wrench_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<geometry_msgs::msg::WrenchStamped>(m), now);
      } else if (m.topic == arm_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<tactile_msgs::msg::ArmImuArray>(m), now);
      } else if (m.topic == imu_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<sensor_msgs::msg::Imu>(m), now);
      } else if (m.topic == thrust_topic) {
        host.bus().publish(m.topic, tactile_bag::decode<tactile_msgs::msg::ThrustCommand>(m), now);
      }
    } catch (const tactile_bag::BagError& e) {
      // A corrupt message is dropped, counted and said (the map keeps the rest).
      if (undecodable++ == 0) first_error = e.what();
      continue;
    }
    ++used;
  }
  warnings.add("corrupt_messages_dropped", undecodable,
               std::to_string(undecodable) + " message(s) that did not decode dropped (first: " + first_error + ")");
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
