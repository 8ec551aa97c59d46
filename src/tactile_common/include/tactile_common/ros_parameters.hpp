// rclcpp side of the parameter bridge: declares every parameter a node logic
// reads (with the logic's defaults) on an rclcpp::Node and returns the values
// as a ParamMap. Header-only and included only by rclcpp components, so the
// ROS-free build never sees rclcpp.
#pragma once

#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "rcl/arguments.h"
#include "rcl/error_handling.h"
#include "rclcpp/parameter_map.hpp"
#include "rclcpp/rclcpp.hpp"
#include "tactile_common/parameters.hpp"

namespace tactile_common {

inline rclcpp::ParameterValue to_ros(const ParamValue& value) {
  return std::visit([](const auto& v) { return rclcpp::ParameterValue(v); }, value);
}

inline ParamValue from_ros(const rclcpp::ParameterValue& value, const std::string& key) {
  switch (value.get_type()) {
    case rclcpp::ParameterType::PARAMETER_BOOL: return value.get<bool>();
    case rclcpp::ParameterType::PARAMETER_INTEGER: return value.get<int64_t>();
    case rclcpp::ParameterType::PARAMETER_DOUBLE: return value.get<double>();
    case rclcpp::ParameterType::PARAMETER_STRING: return value.get<std::string>();
    case rclcpp::ParameterType::PARAMETER_BOOL_ARRAY: return value.get<std::vector<bool>>();
    case rclcpp::ParameterType::PARAMETER_INTEGER_ARRAY: return value.get<std::vector<int64_t>>();
    case rclcpp::ParameterType::PARAMETER_DOUBLE_ARRAY: return value.get<std::vector<double>>();
    case rclcpp::ParameterType::PARAMETER_STRING_ARRAY:
      return value.get<std::vector<std::string>>();
    default:
      throw ParamError("ros parameters: " + key + ": unsupported parameter type " + rclcpp::to_string(value.get_type()));
  }
}

/// Where each parameter value of a node came from, so that a parameter error names
/// the file (or the launch override) that gave the bad value:
///  - the --params-file arguments rcl parsed for the node (`ros2 run <pkg> <node>_node
///    --ros-args --params-file F`, or a NodeOptions argument): the last file that sets
///    the key to the value the node got;
///  - `ros2 launch` reads parameter files itself and hands a component plain values, so
///    the launch files of this workspace also pass the string array
///    `tactile.parameter_sources` (launch/launch_common.py `parameters()`): in launch's
///    order, each parameter file's path and, for every key a launch-file dict sets,
///    "launch:<key>" or "launch:<key>:<launch argument>". The last entry that sets the
///    key names its origin.
/// A key without an override has its default; an override none of these explains is
/// "a launch or -p override".
class ParameterOrigins {
 public:
  static constexpr const char* kSourcesKey = "tactile.parameter_sources";

  /// `overrides`: the node's parameter overrides (all of them, from files, -p and
  /// NodeOptions), to tell a default from a given value.
  /// NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode (the same parameter interface).
  template <class NodeT>
  ParameterOrigins(const NodeT& node, std::map<std::string, rclcpp::ParameterValue> overrides)
  : fqn_(node.get_fully_qualified_name()), overrides_(std::move(overrides)) {
    if (node.has_parameter(kSourcesKey)) {
      const auto value = node.get_parameter(kSourcesKey).get_parameter_value();
      if (value.get_type() == rclcpp::ParameterType::PARAMETER_STRING_ARRAY) {
        for (const auto& entry : value.template get<std::vector<std::string>>()) launch_.push_back(parse_source(entry));
      }
    }
    const auto& options = node.get_node_options();
    // rclcpp applies global arguments, then the node's own, then NodeOptions overrides.
    if (options.use_global_arguments() && options.context()) {
      add_rcl_files(&options.context()->get_rcl_context()->global_arguments);
    }
    add_rcl_files(&options.get_rcl_node_options()->arguments);
  }

  /// "ros parameters of /whisker/left/tdorc_filter" plus where `key`'s value came from:
  /// " from <file>", " from the launch file (launch argument <name>)", " (default)", ...
  std::string of(const std::string& key) const {
    const std::string head = "ros parameters of " + fqn_;
    const auto given = overrides_.find(key);
    if (given == overrides_.end()) return defaults();
    for (auto it = launch_.rbegin(); it != launch_.rend(); ++it) {
      if (!it->file.empty() ? it->sets(key, nullptr) : it->key == key) {
        if (!it->file.empty()) return head + " from " + it->file;
        return head + " from the launch file" +
               (it->argument.empty() ? std::string() : " (launch argument " + it->argument + ")");
      }
    }
    for (auto it = rcl_files_.rbegin(); it != rcl_files_.rend(); ++it) {
      if (it->sets(key, &given->second)) return head + " from " + it->file;
    }
    return head + " (a launch or -p override" + files_note("; not from ") + ")";
  }

  /// The origin of the keys nobody set: "ros parameters of <node> (default; not set in <files>)".
  std::string defaults() const { return "ros parameters of " + fqn_ + " (default" + files_note("; not set in ") + ")"; }

  /// The parameter files named for the node, comma-separated ("" when none).
  std::string files() const {
    std::string out;
    for (const auto* list : {&launch_, &rcl_files_}) {
      for (const auto& s : *list) {
        if (!s.file.empty()) out += (out.empty() ? "" : ", ") + s.file;
      }
    }
    return out;
  }

 private:
  struct Source {
    std::string file;      ///< a parameter file, or empty for a launch-file override
    std::string key;       ///< the key a launch-file override sets
    std::string argument;  ///< the launch argument that override takes its value from
    bool readable = false;  ///< rcl's YAML reader could read `file`
    std::map<std::string, std::vector<rclcpp::ParameterValue>> values;  ///< this node's keys in `file`

    /// Whether the file sets `key` for the node (to `value`, when given).
    bool sets(const std::string& k, const rclcpp::ParameterValue* value) const {
      const auto it = values.find(k);
      if (it == values.end()) return false;
      if (value == nullptr) return true;
      for (const auto& v : it->second) {
        if (v == *value) return true;
      }
      return false;
    }
  };

  Source read_file(const std::string& path) const {
    Source s;
    s.file = path;
    try {
      // rcl's YAML reader, the one --params-file goes through, with ROS 2's node-name matching.
      for (const auto& p : rclcpp::parameters_from_map(rclcpp::parameter_map_from_yaml_file(path),
                                                       fqn_.c_str())) {
        s.values[p.get_name()].push_back(p.get_parameter_value());
      }
      s.readable = true;
    } catch (const std::exception&) {
      // Unreadable here (launch read it with PyYAML): it is still named among the files.
    }
    return s;
  }

  Source parse_source(const std::string& entry) const {
    const std::string prefix = "launch:";
    if (entry.compare(0, prefix.size(), prefix) != 0) return read_file(entry);
    Source s;
    const std::string rest = entry.substr(prefix.size());
    const auto colon = rest.find(':');
    s.key = rest.substr(0, colon);
    if (colon != std::string::npos) s.argument = rest.substr(colon + 1);
    return s;
  }

  void add_rcl_files(const rcl_arguments_t* args) {
    if (args == nullptr || args->impl == nullptr) return;
    const int count = rcl_arguments_get_param_files_count(args);
    if (count <= 0) return;
    rcl_allocator_t allocator = rcl_get_default_allocator();
    char** paths = nullptr;
    if (rcl_arguments_get_param_files(args, allocator, &paths) != RCL_RET_OK) {
      rcl_reset_error();
      return;
    }
    for (int i = 0; i < count; ++i) {
      rcl_files_.push_back(read_file(paths[i]));
      allocator.deallocate(paths[i], allocator.state);
    }
    allocator.deallocate(paths, allocator.state);
  }

  /// lead + the files (or "; parameter files: <files>" when rcl could not read one).
  std::string files_note(const char* lead) const {
    const std::string f = files();
    if (f.empty()) return f;
    bool all_readable = true;
    for (const auto* list : {&launch_, &rcl_files_}) {
      for (const auto& s : *list) all_readable = all_readable && (s.file.empty() || s.readable);
    }
    return (all_readable ? lead : "; parameter files: ") + f;
  }

  std::string fqn_;
  std::map<std::string, rclcpp::ParameterValue> overrides_;
  std::vector<Source> launch_;     ///< tactile.parameter_sources, in launch's order
  std::vector<Source> rcl_files_;  ///< --params-file arguments, in rclcpp's order
};

/// Where a node's parameter values came from, for error messages that are not about one
/// key: "ros parameters of <node> (<its parameter files>)".
template <class NodeT = rclcpp::Node>
std::string parameter_source(const NodeT& node) {
  const std::string files = ParameterOrigins(node, {}).files();
  return std::string("ros parameters of ") + node.get_fully_qualified_name() +
         (files.empty() ? std::string(" (launch or -p overrides)") : " (" + files + ")");
}

/// Declares every parameter of `defaults` on `node` and returns the values the
/// node was started with (launch file / --params-file overrides included).
/// Every key remembers where its value came from (ParameterOrigins), so any
/// ParamError about it — a wrong type here, an invalid value in the node
/// logic — names the node, the file (or launch override), the key and the
/// reason. A value of the wrong type names the type it has and the type it
/// needs, e.g. "52.0e9" (a string to YAML 1.1, which the launch system's parser
/// follows: write 52.0e+9).
/// NodeT: rclcpp::Node or rclcpp_lifecycle::LifecycleNode.
template <class NodeT = rclcpp::Node>
ParamMap declare_parameters(NodeT& node, const ParamMap& defaults) {
  if (!node.has_parameter(ParameterOrigins::kSourcesKey)) {
    rcl_interfaces::msg::ParameterDescriptor descriptor;
    descriptor.dynamic_typing = true;  // a launch file may pass it malformed: then it is ignored
    descriptor.description = "where the parameter values come from (launch files set it)";
    node.declare_parameter(ParameterOrigins::kSourcesKey, rclcpp::ParameterValue(std::vector<std::string>{}),
                           descriptor);
  }
  const ParameterOrigins origins(node, node.get_node_parameters_interface()->get_parameter_overrides());
  const auto error = [&](const std::string& key, const std::string& reason) {
    return ParamMap(node.get_name(), origins.of(key)).error(key, reason);
  };
  ParamMap params(node.get_name(), origins.defaults());
  std::map<std::string, ParamMap> given_by_origin;  // merged below, so each key keeps its origin
  for (const auto& [key, value] : defaults.values()) {
    const rclcpp::ParameterValue fallback = to_ros(value);
    rclcpp::ParameterValue given;
    try {
      rcl_interfaces::msg::ParameterDescriptor descriptor;
      descriptor.dynamic_typing = true;  // checked below with a message that names the key
      given = node.declare_parameter(key, fallback, descriptor);
    } catch (const rclcpp::exceptions::InvalidParameterValueException& e) {
      throw error(key, e.what());
    }
    const bool widened = fallback.get_type() == rclcpp::ParameterType::PARAMETER_DOUBLE &&
                         given.get_type() == rclcpp::ParameterType::PARAMETER_INTEGER;
    if (given.get_type() != fallback.get_type() && !widened) {
      std::string reason = "is a " + rclcpp::to_string(given.get_type()) + " (" +
                           rclcpp::to_string(given) + "), expected a " +
                           rclcpp::to_string(fallback.get_type());
      if (given.get_type() == rclcpp::ParameterType::PARAMETER_STRING &&
          fallback.get_type() == rclcpp::ParameterType::PARAMETER_DOUBLE) {
        reason += " (YAML 1.1, which the launch system reads, takes 52.0e9 as a string: write 52.0e+9)";
      }
      throw error(key, reason);
    }
    ParamValue v = widened ? ParamValue(static_cast<double>(given.get<int64_t>())) : from_ros(given, key);
    params.set(key, v);
    const std::string origin = origins.of(key);
    if (origin != params.source()) {
      given_by_origin.try_emplace(origin, node.get_name(), origin).first->second.set(key, std::move(v));
    }
  }
  for (const auto& [origin, given] : given_by_origin) params.merge_from(given);
  return params;
}

}  // namespace tactile_common
