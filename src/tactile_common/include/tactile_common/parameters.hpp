// ROS-free node parameters: typed values, a map per node, and the loader for
// ROS 2 `ros__parameters` YAML files. The rclcpp components declare the same
// parameters (tactile_common/ros_parameters.hpp), so a node reads identical
// values under both hosts.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace tactile_common {

/// A parameter value: the subset of rclcpp::ParameterValue types the workspace uses.
using ParamValue = std::variant<bool, int64_t, double, std::string, std::vector<bool>,
                                std::vector<int64_t>, std::vector<double>, std::vector<std::string>>;

/// Name of the type held by a ParamValue ("bool", "integer", "double", "string",
/// "bool array", ...), as used in error messages.
std::string type_name(const ParamValue& value);

/// Error in configuration: names the source (file), the key path and the reason.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The parameters of one node. Every key a node reads is declared in its
/// default_parameters(); getters check the type and name the source on error.
class ParamMap {
 public:
  ParamMap() = default;
  /// @param node   node name, used in error messages ("tdorc_filter")
  /// @param source where the values come from ("config/tdorc_filter.yaml", "defaults")
  ParamMap(std::string node, std::string source);

  const std::string& node() const { return node_; }
  const std::string& source() const { return source_; }

  void set(const std::string& key, ParamValue value);
  bool has(const std::string& key) const;
  const std::map<std::string, ParamValue>& values() const { return values_; }

  /// Typed getters. Throw ParamError if the key is missing or holds another
  /// type. An integer is accepted where a double is asked for.
  bool get_bool(const std::string& key) const;
  int64_t get_int(const std::string& key) const;
  double get_double(const std::string& key) const;
  std::string get_string(const std::string& key) const;
  std::vector<bool> get_bool_array(const std::string& key) const;
  std::vector<int64_t> get_int_array(const std::string& key) const;
  std::vector<double> get_double_array(const std::string& key) const;
  std::vector<std::string> get_string_array(const std::string& key) const;

  /// A ParamError for `key` with `reason`, formatted like every other
  /// parameter error: "<source>: <node>.ros__parameters.<key>: <reason>",
  /// where <source> is where this key's value came from (the file that set
  /// it, or the map's own source for defaults).
  /// Node logic uses it when a value has the right type but is invalid.
  ParamError error(const std::string& key, const std::string& reason) const;
  /// The parameter error for a core Params::validate() failure whose message
  /// reads "<Type>.<field>[<i>]: <reason>" (the workspace convention): the
  /// key is <field>, the reason the text after ": " (the whole message when
  /// it has no ": ").
  ParamError error_from(const std::invalid_argument& e) const;

  /// Overlays `other` onto this map: keys of `other` must exist here (unknown
  /// keys are typos) and have a compatible type; the source of each error is
  /// other.source(). Each overlaid key remembers other.source() as its origin.
  void merge_from(const ParamMap& other);
  /// Where the value of `key` came from.
  const std::string& origin(const std::string& key) const;

 private:
  const ParamValue& at(const std::string& key) const;
  [[noreturn]] void wrong_type(const std::string& key, const char* wanted) const;

  std::string node_;
  std::string source_ = "defaults";
  std::map<std::string, ParamValue> values_;
  std::map<std::string, std::string> origin_;  ///< keys set by merge_from
};

/// Reads the parameters of a node from a ROS 2 parameter file. `node_name` is
/// the node's fully qualified name ("/whisker/left/tdorc_filter"; a name
/// without namespace is in the root namespace). Sections match as in ROS 2:
///
///   /**:                        # every node
///     ros__parameters: {...}
///   /**/tdorc_filter:           # tdorc_filter in any namespace ('*' = one token)
///     ros__parameters: {...}
///   /whisker/left/tdorc_filter: # exactly this node (leading '/' optional)
///     ros__parameters: {...}
///
/// Less specific sections apply first, so an exact name overrides a wildcard.
/// Starts from `defaults`; values in the file override them. Unknown keys,
/// wrong types, YAML syntax errors and a missing file throw ParamError naming
/// the file, the key and the reason. Nested maps are flattened with '.'
/// ("kf.q"), as ROS 2 does.
ParamMap load_node_parameters(const std::string& path, const std::string& node_name,
                              const ParamMap& defaults);

/// Same, from YAML text (for tests and embedded configs). `source` names it in errors.
ParamMap load_node_parameters_from_string(const std::string& yaml, const std::string& source,
                                          const std::string& node_name, const ParamMap& defaults);

}  // namespace tactile_common
