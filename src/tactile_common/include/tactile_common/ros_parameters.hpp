// rclcpp side of the parameter bridge: declares every parameter a node logic
// reads (with the logic's defaults) on an rclcpp::Node and returns the values
// as a ParamMap. Header-only and included only by rclcpp components, so the
// ROS-free build never sees rclcpp.
#pragma once

#include <string>
#include <type_traits>
#include <variant>
#include <vector>

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

/// Where a node's parameter values came from, for error messages: the
/// --params-file arguments of the node and of the process, or the load request
/// of a component container (launch evaluates parameter files itself and passes
/// the values, so the file's name does not reach the node).
inline std::string parameter_source(const rclcpp::Node& node) {
  std::string files;
  const auto& args = node.get_node_options().arguments();
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == "--params-file") files += (files.empty() ? "" : ", ") + args[i + 1];
  }
  return std::string("ros parameters of ") + node.get_fully_qualified_name() +
         (files.empty() ? std::string(" (launch or --params-file overrides)") : " (" + files + ")");
}

/// Declares every parameter of `defaults` on `node` and returns the values the
/// node was started with (launch file / --params-file overrides included).
/// A value of the wrong type throws ParamError naming the node, the key, the
/// type it has and the type it needs, e.g. "52.0e9" (a string to YAML 1.1, which
/// the launch system's parser follows: write 52.0e+9).
inline ParamMap declare_parameters(rclcpp::Node& node, const ParamMap& defaults) {
  ParamMap params(node.get_name(), parameter_source(node));
  for (const auto& [key, value] : defaults.values()) {
    const rclcpp::ParameterValue fallback = to_ros(value);
    rclcpp::ParameterValue given;
    try {
      rcl_interfaces::msg::ParameterDescriptor descriptor;
      descriptor.dynamic_typing = true;  // checked below with a message that names the key
      given = node.declare_parameter(key, fallback, descriptor);
    } catch (const rclcpp::exceptions::InvalidParameterValueException& e) {
      throw params.error(key, e.what());
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
      throw params.error(key, reason);
    }
    params.set(key, widened ? ParamValue(static_cast<double>(given.get<int64_t>())) : from_ros(given, key));
  }
  return params;
}

}  // namespace tactile_common
