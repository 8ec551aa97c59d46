#include "tactile_cli/host_nodes.hpp"

#include <utility>

#include "tactile_cli/host_ports.hpp"
#include "tactile_common/event_tick.hpp"
#include "tactile_common/time.hpp"

namespace tactile_cli {

std::shared_ptr<whisker_driver::WhiskerDriverLogic> add_whisker_driver(
    Host& host, const std::string& ns, const tactile_common::ParamMap& over) {
  using Logic = whisker_driver::WhiskerDriverLogic;
  auto logic = add_logic<Logic>(host, ns, over);
  wire(host, ns, *logic);
  Logic* l = logic.get();
  host.add_reporter([l, name = resolve_topic(ns, Logic::kNodeName)] {
    const auto s = l->stats();
    return NodeReport{name,
                      {{"published", s.published},
                       {"source_errors", s.source_errors},
                       {"sequence_gaps", s.sequence_gaps},
                       {"stamps_repaired_ahead", s.stamps_repaired_ahead},
                       {"stamps_repaired_behind", s.stamps_repaired_behind},
                       {"clock_steps", s.clock_steps},
                       {"dropped_duplicate", s.dropped_duplicate},
                       {"dropped_late", s.dropped_late},
                       {"sequence_restarts", s.sequence_restarts},
                       {"gaps", s.gaps},
                       {"samples_missing", s.samples_missing},
                       {"parse_lines", s.parse.lines},
                       {"parse_frames", s.parse.frames},
                       {"parse_dropped_lines", s.parse.dropped_lines()},
                       {"parse_dropped_frames", s.parse.dropped_frames()}}};
  });
  return logic;
}

std::shared_ptr<tdorc_filter::TdorcFilterLogic> add_tdorc_filter(
    Host& host, const std::string& ns, const tactile_common::ParamMap& over) {
  using Logic = tdorc_filter::TdorcFilterLogic;
  auto logic = add_logic<Logic>(host, ns, over);
  wire(host, ns, *logic);
  Logic* l = logic.get();
  host.add_reporter([l, name = resolve_topic(ns, Logic::kNodeName)] {
    const auto& s = l->stats();
    return NodeReport{name,
                      {{"received", s.received},
                       {"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_wrong_whisker", s.dropped_wrong_whisker},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"dropped_duplicate", s.dropped_duplicate},
                       {"dropped_late", s.dropped_late},
                       {"stamps_repaired_ahead", s.stamps_repaired_ahead},
                       {"stamps_repaired_behind", s.stamps_repaired_behind},
                       {"clock_steps", s.clock_steps},
                       {"sequence_restarts", s.sequence_restarts},
                       {"gaps_bridged", s.gaps_bridged},
                       {"samples_missing", s.samples_missing},
                       {"resets_on_gap", s.resets_on_gap},
                       {"sequence_gaps", s.sequence_gaps}}};
  });
  return logic;
}

std::shared_ptr<tactile_depth::TactileDepthLogic> add_tactile_depth(Host& host,
                                                                   const tactile_common::ParamMap& over,
                                                                   const std::string& output_topic) {
  using Logic = tactile_depth::TactileDepthLogic;
  auto logic = add_logic<Logic>(host, "", over);
  const std::string own = resolve_topic("", Logic::kOutputTopic);
  const std::string out = resolve_topic("", output_topic);
  wire(host, "", *logic, out == own ? HostPorts::Remap{} : HostPorts::Remap{{own, out}});
  Logic* l = logic.get();
  host.add_reporter([l, output_topic] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName + (output_topic == Logic::kOutputTopic ? "" : output_topic),
                      {{"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_wrong_whisker", s.dropped_wrong_whisker},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"dropped_unpaired", s.dropped_unpaired},
                       {"dropped_stale", s.dropped_stale},
                       {"ticks_without_odometry", s.ticks_without_odometry},
                       {"prediction_skipped", s.prediction_skipped}}};
  });
  return logic;
}

WhiskerFrontEnd add_whisker_front_end(Host& host, const tactile_common::ParamMap& tdorc_overrides,
                                      const std::optional<tactile_common::ParamMap>& depth_overrides) {
  WhiskerFrontEnd f;
  f.left = add_tdorc_filter(host, "whisker/left", tdorc_overrides);
  f.right = add_tdorc_filter(host, "whisker/right", tdorc_overrides);
  if (depth_overrides) f.depth = add_tactile_depth(host, *depth_overrides);
  return f;
}

std::shared_ptr<tactile_fsm::WhiskerFsmLogic> add_whisker_fsm(Host& host, const tactile_common::ParamMap& over,
                                                               std::function<int64_t()> arrival_clock) {
  using Logic = tactile_fsm::WhiskerFsmLogic;
  auto logic = add_logic<Logic>(host, "", over);
  Logic* l = logic.get();
  Logic::Stepping stepping;
  // Event driven only with a real-time clock (see the header).
  auto tick = arrival_clock ? std::make_shared<tactile_common::EventTick>(Logic::kTimerPeriodNs) : nullptr;
  if (tick) host.keep(tick);
  stepping.tick = tick.get();
  // Steps never go back in time: a real-time host's executor may fire an overdue
  // watchdog with its due time after a depth arrival stepped the FSM later (a no-op
  // when the timer alone steps it).
  stepping.monotonic = true;
  // The arrival clock is the node's clock: a depth's receive time (the event step's
  // time) and the stamps of what it publishes.
  HostPorts ports(host, "", {}, std::move(arrival_clock));
  Logic::wire(ports, *l, stepping);
  host.add_reporter([l, tick] {
    const auto& s = l->stats();
    NodeReport r{std::string("/") + Logic::kNodeName,
                 {{"ticks", s.ticks},
                  {"dropped_nonfinite", s.dropped_nonfinite},
                  {"dropped_out_of_order", s.dropped_out_of_order},
                  {"dropped_wrong_whisker", s.dropped_wrong_whisker}}};
    if (tick) {  // event driven: why each tick ran
      r.counters.emplace_back("ticks_on_depth", tick->stats().event_steps);
      r.counters.emplace_back("ticks_on_watchdog", tick->stats().watchdog_steps);
      r.counters.emplace_back("depth_held_back", tick->stats().skipped_events);
    }
    return r;
  });
  return logic;
}

std::shared_ptr<gpis_explorer::GpisExplorerLogic> add_gpis_explorer(Host& host, const tactile_common::ParamMap& over) {
  using Logic = gpis_explorer::GpisExplorerLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"ticks", s.ticks},
                       {"stale_ticks", s.stale_ticks},
                       {"maps_published", s.maps_published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_out_of_order", s.dropped_out_of_order}}};
  });
  return logic;
}

std::shared_ptr<whisker_localization::WhiskerLocalizationLogic> add_whisker_localization(
    Host& host, const tactile_common::ParamMap& over) {
  using Logic = whisker_localization::WhiskerLocalizationLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"moments_received", s.moments_received},
                       {"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"dropped_no_odom", s.dropped_no_odom},
                       {"no_contact", s.no_contact},
                       {"resets", s.resets}}};
  });
  return logic;
}

namespace {
template <class T>
void publish_all(Host& host, std::vector<tactile_sim::Published<T>>& msgs, int64_t now_ns) {
  for (const auto& m : msgs) host.bus().publish(m.topic, m.msg, now_ns);
}
}  // namespace

void add_tactile_sim(Host& host, std::shared_ptr<tactile_sim::SimLogic> sim) {
  using Sim = tactile_sim::SimLogic;
  Host* h = &host;
  Sim* s = sim.get();
  // The inputs through the component's wire; the world's steps and outputs are the host's own.
  HostPorts ports(host, "");
  Sim::wire_setpoints(ports, *s, [](const auto& /*stamp*/) {});
  auto out = std::make_shared<Sim::Outputs>();
  host.executor().add_timer(
      sim->period_ns(),
      [h, s, out](int64_t now_ns) {
        out->clear();
        s->step(now_ns, *out);
        publish_all(*h, out->pressure, now_ns);
        publish_all(*h, out->whisker_truth, now_ns);
        publish_all(*h, out->odometry, now_ns);
        publish_all(*h, out->imu, now_ns);
        publish_all(*h, out->range, now_ns);
        publish_all(*h, out->flow, now_ns);
        publish_all(*h, out->arm_imu, now_ns);
        publish_all(*h, out->thrust, now_ns);
        publish_all(*h, out->wrench, now_ns);
        publish_all(*h, out->wall, now_ns);
        publish_all(*h, out->collisions, now_ns);
        if (s->finished(now_ns)) h->executor().stop();
      },
      host.executor().now_ns());
  host.add_reporter([s] {
    NodeReport r{std::string("/") + Sim::kNodeName, {{"dropped_setpoints", s->dropped_setpoints()}}};
    for (const auto& [type, n] : s->fault_counts()) r.counters.emplace_back("faults_" + type, n);
    return r;
  });
  host.keep(out);
  host.keep(sim);
}

void add_scenario_pilot(Host& host, std::shared_ptr<tactile_sim::ScriptedPilotLogic> pilot) {
  using Pilot = tactile_sim::ScriptedPilotLogic;
  Host* h = &host;
  Pilot* p = pilot.get();
  for (const char* side : {"/whisker/left/signal", "/whisker/right/signal"}) {
    host.bus().subscribe<tactile_msgs::msg::WhiskerSignal>(
        side, [p](const tactile_msgs::msg::WhiskerSignal& m) { p->on_whisker_signal(m); });
  }
  host.bus().subscribe<tactile_msgs::msg::CollisionEvent>(
      Pilot::kCollisionTopic, [p](const tactile_msgs::msg::CollisionEvent& m) { p->on_collision(m); });
  host.bus().subscribe<nav_msgs::msg::Odometry>(Pilot::kOdometryTopic,
                                                [p](const nav_msgs::msg::Odometry& m) { p->on_odometry(m); });
  host.executor().add_timer(
      tactile_common::from_seconds(1.0 / Pilot::kRateHz),
      [h, p](int64_t now_ns) {
        const auto out = p->on_timer(now_ns);
        if (out.hover) h->bus().publish(Pilot::kHoverTopic, *out.hover, now_ns);
        if (out.position) h->bus().publish(Pilot::kPositionTopic, *out.position, now_ns);
      },
      host.executor().now_ns());
  host.add_reporter([p] {
    const auto& s = p->stats();
    return NodeReport{std::string("/") + Pilot::kNodeName,
                      {{"steps_completed", s.steps_completed},
                       {"steps_timed_out", s.steps_timed_out},
                       {"finished", s.finished ? 1u : 0u}}};
  });
  host.keep(pilot);
}

std::shared_ptr<wall_effect_ekf::WallEffectEkfLogic> add_wall_effect_ekf(Host& host, const tactile_common::ParamMap& over) {
  using Logic = wall_effect_ekf::WallEffectEkfLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_bad_thrust", s.dropped_bad_thrust},
                       {"dropped_low_quality", s.dropped_low_quality},
                       {"dropped_out_of_range", s.dropped_out_of_range},
                       {"ticks_without_input", s.ticks_without_input},
                       {"ticks_without_imu", s.ticks_without_imu},
                       {"flow_gated", l->ekf().stats().flow_gated},
                       {"tof_gated", l->ekf().stats().tof_gated},
                       {"reacquisitions", l->ekf().stats().reacquisitions}}};
  });
  return logic;
}

std::shared_ptr<wall_effect_ekf::IndiControlLogic> add_indi_controller(Host& host, const tactile_common::ParamMap& over) {
  using Logic = wall_effect_ekf::IndiControlLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"published", s.published},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"dropped_out_of_order", s.dropped_out_of_order},
                       {"ticks_without_input", s.ticks_without_input},
                       {"ticks_nominal", s.ticks_nominal},
                       {"ticks_odometry_lost", s.ticks_odometry_lost},
                       {"ticks_motors_stopped", s.ticks_motors_stopped},
                       {"odometry_ignored", s.odometry_ignored},
                       {"floor_probes", s.floor_probes},
                       {"floor_probes_aborted", s.floor_probes_aborted},
                       {"accel_bias_updates", s.accel_bias_updates},
                       {"accel_bias_gated", s.accel_bias_gated}}};
  });
  return logic;
}

std::shared_ptr<wall_effect_ekf::WallTrajectoryLogic> add_wall_trajectory(Host& host,
                                                                          const tactile_common::ParamMap& over) {
  using Logic = wall_effect_ekf::WallTrajectoryLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  return logic;
}

std::shared_ptr<tactile_fsm::WallEffectNavLogic> add_wall_effect_nav(Host& host, const tactile_common::ParamMap& over) {
  using Logic = tactile_fsm::WallEffectNavLogic;
  auto logic = add_logic<Logic>(host, "", over);
  wire(host, "", *logic);
  Logic* l = logic.get();
  host.add_reporter([l] {
    const auto& s = l->stats();
    return NodeReport{std::string("/") + Logic::kNodeName,
                      {{"ticks", s.ticks},
                       {"dropped_nonfinite", s.dropped_nonfinite},
                       {"ticks_without_odometry", s.ticks_without_odometry},
                       {"ticks_wall_stale", s.ticks_wall_stale}}};
  });
  return logic;
}

}  // namespace tactile_cli
