// Test component (tactile_ros_tests only): loaded into a launch graph's component
// container by test_humble_intra_process.py, it finds which publishers of that process
// rclcpp delivers intra-process and fails to load if one of them is not volatile.
//
// Why: ROS 2 Humble's rclcpp throws std::invalid_argument("intraprocess communication
// allowed only with volatile durability") when a publisher or subscription with any other
// durability is created with intra-process communication on (rclcpp 16.x publisher.hpp,
// subscription.hpp), so a graph composed with use_intra_process_comms: true cannot start
// there. Jazzy and Kilted accept transient local under intra-process (rclcpp PR 2303), so
// the graphs start on the distros we test and only this check sees the problem.
//
// How: every publisher on the graph (get_publishers_info_by_topic: topic, node, QoS and
// the endpoint's GID) is looked up in this process's IntraProcessManager, which knows the
// GID of every publisher that rclcpp registered for intra-process delivery in this context
// (the container's: components share it). The result is the read-only string-array
// parameter `report`, one line per publisher "topic|/ns/node|durability|intra_process"
// (durability: volatile, transient_local, ...; intra_process 1 or 0), so the test can also
// check the lookup itself (a volatile publisher of the graph must read 1). A violation
// throws from the constructor: the container's LoadNode answers success false with the
// message, which names each topic and node.
//
// Subscriptions are not covered (the graph gives no handle to tell an intra-process
// subscription): the source check of the same test refuses transient local outside
// tactile_common/ros_qos.hpp instead.
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rclcpp/experimental/intra_process_manager.hpp"
#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "rmw/rmw.h"

namespace tactile_ros_tests {

namespace {

std::string durability_name(rclcpp::DurabilityPolicy d) {
  switch (d) {
    case rclcpp::DurabilityPolicy::Volatile: return "volatile";
    case rclcpp::DurabilityPolicy::TransientLocal: return "transient_local";
    case rclcpp::DurabilityPolicy::SystemDefault: return "system_default";
    default: return "other";
  }
}

}  // namespace

class IntraProcessQosProbe : public rclcpp::Node {
 public:
  explicit IntraProcessQosProbe(const rclcpp::NodeOptions& options) : Node("intra_process_qos_probe", options) {
    auto ipm = get_node_base_interface()->get_context()->get_sub_context<rclcpp::experimental::IntraProcessManager>();
    std::vector<std::string> report;
    std::vector<std::string> violations;
    for (const auto& [topic, types] : get_topic_names_and_types()) {
      (void)types;
      for (const auto& info : get_publishers_info_by_topic(topic)) {
        rmw_gid_t gid{};
        gid.implementation_identifier = rmw_get_implementation_identifier();
        std::copy(info.endpoint_gid().begin(), info.endpoint_gid().end(), gid.data);
        const bool intra = ipm->matches_any_publishers(&gid);
        const auto durability = info.qos_profile().durability();
        std::string node = info.node_namespace();
        if (node.empty() || node.back() != '/') {node += '/';}
        node += info.node_name();
        report.push_back(topic + "|" + node + "|" + durability_name(durability) + "|" + (intra ? "1" : "0"));
        if (intra && durability != rclcpp::DurabilityPolicy::Volatile) {
          violations.push_back(topic + " (" + node + ", " + durability_name(durability) + ")");
        }
      }
    }
    std::sort(report.begin(), report.end());
    rcl_interfaces::msg::ParameterDescriptor descriptor;
    descriptor.read_only = true;
    descriptor.description = "topic|node|durability|intra_process of every publisher on the graph";
    declare_parameter("report", report, descriptor);
    if (!violations.empty()) {
      std::string text = "intra_process_qos_probe: non-volatile publishers under intra-process communication "
                         "(ROS 2 Humble's rclcpp refuses them: \"intraprocess communication allowed only with "
                         "volatile durability\"; create them with tactile_common::latched_publisher):";
      for (const auto& v : violations) {text += " " + v + ";";}
      throw std::runtime_error(text);
    }
    RCLCPP_INFO(get_logger(), "intra_process_qos_probe: %zu publishers on the graph, none non-volatile under "
                "intra-process", report.size());
  }
};

}  // namespace tactile_ros_tests

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_ros_tests::IntraProcessQosProbe)
