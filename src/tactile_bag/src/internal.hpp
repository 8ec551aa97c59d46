// Internal helpers shared by the reader and the writer.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "tactile_bag/bag.hpp"

namespace tactile_bag {

/// QoS profiles as a YAML sequence node in the spelling of `metadata_version`.
YAML::Node qos_node(const std::vector<QosProfile>& profiles, int metadata_version);

}  // namespace tactile_bag
