#include "xplorer_nodes.hpp"

#include "tactile_cli/host_ports.hpp"

namespace tactile_cli {

std::shared_ptr<xplorer_force_est::XplorerForceEstLogic> add_xplorer_force_est(
    Host& host, const tactile_common::ParamMap& over) {
  using Logic = xplorer_force_est::XplorerForceEstLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    NodeReport r{std::string("/") + Logic::kNodeName,
                 {{"received_arm", s.received_arm},
                  {"received_imu", s.received_imu},
                  {"received_thrust", s.received_thrust},
                  {"published", s.published},
                  {"published_degraded", s.published_degraded},
                  {"dropped_nonfinite_imu", s.dropped_nonfinite_imu},
                  {"dropped_nonfinite_thrust", s.dropped_nonfinite_thrust},
                  {"dropped_out_of_order", s.dropped_out_of_order},
                  {"arm_bad_id", s.arm_bad_id},
                  {"arm_from_orientation", s.arm_from_orientation},
                  {"arm_out_of_range", s.arm_out_of_range},
                  {"resets_on_gap", s.resets_on_gap},
                  {"dropped_imu_stale", s.dropped_imu_stale}}};
    for (size_t i = 0; i < 4; ++i) r.counters.emplace_back("arm" + std::to_string(i) + "_missing", s.arm_missing[i]);
    return r;
  });
  return logic;
}

std::shared_ptr<tactile_fsm::XplorerFsmLogic> add_xplorer_fsm(Host& host, const tactile_common::ParamMap& over) {
  using Logic = tactile_fsm::XplorerFsmLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"ticks", s.ticks},
                       {"ticks_stale", s.ticks_stale},
                       {"failsafe_hovers", s.failsafe_hovers},
                       {"failsafe_landings", s.failsafe_landings},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_wrong_frame", s.dropped_wrong_frame},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"state_messages", s.state_messages}}};
  });
  return logic;
}

std::shared_ptr<mapping_pcl::XplorerMapLogic> add_xplorer_mapping(Host& host, const tactile_common::ParamMap& over) {
  using Logic = mapping_pcl::XplorerMapLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    const auto& m = l->mapper().stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"received_wrench", s.received_wrench},
                       {"received_odometry", s.received_odometry},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_wrong_frame", s.dropped_wrong_frame},
                       {"ticks_without_input", s.ticks_without_input},
                       {"published", s.published},
                       {"ticks_gated", s.ticks_gated},
                       {"received_arm_imu", s.received_arm_imu},
                       {"dropped_arm_samples", s.dropped_arm_samples},
                       {"slabs", m.slabs},
                       {"offset_from_arms", m.offset_from_arms},
                       {"corner_slabs", m.corner_slabs}}};
  });
  return logic;
}

}  // namespace tactile_cli
