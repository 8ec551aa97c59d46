// offered_qos_profiles: parsing both rosbag2 spellings and writing either.
//
// Metadata versions 4..8 store the profiles as a YAML *string* whose policies are
// the integer values of the rmw enums; version 9 (Jazzy) stores a YAML sequence with
// lower-case policy names. The enum values below are those of rmw/types.h.
#include <algorithm>
#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "tactile_bag/bag.hpp"
#include "internal.hpp"

namespace tactile_bag {
namespace {

using Table = std::vector<std::pair<int, const char*>>;

const Table kHistory{{0, "system_default"}, {1, "keep_last"}, {2, "keep_all"}, {3, "unknown"}};
const Table kReliability{{0, "system_default"}, {1, "reliable"}, {2, "best_effort"},
                         {3, "unknown"}, {4, "best_available"}};
const Table kDurability{{0, "system_default"}, {1, "transient_local"}, {2, "volatile"},
                        {3, "unknown"}, {4, "best_available"}};
const Table kLiveliness{{0, "system_default"}, {1, "automatic"}, {2, "manual_by_node"},
                        {3, "manual_by_topic"}, {4, "unknown"}, {5, "best_available"}};

std::string policy_from_node(const YAML::Node& node, const Table& table, const std::string& where) {
  if (!node || !node.IsScalar()) {
    throw BagError(where + ": missing or not a scalar");
  }
  const std::string s = node.Scalar();
  bool numeric = !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) {
    return std::isdigit(c) != 0;
  });
  if (numeric) {
    int v = std::stoi(s);
    for (const auto& [k, name] : table) {
      if (k == v) return name;
    }
    throw BagError(where + ": unknown enum value " + s);
  }
  std::string lower;
  for (unsigned char c : s) lower.push_back(static_cast<char>(std::tolower(c)));
  for (const auto& [k, name] : table) {
    if (lower == name) return name;
  }
  throw BagError(where + ": unknown policy '" + s + "'");
}

int policy_to_int(const std::string& name, const Table& table) {
  for (const auto& [k, n] : table) {
    if (name == n) return k;
  }
  throw BagError("offered_qos_profiles: unknown policy '" + name + "'");
}

QosProfile::Time time_from_node(const YAML::Node& node, const std::string& where) {
  if (!node || !node.IsMap()) throw BagError(where + ": missing or not a map {sec, nsec}");
  QosProfile::Time t;
  try {
    t.sec = node["sec"].as<int64_t>();
    t.nsec = node["nsec"].as<int64_t>();
  } catch (const YAML::Exception&) {
    throw BagError(where + ": needs integer 'sec' and 'nsec'");
  }
  return t;
}

YAML::Node time_node(const QosProfile::Time& t) {
  YAML::Node n;
  n["sec"] = t.sec;
  n["nsec"] = t.nsec;
  return n;
}

}  // namespace

std::vector<QosProfile> parse_qos_profiles(const std::string& yaml_text, const std::string& context) {
  std::vector<QosProfile> out;
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw BagError(context + ": not valid YAML: " + e.what());
  }
  if (!root || root.IsNull()) return out;
  if (!root.IsSequence()) throw BagError(context + ": expected a sequence of QoS profiles");
  for (size_t i = 0; i < root.size(); ++i) {
    const YAML::Node item = root[i];
    const std::string w = context + "[" + std::to_string(i) + "].";
    if (!item.IsMap()) throw BagError(context + "[" + std::to_string(i) + "]: expected a map");
    QosProfile p;
    p.history = policy_from_node(item["history"], kHistory, w + "history");
    try {
      p.depth = item["depth"].as<int64_t>();
    } catch (const YAML::Exception&) {
      throw BagError(w + "depth: missing or not an integer");
    }
    p.reliability = policy_from_node(item["reliability"], kReliability, w + "reliability");
    p.durability = policy_from_node(item["durability"], kDurability, w + "durability");
    p.deadline = time_from_node(item["deadline"], w + "deadline");
    p.lifespan = time_from_node(item["lifespan"], w + "lifespan");
    p.liveliness = policy_from_node(item["liveliness"], kLiveliness, w + "liveliness");
    p.liveliness_lease_duration =
        time_from_node(item["liveliness_lease_duration"], w + "liveliness_lease_duration");
    try {
      p.avoid_ros_namespace_conventions = item["avoid_ros_namespace_conventions"].as<bool>();
    } catch (const YAML::Exception&) {
      throw BagError(w + "avoid_ros_namespace_conventions: missing or not a bool");
    }
    out.push_back(p);
  }
  return out;
}

YAML::Node qos_node(const std::vector<QosProfile>& profiles, int metadata_version) {
  YAML::Node seq(YAML::NodeType::Sequence);
  const bool names = metadata_version >= 9;
  for (const auto& p : profiles) {
    YAML::Node n;
    if (names) {
      n["history"] = p.history;
    } else {
      n["history"] = policy_to_int(p.history, kHistory);
    }
    n["depth"] = p.depth;
    if (names) {
      n["reliability"] = p.reliability;
      n["durability"] = p.durability;
    } else {
      n["reliability"] = policy_to_int(p.reliability, kReliability);
      n["durability"] = policy_to_int(p.durability, kDurability);
    }
    n["deadline"] = time_node(p.deadline);
    n["lifespan"] = time_node(p.lifespan);
    if (names) {
      n["liveliness"] = p.liveliness;
    } else {
      n["liveliness"] = policy_to_int(p.liveliness, kLiveliness);
    }
    n["liveliness_lease_duration"] = time_node(p.liveliness_lease_duration);
    n["avoid_ros_namespace_conventions"] = p.avoid_ros_namespace_conventions;
    seq.push_back(n);
  }
  return seq;
}

std::string dump_qos_profiles(const std::vector<QosProfile>& profiles, int metadata_version) {
  if (profiles.empty()) return "";
  YAML::Emitter e;
  e << qos_node(profiles, metadata_version);
  return e.c_str();
}

std::string default_qos_profiles(int metadata_version) {
  return dump_qos_profiles({QosProfile{}}, metadata_version);
}

}  // namespace tactile_bag
