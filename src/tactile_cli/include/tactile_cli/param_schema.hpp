// The parameter schema of every node (issue 33, item 4): each node logic's
// default_parameters() is the one definition of its keys (value, description, unit,
// range, live). `tactile params` prints it as a markdown table or as a ROS 2
// parameter file; the package READMEs carry the generated table between
//   <!-- BEGIN params <node> -->
//   <!-- END params <node> -->
// and test_param_schema checks the READMEs and config/<node>.yaml against it.
#pragma once

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/parameters.hpp"

namespace tactile_cli {

/// One ROS 2 node: the keys `ros2 param list` shows for it (one node logic, or two
/// whose maps the component declares together: bridge + health, driver + health).
struct NodeSchema {
  std::string name;     ///< node name, e.g. "tdorc_filter" (its section is /**/<name>)
  std::string package;  ///< the package whose README documents it
  /// The files under config/ the launches pass to the node, in launch order; empty when
  /// its values come from launch arguments (tactile_sim).
  std::vector<std::string> config_files;
  /// Fully qualified names the launches run it as (namespaced sections per instance).
  std::vector<std::string> instances;
  /// Every key with its default and ParamInfo (the logics' default_parameters()).
  std::function<tactile_common::ParamMap()> parameters;
};

/// Every node with parameters, by name.
const std::vector<NodeSchema>& node_schemas();

/// A node name that no schema has; the message lists the known ones.
class UnknownNode : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The schema of `name`; UnknownNode otherwise.
const NodeSchema& node_schema(const std::string& name);

/// A value as a ROS 2 parameter file writes it: 100, 5.0, 2.0e-04, .inf, true,
/// "text", [1.0, -2.0]. Doubles keep a '.' (an integer there is the wrong type for ROS)
/// and the shortest text that reads back to the same double.
std::string yaml_value(const tactile_common::ParamValue& value);

/// The node's parameters as a markdown table (key, type, default, range, unit,
/// live/read-only, source as "paper: 000 eq. 8" / "choice" / "tuned: <evidence>", description), one row per key in `ros2 param list` order, after a
/// line naming the node, the count and how the table is made.
std::string schema_markdown(const NodeSchema& node);

/// The node's parameters as a ROS 2 parameter file: a /**/<node> section with every key
/// at its default, each after a comment with its description, unit, range, whether it
/// is live, and "source: paper|choice|tuned" with "evidence: ..." (when it has any). `load_node_parameters` reads it back to the defaults.
std::string schema_yaml(const NodeSchema& node);

/// A shipped value (config/<file>) that is not the key's default_parameters() default.
struct ShippedValue {
  std::string instance;  ///< the node instance it applies to ("/whisker/left/tdorc_filter")
  std::string key;
  std::string file;                   ///< the file that sets it
  tactile_common::ParamValue shipped;  ///< the file's value
  tactile_common::ParamValue fallback; ///< the default
};

/// What the node's config files set, for every instance (as ROS 2 and the standalone host
/// read them: tactile_common::load_node_parameters).
struct ShippedConfig {
  std::vector<std::string> missing;      ///< keys some instance gets from no file ("key" or "key (instance)")
  std::vector<std::string> twice;        ///< keys two files set for one instance ("key: a.yaml, b.yaml")
  std::vector<ShippedValue> differing;   ///< shipped values that differ from the default
};

/// Reads each of node.config_files in `config_dir` for each instance. A key the node does
/// not have (a typo), a value of the wrong type, a missing file or a file without the node's
/// section throws tactile_common::ParamError naming the file, the key and the reason.
ShippedConfig shipped_config(const NodeSchema& node, const std::string& config_dir);

/// A README whose parameter blocks are malformed: the message names the source, the line
/// and the reason.
class ReadmeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A README with its parameter blocks regenerated.
struct ReadmeTables {
  std::string text;                ///< the README with every block's table regenerated
  std::vector<std::string> nodes;  ///< the nodes of its blocks, in order
};

/// Replaces the lines between each `<!-- BEGIN params <node> -->` and its
/// `<!-- END params <node> -->` by schema_markdown(<node>). ReadmeError (naming `source`
/// and the line) for an unknown node, a BEGIN without its END, an END without its BEGIN,
/// nested blocks or a node's second block; the text outside the blocks is kept as it is.
ReadmeTables regenerate_param_tables(const std::string& text, const std::string& source);

/// The documents of the packages under `src_dir` that may carry parameter blocks:
/// `<package>/README.md` and `<package>/docs/*.md` (a package whose README points to a
/// page per behaviour: tactile_fsm), sorted.
std::vector<std::filesystem::path> package_documents(const std::string& src_dir);

/// regenerate_param_tables() on every package_documents() file, writing those whose
/// tables changed. One line per file with blocks: its path, its nodes, "updated" or
/// "up to date". ReadmeError on a malformed file (nothing of it is written).
std::vector<std::string> write_param_tables(const std::string& src_dir);

}  // namespace tactile_cli
