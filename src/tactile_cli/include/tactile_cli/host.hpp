// The standalone host: node logic objects composed in one process on the
// deterministic Executor, wired by the Bus, configured from the same
// `ros__parameters` YAML files the launch files hand to the rclcpp components.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tactile_bag/bag.hpp"
#include "tactile_cli/executor.hpp"
#include "tactile_common/parameters.hpp"

namespace tactile_cli {

/// Records every message published on the bus into a rosbag2 bag, creating
/// each topic (type + definition) on its first message.
class BagRecorder : public BusTap {
 public:
  /// Storage, distro and compression of every bag the `tactile` commands record (set once
  /// from --storage, --bag-distro, --bag-compression). Default: what `ros2 bag record` of
  /// Kilted writes: mcap, uncompressed chunks, Kilted layouts and RIHS01 hashes.
  static tactile_bag::WriterOptions& default_options();
  /// When the bag reaches the disk. kLive (hardware, bench rigs): committed every 250 ms of
  /// wall time, so a killed recording loses at most that. kReproducible (simulation, replay,
  /// demo: their messages do not depend on the wall clock, so neither should the file):
  /// chunks by size only (WriterOptions::flush_interval 0), the same bytes however fast the
  /// machine and on however many workers the trials run.
  enum class Commit { kLive, kReproducible };
  explicit BagRecorder(const std::string& dir, Commit commit = Commit::kLive);
  void on_message(const TapTopic& topic, int64_t stamp_ns,
                  const std::function<void(std::vector<uint8_t>&)>& serialize_into) override;
  void close() { writer_.close(); }
  uint64_t message_count() const { return writer_.message_count(); }

 private:
  tactile_bag::Writer writer_;
  /// Bus topic name -> bag topic (created) and its serialization buffer, reused.
  struct Topic {
    tactile_bag::Writer::TopicId id = 0;
    std::vector<uint8_t> buffer;
  };
  std::map<const std::string*, Topic> topics_;  // keyed by the bus slot's stable name
};

/// A summary line of one node instance's counters, for metrics and logs.
struct NodeReport {
  std::string name;  ///< fully qualified, e.g. "/whisker/left/tdorc_filter"
  std::vector<std::pair<std::string, uint64_t>> counters;
};

class Host {
 public:
  /// @param config_dir directory holding <node>.yaml parameter files; every
  ///        node loaded through load_parameters() needs its file (no default
  ///        fallback: a missing, empty, non-file or misnamed file is an error).
  explicit Host(std::string config_dir);

  Bus& bus() { return bus_; }
  Executor& executor() { return executor_; }
  const std::string& config_dir() const { return config_dir_; }

  /// Parameters of node `node_name` in namespace `ns`: defaults <-
  /// config/<parameter_file_name(node_name)> (sections matched against the fully qualified
  /// name, as ROS 2 does) <- overrides (like a launch file's per-node
  /// parameter dict). Errors name the file, key and reason; the file must
  /// exist, be a regular file and have a section naming the node
  /// (tactile_common::load_node_parameters).
  tactile_common::ParamMap load_parameters(const std::string& ns, const std::string& node_name,
                                           const tactile_common::ParamMap& defaults,
                                           const tactile_common::ParamMap& overrides) const;

  /// Applies the parameter profile <config_dir>/profiles/<name>.yaml to every node loaded
  /// after this call, between the node's file and the overrides (a launch file passes the
  /// same file after the node's: launch/sitl_explore.launch.py). A profile names only the
  /// nodes and keys it changes (tactile_common::load_profile_overlay). Throws
  /// tactile_common::ParamError naming the file if it is missing; later profiles win, except that
  /// `graph_default` ones (a graph's own, e.g. gpis_explore's exploration) go before the
  /// user's (`tactile sim --profile`), so the user's win.
  void use_profile(const std::string& name, bool graph_default = false);
  const std::vector<std::string>& profiles() const { return profiles_; }

  /// Keeps an object alive for the lifetime of the host.
  template <class T>
  T* keep(std::shared_ptr<T> object) {
    T* raw = object.get();
    objects_.push_back(std::move(object));
    return raw;
  }

  /// Registers a function reporting a node's counters.
  void add_reporter(std::function<NodeReport()> reporter) { reporters_.push_back(std::move(reporter)); }
  std::vector<NodeReport> reports() const;

 private:
  std::string config_dir_;
  std::vector<std::string> profiles_;  ///< paths of the profiles in use, in order
  std::size_t graph_profiles_ = 0;     ///< the first ones are the graph's (use_profile(name, true))
  Bus bus_;
  Executor executor_;
  std::vector<std::shared_ptr<void>> objects_;
  std::vector<std::function<NodeReport()>> reporters_;
};

/// Name of the parameter file of node `node_name` in the config directory, the one the
/// launch files give that node: `<node_name>.yaml`, but `tactile_fsm.yaml` for `whisker_fsm`.
std::string parameter_file_name(const std::string& node_name);

/// The logic object of node `Logic` in namespace `ns`, built from its
/// parameters (defaults <- config/<node>.yaml <- `over`, Host::load_parameters)
/// and kept alive by the host; the add_<node> functions wire its topics.
template <class Logic>
std::shared_ptr<Logic> add_logic(Host& host, const std::string& ns, const tactile_common::ParamMap& over) {
  auto logic = std::make_shared<Logic>(
      Logic::params_from(host.load_parameters(ns, Logic::kNodeName, Logic::default_parameters(), over)));
  host.keep(logic);
  return logic;
}

/// Overrides for a node, like the parameter dicts of a launch file.
tactile_common::ParamMap overrides(
    std::initializer_list<std::pair<const char*, tactile_common::ParamValue>> values);

}  // namespace tactile_cli
