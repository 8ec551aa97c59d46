#include "tactile_cli/host.hpp"

#include <chrono>
#include <filesystem>
#include <stdexcept>

#include "tactile_bag/typed.hpp"

namespace tactile_cli {

tactile_bag::WriterOptions& BagRecorder::default_options() {
  static tactile_bag::WriterOptions options = [] {
    tactile_bag::WriterOptions o;
    o.storage = "mcap";
    o.ros_distro = "kilted";
    return o;
  }();
  return options;
}

namespace {
tactile_bag::WriterOptions options_for(BagRecorder::Commit commit) {
  tactile_bag::WriterOptions o = BagRecorder::default_options();
  if (commit == BagRecorder::Commit::kReproducible) o.flush_interval = std::chrono::milliseconds(0);
  return o;
}
}  // namespace

BagRecorder::BagRecorder(const std::string& dir, Commit commit) : writer_(options_for(commit)) {
  writer_.open(dir);
}

void BagRecorder::on_message(const TapTopic& topic, int64_t stamp_ns,
                             const std::function<void(std::vector<uint8_t>&)>& serialize_into) {
  auto it = topics_.find(&topic.name);
  if (it == topics_.end()) {
    tactile_bag::TopicInfo info;
    info.name = topic.name;
    info.type = topic.type_name;
    info.type_definition = topic.definition;
    it = topics_.emplace(&topic.name, Topic{writer_.create_topic(info), {}}).first;
  }
  Topic& t = it->second;
  serialize_into(t.buffer);
  writer_.write(t.id, stamp_ns, t.buffer.data(), t.buffer.size());
}

Host::Host(std::string config_dir) : config_dir_(std::move(config_dir)) {}

std::string parameter_file_name(const std::string& node_name) {
  // As the launch files pass them: every node's file is <node>.yaml except the whisker
  // FSM's, which is named after its package (launch/sitl_whisker.launch.py and the others
  // give config/tactile_fsm.yaml to the node whisker_fsm).
  if (node_name == "whisker_fsm") return "tactile_fsm.yaml";
  return node_name + ".yaml";
}

tactile_common::ParamMap Host::load_parameters(const std::string& ns, const std::string& node_name,
                                               const tactile_common::ParamMap& defaults,
                                               const tactile_common::ParamMap& over) const {
  const std::string path = (std::filesystem::path(config_dir_) / parameter_file_name(node_name)).string();
  // Every node the host runs reads its file: a missing, empty, non-file or
  // misnamed one is an error naming the file and the reason (issue 32: a
  // missing tdorc_filter.yaml ran TDORC on its defaults and the three-baffle
  // course ended in a collision with exit 0). No node has a file-less default.
  tactile_common::ParamMap params =
      tactile_common::load_node_parameters(path, resolve_topic(ns, node_name), defaults);
  for (const auto& profile : profiles_) {
    params.merge_from(tactile_common::load_profile_overlay(profile, resolve_topic(ns, node_name), params));
  }
  tactile_common::ParamMap o(node_name, "overrides of " + node_name + " in the standalone host");
  for (const auto& [k, v] : over.values()) o.set(k, v);
  params.merge_from(o);
  return params;
}

void Host::use_profile(const std::string& name, bool graph_default) {
  const auto path = std::filesystem::path(config_dir_) / "profiles" / (name + ".yaml");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    // A configuration error, as a missing node file: a sweep stops on it (exit 1).
    throw tactile_common::ParamError(path.string() + ": no such parameter profile (profiles are the files in " +
                             (std::filesystem::path(config_dir_) / "profiles").string() + ")");
  }
  if (graph_default) {
    profiles_.insert(profiles_.begin() + static_cast<std::ptrdiff_t>(graph_profiles_++), path.string());
  } else {
    profiles_.push_back(path.string());
  }
}

std::vector<NodeReport> Host::reports() const {
  std::vector<NodeReport> out;
  for (const auto& r : reporters_) out.push_back(r());
  return out;
}

tactile_common::ParamMap overrides(
    std::initializer_list<std::pair<const char*, tactile_common::ParamValue>> values) {
  tactile_common::ParamMap m("", "overrides");
  for (const auto& [k, v] : values) m.set(k, v);
  return m;
}

}  // namespace tactile_cli
