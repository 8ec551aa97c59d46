#include "tactile_cli/param_schema.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <system_error>

#include "crazyflie_bridge/bridge_health.hpp"
#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "gpis_explorer/gpis_explorer_logic.hpp"
#include "mapping_pcl/xplorer_map_logic.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"
#include "tactile_fsm/wall_effect_nav_logic.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_viz/visualization_logic.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"
#include "wall_effect_ekf/indi_control_logic.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"
#include "whisker_driver/driver_health.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"
#include "whisker_localization/whisker_localization_logic.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

namespace tactile_cli {

namespace {

using tactile_common::ParamInfo;
using tactile_common::ParamMap;
using tactile_common::ParamValue;

// The keys of a node whose component declares two logics' maps (as
// NodeParameters::combined does): a key in both would be declared twice.
ParamMap combined(const std::string& node, std::initializer_list<ParamMap> maps) {
  ParamMap all(node, "defaults");
  for (const ParamMap& m : maps) {
    for (const auto& [key, value] : m.values()) {
      if (all.has(key)) throw std::logic_error("node " + node + ": parameter " + key + " declared by two logics");
      const ParamInfo* info = m.info(key);
      if (info == nullptr) throw std::logic_error("node " + node + ": parameter " + key + " has no ParamInfo");
      all.set(key, value, *info);
    }
  }
  return all;
}

std::vector<NodeSchema> make_schemas() {
  // Files and instances as the launch files pass them (launch/*.launch.py; the standalone
  // host reads the same files, Host::load_parameters).
  return {
      {"crazyflie_bridge", "crazyflie_bridge", {"crazyflie_bridge.yaml", "crazyflie_bridge_health.yaml"},
       {"crazyflie_bridge"},
       [] {
         return combined("crazyflie_bridge", {crazyflie_bridge::CrazyflieBridgeLogic::default_parameters(),
                                              crazyflie_bridge::BridgeHealth::default_parameters()});
       }},
      {"gpis_explorer", "gpis_explorer", {"gpis_explorer.yaml"}, {"gpis_explorer"},
       [] { return gpis_explorer::GpisExplorerLogic::default_parameters(); }},
      {"indi_controller", "wall_effect_ekf", {"indi_controller.yaml"}, {"indi_controller"},
       [] { return wall_effect_ekf::IndiControlLogic::default_parameters(); }},
      {"tactile_depth", "tactile_depth", {"tactile_depth.yaml"}, {"tactile_depth"},
       [] { return tactile_depth::TactileDepthLogic::default_parameters(); }},
      // No file: launch_common.simulator_node() passes every key from launch arguments.
      {"tactile_sim", "tactile_sim", {}, {"tactile_sim"},
       [] {
         return combined("tactile_sim", {tactile_sim::SimLogic::default_parameters(),
                                         tactile_sim::SimLogic::component_parameters()});
       }},
      {"tdorc_filter", "tdorc_filter", {"tdorc_filter.yaml"},
       {"/whisker/left/tdorc_filter", "/whisker/right/tdorc_filter"},
       [] { return tdorc_filter::TdorcFilterLogic::default_parameters(); }},
      // launch_common.visualization_nodes(); no component where visualization_msgs is missing.
      {"visualization", "tactile_viz", {"visualization.yaml"}, {"visualization"},
       [] { return tactile_viz::VisualizationLogic::default_parameters(); }},
      {"wall_effect_ekf", "wall_effect_ekf", {"wall_effect_ekf.yaml"}, {"wall_effect_ekf"},
       [] { return wall_effect_ekf::WallEffectEkfLogic::default_parameters(); }},
      {"wall_effect_nav", "tactile_fsm", {"wall_effect_nav.yaml"}, {"wall_effect_nav"},
       [] { return tactile_fsm::WallEffectNavLogic::default_parameters(); }},
      {"wall_trajectory", "wall_effect_ekf", {"wall_trajectory.yaml"}, {"wall_trajectory"},
       [] { return wall_effect_ekf::WallTrajectoryLogic::default_parameters(); }},
      {"whisker_driver", "whisker_driver", {"whisker_driver.yaml", "whisker_driver_health.yaml"},
       {"/whisker/left/whisker_driver", "/whisker/right/whisker_driver"},
       [] {
         return combined("whisker_driver", {whisker_driver::WhiskerDriverLogic::default_parameters(),
                                            whisker_driver::DriverHealth::default_parameters()});
       }},
      // The whisker FSM's file is named after its package (Host::load_parameters).
      {"whisker_fsm", "tactile_fsm", {"tactile_fsm.yaml"}, {"whisker_fsm"},
       [] { return tactile_fsm::WhiskerFsmLogic::default_parameters(); }},
      {"whisker_localization", "whisker_localization", {"whisker_localization.yaml"}, {"whisker_localization"},
       [] { return whisker_localization::WhiskerLocalizationLogic::default_parameters(); }},
      {"xplorer_force_est", "xplorer_force_est", {"xplorer_force_est.yaml"}, {"xplorer_force_est"},
       [] { return xplorer_force_est::XplorerForceEstLogic::default_parameters(); }},
      {"xplorer_fsm", "tactile_fsm", {"xplorer_fsm.yaml"}, {"xplorer_fsm"},
       [] { return tactile_fsm::XplorerFsmLogic::default_parameters(); }},
      {"xplorer_mapping", "mapping_pcl", {"xplorer_mapping.yaml"}, {"xplorer_mapping"},
       [] { return mapping_pcl::XplorerMapLogic::default_parameters(); }},
  };
}

std::string double_text(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest text that reads back to v
  if (r.ec != std::errc()) throw std::logic_error("double_text: to_chars failed");
  std::string s(buf, r.ptr);
  // A double keeps a '.' before any exponent: "5" is an integer to ROS 2 (the wrong
  // type) and YAML 1.1 reads "2e-04" as a string.
  const auto e = s.find('e');
  const std::string mantissa = s.substr(0, e);
  if (mantissa.find('.') == std::string::npos) s.insert(e == std::string::npos ? s.size() : e, ".0");
  return s;
}

std::string string_text(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

struct YamlText {
  std::string operator()(bool b) const { return b ? "true" : "false"; }
  std::string operator()(int64_t i) const { return std::to_string(i); }
  std::string operator()(double d) const { return double_text(d); }
  std::string operator()(const std::string& s) const { return string_text(s); }
  template <typename T>
  std::string operator()(const std::vector<T>& v) const {
    std::string out = "[";
    for (size_t i = 0; i < v.size(); ++i) {
      if (i) out += ", ";
      out += (*this)(static_cast<T>(v[i]));
    }
    return out + "]";
  }
};

std::string range_text(const ParamInfo& info) { return info.range ? info.range->text() : ""; }

// A table cell: '|' would end it, a line break would end the row.
std::string cell(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '|') {
      out += "\\|";
    } else if (c == '\n') {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out;
}

// `text` split into lines of at most `width` characters at spaces (a longer word stays whole).
std::vector<std::string> wrap(const std::string& text, size_t width) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string word, line;
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

const ParamInfo& info_of(const ParamMap& m, const std::string& key) {
  const ParamInfo* info = m.info(key);
  // default_parameters() describes every key (tactile_common: the one place per node).
  if (info == nullptr) throw std::logic_error("node " + m.node() + ": parameter " + key + " has no ParamInfo");
  return *info;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// "<!-- BEGIN params NODE -->" -> NODE (kind "BEGIN" or "END"); "" when the line is not one.
std::string marker_node(const std::string& line, const std::string& kind) {
  const std::string head = "<!-- " + kind + " params ";
  const std::string tail = " -->";
  const std::string t = trim(line);
  if (t.size() <= head.size() + tail.size() || t.compare(0, head.size(), head) != 0 ||
      t.compare(t.size() - tail.size(), tail.size(), tail) != 0) {
    return "";
  }
  return trim(t.substr(head.size(), t.size() - head.size() - tail.size()));
}

// A value of the same type that differs from `v`: loading a file over the defaults and over
// these shows which keys the file sets (its value either way) with the loader's own section
// rules (ParamMap::origin() cannot: a loaded map's own source is the file too).
struct Perturb {
  ParamValue operator()(bool b) const { return !b; }
  ParamValue operator()(int64_t i) const { return i == INT64_MAX ? i - 1 : i + 1; }
  ParamValue operator()(double d) const { return std::isnan(d) ? 0.0 : d == 1.0 ? 2.0 : 1.0; }
  ParamValue operator()(const std::string& s) const { return s + "\x01"; }
  template <typename T>
  ParamValue operator()(const std::vector<T>& v) const {
    std::vector<T> out(v.begin(), v.end());
    out.push_back(T{});
    return out;
  }
};

}  // namespace

const std::vector<NodeSchema>& node_schemas() {
  static const std::vector<NodeSchema> schemas = make_schemas();
  return schemas;
}

const NodeSchema& node_schema(const std::string& name) {
  std::string known;
  for (const auto& s : node_schemas()) {
    if (s.name == name) return s;
    known += (known.empty() ? "" : ", ") + s.name;
  }
  throw UnknownNode("unknown node '" + name + "' (known: " + known + ")");
}

std::string yaml_value(const ParamValue& value) { return std::visit(YamlText{}, value); }

std::string schema_markdown(const NodeSchema& node) {
  const ParamMap m = node.parameters();
  std::ostringstream out;
  out << "`" << node.name << "`: " << m.values().size()
      << " parameters, generated from `default_parameters()` by `tactile params " << node.name
      << "` (regenerate: `scripts/param_tables.sh`).\n\n";
  out << "| key | type | default | range | unit | live | source | description |\n";
  out << "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const auto& [key, value] : m.values()) {
    const ParamInfo& info = info_of(m, key);
    const std::string range = range_text(info);
    out << "| `" << key << "` | " << tactile_common::type_name(value) << " | `" << cell(yaml_value(value)) << "` | "
        << (range.empty() ? "" : cell(range)) << " | " << cell(info.unit) << " | "
        << (info.live ? "live" : "read-only") << " | " << cell(info.source.text()) << " | " << cell(info.description)
        << " |\n";
  }
  return out.str();
}

std::string schema_yaml(const NodeSchema& node) {
  const ParamMap m = node.parameters();
  std::ostringstream out;
  out << "# " << node.name << ": " << m.values().size() << " parameters at their defaults (tactile params "
      << node.name << " --format yaml).\n";
  if (node.config_files.empty()) {
    out << "# The launches pass every key as a launch argument (no file under config/).\n";
  } else {
    out << "# Shipped values: config/";
    for (size_t i = 0; i < node.config_files.size(); ++i) out << (i ? ", config/" : "") << node.config_files[i];
    out << ".\n";
  }
  out << "/**/" << node.name << ":\n  ros__parameters:\n";
  for (const auto& [key, value] : m.values()) {
    const ParamInfo& info = info_of(m, key);
    for (const auto& line : wrap(info.description, 88)) out << "    # " << line << "\n";
    std::string facts = tactile_common::type_name(value);
    if (!info.unit.empty()) facts += " [" + info.unit + "]";
    if (info.range) facts += ", range " + info.range->text();
    facts += info.live ? ", live (ros2 param set applies it)" : ", read-only";
    out << "    # " << facts << "\n";
    if (info.source.kind != tactile_common::ParamSource::kUnset) {
      out << "    # source: " << tactile_common::to_string(info.source.kind) << "\n";
      if (!info.source.evidence.empty()) {
        for (const auto& line : wrap("evidence: " + info.source.evidence, 88)) out << "    # " << line << "\n";
      }
    }
    out << "    " << key << ": " << yaml_value(value) << "\n";
  }
  return out.str();
}

ReadmeTables regenerate_param_tables(const std::string& text, const std::string& source) {
  ReadmeTables result;
  std::set<std::string> seen;
  std::string open;  // the node of the block being replaced
  size_t open_line = 0;
  size_t line_no = 0;
  size_t pos = 0;
  auto fail = [&](size_t line, const std::string& why) -> ReadmeError {
    return ReadmeError(source + ":" + std::to_string(line) + ": " + why);
  };
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    const size_t end = nl == std::string::npos ? text.size() : nl + 1;
    const std::string line = text.substr(pos, end - pos);
    pos = end;
    ++line_no;
    const std::string begin = marker_node(line, "BEGIN");
    const std::string finish = marker_node(line, "END");
    if (!begin.empty()) {
      if (!open.empty()) {
        throw fail(line_no, "BEGIN params " + begin + " inside the block of " + open + " (opened on line " +
                                std::to_string(open_line) + ")");
      }
      const NodeSchema* schema = nullptr;
      try {
        schema = &node_schema(begin);
      } catch (const UnknownNode& e) {
        throw fail(line_no, e.what());
      }
      if (!seen.insert(begin).second) throw fail(line_no, "a second parameter block of " + begin);
      result.text += line;
      // A blank line ends the table before the END comment in every markdown renderer.
      result.text += schema_markdown(*schema) + "\n";
      result.nodes.push_back(begin);
      open = begin;
      open_line = line_no;
    } else if (!finish.empty()) {
      if (open.empty()) throw fail(line_no, "END params " + finish + " without its BEGIN");
      if (finish != open) {
        throw fail(line_no, "END params " + finish + " closes the block of " + open + " (opened on line " +
                                std::to_string(open_line) + ")");
      }
      result.text += line;
      open.clear();
    } else if (open.empty()) {
      result.text += line;  // outside a block: kept; inside: replaced by the table
    }
  }
  if (!open.empty()) {
    throw fail(open_line, "BEGIN params " + open + " without its END (<!-- END params " + open + " -->)");
  }
  return result;
}

std::vector<std::filesystem::path> package_documents(const std::string& src_dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(src_dir)) {
    if (!entry.is_directory()) continue;
    const fs::path readme = entry.path() / "README.md";
    if (fs::is_regular_file(readme)) out.push_back(readme);
    const fs::path docs = entry.path() / "docs";
    if (!fs::is_directory(docs)) continue;
    for (const auto& doc : fs::directory_iterator(docs)) {
      if (doc.is_regular_file() && doc.path().extension() == ".md") out.push_back(doc.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> write_param_tables(const std::string& src_dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> readmes = package_documents(src_dir);
  std::vector<std::string> lines;
  for (const auto& readme : readmes) {
    std::ifstream in(readme, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) throw ReadmeError(readme.string() + ": cannot read");
    const ReadmeTables tables = regenerate_param_tables(text.str(), readme.string());
    if (tables.nodes.empty()) continue;
    std::string line = readme.string() + ":";
    for (const auto& n : tables.nodes) line += " " + n;
    if (tables.text != text.str()) {
      std::ofstream out(readme, std::ios::binary | std::ios::trunc);
      out << tables.text;
      if (!out.flush()) throw ReadmeError(readme.string() + ": cannot write");
      line += " (updated)";
    } else {
      line += " (up to date)";
    }
    lines.push_back(line);
  }
  return lines;
}

ShippedConfig shipped_config(const NodeSchema& node, const std::string& config_dir) {
  const ParamMap defaults = node.parameters();
  ShippedConfig out;
  std::map<std::string, std::vector<std::string>> missing_for;  // key -> instances no file sets it for
  for (const auto& instance : node.instances) {
    std::map<std::string, std::vector<std::string>> set_by;  // key -> files that set it
    for (const auto& file : node.config_files) {
      const std::string path = (std::filesystem::path(config_dir) / file).string();
      ParamMap other = defaults;
      for (const auto& [key, value] : defaults.values()) other.set(key, std::visit(Perturb{}, value));
      const ParamMap loaded = tactile_common::load_node_parameters(path, instance, defaults);
      const ParamMap loaded_other = tactile_common::load_node_parameters(path, instance, other);
      for (const auto& [key, value] : loaded.values()) {
        if (!(loaded_other.values().at(key) == value)) continue;  // the file does not set it
        set_by[key].push_back(file);
        if (!(value == defaults.values().at(key))) {
          out.differing.push_back({instance, key, file, value, defaults.values().at(key)});
        }
      }
    }
    for (const auto& [key, value] : defaults.values()) {
      const auto it = set_by.find(key);
      if (it == set_by.end()) {
        missing_for[key].push_back(instance);
      } else if (it->second.size() > 1) {
        std::string files;
        for (const auto& f : it->second) files += (files.empty() ? "" : ", ") + f;
        out.twice.push_back(key + ": " + files + " (" + instance + ")");
      }
    }
  }
  for (const auto& [key, instances] : missing_for) {
    if (instances.size() == node.instances.size()) {
      out.missing.push_back(key);
    } else {
      for (const auto& i : instances) out.missing.push_back(key + " (" + i + ")");
    }
  }
  return out;
}

}  // namespace tactile_cli
