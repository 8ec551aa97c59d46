// rclcpp side of the parameter bridge: declares every parameter a node logic
// reads (with the logic's defaults) on an rclcpp::Node and returns the values
// as a ParamMap. Header-only and included only by rclcpp components, so the
// ROS-free build never sees rclcpp.
#pragma once

#include <string>
#include <type_traits>
#include <variant>

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
      throw ParamError("ros parameters: " + key + ": unsupported parameter type");
  }
}

/// Declares every parameter of `defaults` on `node` and returns the values the
/// node was started with (launch file / --params-file overrides included).
inline ParamMap declare_parameters(rclcpp::Node& node, const ParamMap& defaults) {
  ParamMap params(node.get_name(), "ros parameters of " + node.get_fully_qualified_name());
  for (const auto& [key, value] : defaults.values()) {
    params.set(key, from_ros(node.declare_parameter(key, to_ros(value)), key));
  }
  return params;
}

}  // namespace tactile_common
