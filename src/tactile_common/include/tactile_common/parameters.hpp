// ROS-free node parameters: typed values, a map per node, and the loader for
// ROS 2 `ros__parameters` YAML files. The rclcpp components declare the same
// parameters (tactile_common/ros_parameters.hpp), so a node reads identical
// values under both hosts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
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

/// A numeric range of a parameter, as its node logic's params_from()/validate() check it.
/// Closed unless an end is marked open ("> 0" is {0, inf, open_lo}). A ROS parameter
/// descriptor states the closed hull [lo, hi] (rcl_interfaces ranges are inclusive) and
/// names an open end in its additional_constraints; validate() rejects the end itself.
struct ParamRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool open_lo = false;
  bool open_hi = false;
  /// "[2, 100000]", "(0, inf)", "[0, 1]".
  std::string text() const;
  /// Whether `v` lies in the range (open ends excluded).
  bool contains(double v) const;
};

/// [lo, hi]; (lo, inf); [lo, inf).
inline ParamRange closed(double lo, double hi) { return {lo, hi, false, false}; }
inline ParamRange positive() { return {0.0, std::numeric_limits<double>::infinity(), true, true}; }
inline ParamRange at_least(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, true}; }

/// Where a parameter's value comes from (issue 33 item 4):
///  - kPaper: one of the four papers gives the value or the rule it implements (000 Ye et al.
///    whiskers, 001 XPLORER, 002 whisker localization, 004 ducted-rotor wall effect);
///  - kTuned: chosen by measurement on the SITL families or bags (docs/tuning/*.md rounds, a
///    README's measurement, the issue 17 rules);
///  - kChoice: an engineering choice without such a measurement (units, topics, frames, rates,
///    safety margins, file paths, modes);
///  - kUnset: not classified yet (tactile_cli's ParamSources test lists the nodes allowed to
///    have such keys; it is empty once every node is done).
enum class ParamSource { kUnset, kPaper, kChoice, kTuned };

/// "paper", "choice", "tuned" ("unset" for kUnset).
const char* to_string(ParamSource s);

/// The source of a value and its evidence: for paper, the paper and equation / section /
/// table ("000 eq. 8, Methods n = 100"); for tuned, the measurement ("docs/tuning/tactile_fsm.md
/// Round 4"); for choice, a short why ("" when the description says it).
struct ParamOrigin {
  ParamSource kind = ParamSource::kUnset;
  std::string evidence;
  /// "paper: 000 eq. 8", "choice", "tuned: docs/tuning/x.md Round 2"; "" when unset.
  std::string text() const;
};

/// The last member of a ParamInfo, one short argument per m.set(...):
///   m.set("window", 100, {"n, samples in the drift window", "samples", closed(2, 100000), false,
///                         paper("000 Methods, n = 100")});
inline ParamOrigin paper(std::string evidence) { return {ParamSource::kPaper, std::move(evidence)}; }
inline ParamOrigin choice(std::string why = "") { return {ParamSource::kChoice, std::move(why)}; }
inline ParamOrigin tuned(std::string evidence) { return {ParamSource::kTuned, std::move(evidence)}; }

/// What a key means, for people and ROS tools (`ros2 param describe`): the one place
/// per node is its logic's default_parameters(), next to the default value.
struct ParamInfo {
  ParamInfo() = default;
  /// {description, unit, range, live, source}: the form every default_parameters() writes.
  /// A constructor rather than an aggregate so that a call without its source (a node not
  /// converted yet) compiles without -Wmissing-field-initializers.
  ParamInfo(std::string what, std::string unit_text = "", std::optional<ParamRange> accepted = std::nullopt,
            bool applied_live = false, ParamOrigin origin = {})
      : description(std::move(what)),
        unit(std::move(unit_text)),
        range(std::move(accepted)),
        live(applied_live),
        source(std::move(origin)) {}
  /// What the key does (from the Params struct comment), with its source (paper, README).
  std::string description;
  /// SI unit or count ("Pa", "s", "m", "mm^2", "samples", "V"); "" when dimensionless.
  std::string unit;
  /// The range params_from()/validate() accept, where they check one.
  std::optional<ParamRange> range;
  /// true: the node applies a new value while running (`ros2 param set`) through
  /// params_from() + validate(); false: read at start only (read-only in ROS).
  bool live = false;
  /// paper / choice / tuned, with the evidence.
  ParamOrigin source;
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
  /// The value and its description (see ParamInfo).
  void set(const std::string& key, ParamValue value, ParamInfo info);
  /// The description of `key`, nullptr if it has none.
  const ParamInfo* info(const std::string& key) const;
  const std::map<std::string, ParamInfo>& infos() const { return info_; }
  bool has(const std::string& key) const;
  const std::map<std::string, ParamValue>& values() const { return values_; }

  /// Typed getters. Throw ParamError if the key is missing or holds another
  /// type. An integer is accepted where a double is asked for.
  bool get_bool(const std::string& key) const;
  /// The raw 64-bit integer, unchecked. Node logic reads integers with the
  /// range-checked getters below instead: a value narrowed after this call
  /// wraps silently (2^32 + 10 read into an int is 10).
  [[deprecated("read integer parameters with get_int(key, lo, hi), get_int64, get_size or get_integer<T>")]]
  int64_t get_int(const std::string& key) const;

  /// Range-checked integers: the integer `key`, checked to lie in [lo, hi]
  /// BEFORE it is narrowed to T, so no value wraps into range. Throws
  /// ParamError if the key is missing, is not an integer ("expected integer,
  /// got double") or lies outside [lo, hi]:
  ///   "<source>: <node>.ros__parameters.<key>: must be in [lo, hi], got <value as given>"
  /// lo/hi are the parameter's documented range (the README's "Integer
  /// parameters" says which bounds each node passes and how they relate to
  /// its Params::validate()). std::logic_error if lo > hi (a bug of the caller).
  template <typename T>
  T get_integer(const std::string& key, T lo, T hi) const;
  /// get_integer<int>: counts and windows held in an int.
  int get_int(const std::string& key, int lo, int hi) const { return get_integer<int>(key, lo, hi); }
  int64_t get_int64(const std::string& key, int64_t lo, int64_t hi) const {
    return get_integer<int64_t>(key, lo, hi);
  }
  /// Sizes; a negative value is out of range (never wrapped to a huge size).
  std::size_t get_size(const std::string& key, std::size_t lo, std::size_t hi) const {
    return get_integer<std::size_t>(key, lo, hi);
  }
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
  /// The stored integer of `key` (ParamError if missing or not an integer).
  int64_t raw_int(const std::string& key) const;
  /// The error of a value outside [lo, hi] (bounds and value already as text).
  [[noreturn]] void out_of_range(const std::string& key, const std::string& lo, const std::string& hi,
                                 int64_t value) const;

  std::string node_;
  std::string source_ = "defaults";
  std::map<std::string, ParamValue> values_;
  std::map<std::string, std::string> origin_;  ///< keys set by merge_from
  std::map<std::string, ParamInfo> info_;      ///< descriptions, from default_parameters()
};

template <typename T>
T ParamMap::get_integer(const std::string& key, T lo, T hi) const {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>, "get_integer<T>: T must be an integer type");
  if (lo > hi) {
    throw std::logic_error("ParamMap::get_integer(\"" + key + "\"): empty range [" + std::to_string(lo) + ", " +
                           std::to_string(hi) + "]");
  }
  const int64_t v = raw_int(key);
  // Compared as 64-bit values before any narrowing. Every T's bounds fit in
  // int64_t except unsigned ones above INT64_MAX, which no stored value reaches.
  bool in_range;
  if constexpr (std::is_signed_v<T>) {
    in_range = v >= static_cast<int64_t>(lo) && v <= static_cast<int64_t>(hi);
  } else {
    in_range = v >= 0 && static_cast<uint64_t>(v) >= static_cast<uint64_t>(lo) &&
               static_cast<uint64_t>(v) <= static_cast<uint64_t>(hi);
  }
  if (!in_range) out_of_range(key, std::to_string(lo), std::to_string(hi), v);
  return static_cast<T>(v);
}

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
/// wrong types, YAML syntax errors, a missing file, a path that is not a
/// regular file (a directory), an empty file (or comments only) and a file
/// without a section naming the node (the catch-all '/**' alone does not)
/// throw ParamError naming the file, the node or key and the reason: a node
/// never runs on its compiled defaults because its file was lost or misnamed.
/// A section naming the node with an empty 'ros__parameters' keeps the
/// defaults on purpose. Nested maps are flattened with '.' ("kf.q"), as ROS 2
/// does.
ParamMap load_node_parameters(const std::string& path, const std::string& node_name,
                              const ParamMap& defaults);

/// The values a parameter *profile* sets for the node: a ROS 2 parameter file (same
/// sections and checks as above: unknown keys, wrong types and syntax are errors naming the
/// file) that names only the nodes it changes, so a file without a section for the node
/// gives an empty overlay. `params` are the node's parameters so far (their keys and types
/// check the profile's); the overlay holds the keys whose value the profile changes. Its
/// source is `path`; merge it with
/// ParamMap::merge_from (config/profiles/, tactile_cli Host::use_profile).
ParamMap load_profile_overlay(const std::string& path, const std::string& node_name, const ParamMap& params);

/// Same, from YAML text (for tests and embedded configs), with the same rules
/// for an empty text and a missing section. `source` names it in errors.
ParamMap load_node_parameters_from_string(const std::string& yaml, const std::string& source,
                                          const std::string& node_name, const ParamMap& defaults);

}  // namespace tactile_common
