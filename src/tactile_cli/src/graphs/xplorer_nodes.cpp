#include "xplorer_nodes.hpp"

namespace tactile_cli {

std::shared_ptr<xplorer_force_est::XplorerForceEstLogic> add_xplorer_force_est(
    Host& host, const tactile_common::ParamMap& over) {
  using Logic = xplorer_force_est::XplorerForceEstLogic;
  auto logic = add_logic<Logic>(host, "", over);
  Host* h = &host;
  Logic* l = logic.get();
  host.bus().subscribe<tactile_msgs::msg::ArmImuArray>(Logic::kArmImuTopic, [h, l](const tactile_msgs::msg::ArmImuArray& m) {
    const auto out = l->on_arm_imu(m);
    if (out.world) h->bus().publish(Logic::kWrenchWorldTopic, *out.world, h->executor().now_ns());
    if (out.body) h->bus().publish(Logic::kWrenchBodyTopic, *out.body, h->executor().now_ns());
  });
  host.bus().subscribe<sensor_msgs::msg::Imu>(Logic::kImuTopic, [l](const sensor_msgs::msg::Imu& m) { l->on_imu(m); });
  host.bus().subscribe<tactile_msgs::msg::ThrustCommand>(
      Logic::kThrustTopic, [l](const tactile_msgs::msg::ThrustCommand& m) { l->on_thrust(m); });
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
  Host* h = &host;
  Logic* l = logic.get();
  host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
      Logic::kWrenchTopic, [l](const geometry_msgs::msg::WrenchStamped& m) { l->on_wrench(m); });
  host.bus().subscribe<nav_msgs::msg::Odometry>(Logic::kOdomTopic, [l](const nav_msgs::msg::Odometry& m) { l->on_odometry(m); });
  host.executor().add_timer(
      Logic::kTimerPeriodNs,
      [h, l](int64_t now_ns) {
        const auto out = l->on_timer(now_ns);
        if (out.setpoint) h->bus().publish(Logic::kSetpointTopic, *out.setpoint, now_ns);
        if (out.state) h->bus().publish(Logic::kStateTopic, *out.state, now_ns);
      },
      host.executor().now_ns());
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
  Host* h = &host;
  Logic* l = logic.get();
  host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
      Logic::kWrenchBodyTopic, [l](const geometry_msgs::msg::WrenchStamped& m) { l->on_wrench_body(m); });
  host.bus().subscribe<nav_msgs::msg::Odometry>(Logic::kOdometryTopic,
                                                [l](const nav_msgs::msg::Odometry& m) { l->on_odometry(m); });
  host.bus().subscribe<tactile_msgs::msg::FsmState>(Logic::kFsmStateTopic,
                                                    [l](const tactile_msgs::msg::FsmState& m) { l->on_fsm_state(m); });
  host.bus().subscribe<tactile_msgs::msg::ArmImuArray>(Logic::kArmImuTopic,
                                                       [l](const tactile_msgs::msg::ArmImuArray& m) { l->on_arm_imu(m); });
  host.executor().add_timer(
      logic->period_ns(),
      [h, l](int64_t now_ns) {
        if (auto cloud = l->on_timer(now_ns)) h->bus().publish(Logic::kCloudTopic, *cloud, now_ns);
      },
      host.executor().now_ns());
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
