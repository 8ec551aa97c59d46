// rclcpp side of the parameter bridge: declares every parameter a node logic
// reads (with the logic's defaults and descriptors) on an rclcpp::Node and returns
// the values as a ParamMap; NodeParameters adds the on-set callback that applies a
// live key through the logic or refuses the set with the reason. Header-only and included only by rclcpp components, so the
// ROS-free build never sees rclcpp.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <sstream>
#include <stdexcept>
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

/// The descriptor `ros2 param describe` shows for `key`: its ParamInfo's description, unit
/// and source ("[paper: 000 eq. 8]"), its range as a FloatingPointRange / IntegerRange (closed hull; an open end and the
/// live/read-only rule in additional_constraints), read_only unless `live`.
/// dynamic_typing stays on: a YAML integer for a double key is widened, and a value of a
/// wrong type is refused with a message that names the key (declare_parameters, and the
/// on-set callback of NodeParameters).
inline rcl_interfaces::msg::ParameterDescriptor parameter_descriptor(const std::string& key, const ParamValue& value,
                                                                     const ParamInfo* info, bool live) {
  rcl_interfaces::msg::ParameterDescriptor d;
  d.name = key;
  d.dynamic_typing = true;
  d.read_only = !live;
  std::string constraints;
  if (info != nullptr) {
    // "... [Pa] [paper: 000 Results: 20]": the unit, then where the value comes from.
    d.description = info->description + (info->unit.empty() ? std::string() : " [" + info->unit + "]") +
                    (info->source.kind == ParamSource::kUnset ? std::string() : " [" + info->source.text() + "]");
    if (info->range) {
      const ParamRange& r = *info->range;
      if (std::holds_alternative<double>(value)) {
        rcl_interfaces::msg::FloatingPointRange range;
        range.from_value = r.lo;
        range.to_value = r.hi;
        range.step = 0.0;
        d.floating_point_range.push_back(range);
      } else if (std::holds_alternative<int64_t>(value)) {
        rcl_interfaces::msg::IntegerRange range;
        // Integer ranges of the workspace are closed and finite (get_int(key, lo, hi));
        // an unbounded end is the int64 limit.
        const auto to_int = [](double v, int64_t unbounded) {
          return std::isfinite(v) && std::fabs(v) < 9.2e18 ? static_cast<int64_t>(v) : unbounded;
        };
        range.from_value = to_int(std::ceil(r.lo), INT64_MIN);
        range.to_value = to_int(std::floor(r.hi), INT64_MAX);
        range.step = 1;
        d.integer_range.push_back(range);
      }
      constraints = "range " + r.text() + "; ";
    }
  }
  constraints += live ? "live: a new value is applied while running, after the node's validation"
                      : "read at start: restart the node to change it";
  d.additional_constraints = constraints;
  return d;
}

/// The reason a value outside its descriptor's range is refused ("must be in [2, 100000], got 1").
inline std::string range_reason(const ParamInfo* info, const rclcpp::ParameterValue& value) {
  if (info == nullptr || !info->range) return "out of its descriptor's range";
  std::ostringstream given;  // 0.05, not rclcpp's 0.050000
  if (value.get_type() == rclcpp::ParameterType::PARAMETER_DOUBLE) {
    given << value.get<double>();
  } else {
    given << rclcpp::to_string(value);
  }
  return "must be in " + info->range->text() + ", got " + given.str();
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
/// The keys of `defaults` a node applies while running are those whose ParamInfo is live,
/// and only when `live_keys` is true (NodeParameters with an apply function); every other
/// key is declared read-only.
template <class NodeT = rclcpp::Node>
ParamMap declare_parameters(NodeT& node, const ParamMap& defaults, bool live_keys = false) {
  if (!node.has_parameter(ParameterOrigins::kSourcesKey)) {
    rcl_interfaces::msg::ParameterDescriptor descriptor;
    descriptor.dynamic_typing = true;  // a launch file may pass it malformed: then it is ignored
    descriptor.description = "where the parameter values come from (launch files set it)";
    descriptor.read_only = true;  // read at start, as every key that is not live
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
    const ParamInfo* info = defaults.info(key);
    try {
      // Types are checked below with a message that names the key.
      given = node.declare_parameter(key, fallback,
                                     parameter_descriptor(key, value, info, live_keys && info && info->live));
    } catch (const rclcpp::exceptions::InvalidParameterValueException& e) {
      // Outside the descriptor's range: the range and the value as given, like validate().
      const auto overrides = node.get_node_parameters_interface()->get_parameter_overrides();
      const auto it = overrides.find(key);
      throw error(key, it == overrides.end() ? std::string(e.what()) : range_reason(info, it->second));
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

/// The parameters of a node (one or more node logics' default_parameters()), declared with
/// their descriptors, and the node's on-set callback, so that `ros2 param set` is never
/// accepted and ignored:
///  - a key whose ParamInfo is live (and the node gave an apply function): the new value is
///    type-checked, then `apply` gets the node's current values with it (apply builds the
///    logic's Params with params_from(), which validates, and hands them to the logic);
///    a ParamError or std::invalid_argument from it refuses the value with its reason and
///    nothing changes;
///  - every other key of these maps is read-only (its descriptor says so, and rclcpp refuses
///    the set: "parameter '<key>' cannot be set because it is read-only"); the callback
///    refuses it too, naming the key, should the descriptor be changed;
///  - keys that are not the node logic's (use_sim_time, qos_overrides.*) are left to rclcpp.
/// The callback runs in the node's default callback group, as its subscriptions and timers
/// do unless a component puts them elsewhere: the logic is not read concurrently.
/// Holds the callback's handle: a member of the component, declared before the logic it
/// configures, never moved.
class NodeParameters {
 public:
  /// Receives the node's values with the new ones; throws ParamError (params_from) or
  /// std::invalid_argument (the logic's own refusal) to refuse them.
  using Apply = std::function<void(const ParamMap&)>;

  template <class NodeT>
  NodeParameters(NodeT& node, const ParamMap& defaults, Apply apply = nullptr)
  : NodeParameters(node, std::initializer_list<ParamMap>{defaults}, std::move(apply)) {}

  /// Several node logics on one node (the bridge and its health thresholds): their keys
  /// must differ.
  template <class NodeT>
  NodeParameters(NodeT& node, std::initializer_list<ParamMap> defaults, Apply apply = nullptr)
  : defaults_(combined(node.get_name(), defaults)), apply_(std::move(apply)) {
    values_ = declare_parameters(node, defaults_, static_cast<bool>(apply_));
    node_name_ = node.get_fully_qualified_name();
    handle_ = node.add_on_set_parameters_callback(
      [this](const std::vector<rclcpp::Parameter>& parameters) { return on_set(parameters); });
  }
  NodeParameters(const NodeParameters&) = delete;
  NodeParameters& operator=(const NodeParameters&) = delete;

  /// The node's current values (at start: as declare_parameters returned them).
  const ParamMap& values() const { return values_; }
  /// The keys applied while running.
  std::vector<std::string> live_keys() const {
    std::vector<std::string> keys;
    if (!apply_) return keys;
    for (const auto& [key, info] : defaults_.infos()) {
      if (info.live) keys.push_back(key);
    }
    return keys;
  }

 private:
  static ParamMap combined(const std::string& node, std::initializer_list<ParamMap> maps) {
    ParamMap all(node, "defaults");
    for (const auto& m : maps) {
      for (const auto& [key, value] : m.values()) {
        if (all.has(key)) throw std::logic_error("NodeParameters: key " + key + " of node " + node + " declared twice");
        if (const ParamInfo* info = m.info(key)) {
          all.set(key, value, *info);
        } else {
          all.set(key, value);
        }
      }
    }
    return all;
  }

  rcl_interfaces::msg::SetParametersResult on_set(const std::vector<rclcpp::Parameter>& parameters) {
    rcl_interfaces::msg::SetParametersResult result;
    result.successful = false;
    ParamMap changed(values_.node(), "ros parameters of " + node_name_ + " (set while running)");
    for (const auto& p : parameters) {
      const std::string& key = p.get_name();
      if (key == ParameterOrigins::kSourcesKey) {
        result.reason = "read-only: " + key + " is read at start; restart the node";
        return result;
      }
      if (!defaults_.has(key)) continue;  // rclcpp's own (use_sim_time, qos_overrides.*)
      const ParamInfo* info = defaults_.info(key);
      if (!apply_ || info == nullptr || !info->live) {
        result.reason = "read-only: " + key + " is read at start; restart the node";
        return result;
      }
      const ParamValue& fallback = defaults_.values().at(key);
      const rclcpp::ParameterValue& given = p.get_parameter_value();
      const bool widened = std::holds_alternative<double>(fallback) &&
                           given.get_type() == rclcpp::ParameterType::PARAMETER_INTEGER;
      if (!widened && given.get_type() != to_ros(fallback).get_type()) {
        result.reason = key + ": is a " + rclcpp::to_string(given.get_type()) + " (" + rclcpp::to_string(given) +
                        "), expected a " + rclcpp::to_string(to_ros(fallback).get_type());
        return result;
      }
      if (info->range && (given.get_type() == rclcpp::ParameterType::PARAMETER_DOUBLE ||
                          given.get_type() == rclcpp::ParameterType::PARAMETER_INTEGER)) {
        const double v = given.get_type() == rclcpp::ParameterType::PARAMETER_DOUBLE
                             ? given.get<double>()
                             : static_cast<double>(given.get<int64_t>());
        if (!info->range->contains(v)) {
          result.reason = key + ": " + range_reason(info, given);
          return result;
        }
      }
      changed.set(key, widened ? ParamValue(static_cast<double>(given.get<int64_t>())) : from_ros(given, key));
    }
    if (changed.values().empty()) {
      result.successful = true;
      return result;
    }
    ParamMap next = values_;
    try {
      next.merge_from(changed);
      apply_(next);
    } catch (const std::exception& e) {  // ParamError (params_from) or the logic's refusal
      result.reason = e.what();
      return result;
    }
    values_ = std::move(next);
    result.successful = true;
    return result;
  }

  ParamMap defaults_;
  Apply apply_;
  ParamMap values_;
  std::string node_name_;
  rclcpp::node_interfaces::OnSetParametersCallbackHandle::SharedPtr handle_;
};

}  // namespace tactile_common
