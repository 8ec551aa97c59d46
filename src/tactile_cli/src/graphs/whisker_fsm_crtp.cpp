// Graph `whisker_fsm_crtp`: the whisker_fsm pipeline (TDORC x2 ->
// tactile_depth -> whisker FSM) flying the simulator through crazyflie_bridge
// and CRTP, in lockstep on the simulated clock. The simulator's whisker
// barometers and state estimate become log variables of a simulated Crazyflie
// firmware (crazyflie_bridge::SimulatedCrazyflieFirmware); its two 50 Hz log
// blocks cross a loopback wire (bytes, seeded loss) to the bridge, whose
// messages feed the pipeline on a host of its own; the FSM's setpoints go back
// as generic-commander packets and the firmware's commander (with its
// watchdog) drives the simulator. Reproducible for a seed; compared with
// whisker_fsm it adds the link: encoding, loss, the bridge's clamping and
// stale -> hover -> land -> stop chain. No operator: the bridge runs with
// autostart (forwards the FSM from its first fresh setpoint).
//
// node_parameters: tdorc_filter, tactile_depth, whisker_fsm, crazyflie_bridge
// (config/crazyflie_bridge.yaml keys), crtp_link {loss: 0..1, seed: N}.
// Metrics (key "fsm"): the whisker_fsm metrics plus link_packets_sent,
// link_packets_lost and the bridge's counters.
#include "graphs.hpp"

#include <limits>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/loopback_link.hpp"
#include "crazyflie_bridge/sim_firmware.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/whisker_eval.hpp"

namespace tactile_cli::graphs {

namespace {

using crazyflie_bridge::CrazyflieBridgeLogic;

constexpr int64_t kFirmwareTickNs = 1'000'000;  // firmware log scheduler: 1 ms

class WhiskerFsmCrtpGraph : public SimGraph {
 public:
  explicit WhiskerFsmCrtpGraph(GraphContext& ctx) : inner_(ctx.host.config_dir()) {
    // Link settings.
    const auto link_over = ctx.overrides("crtp_link");
    for (const auto& [k, v] : link_over.values()) {
      if (k != "loss" && k != "seed") {
        throw std::runtime_error(ctx.scenario.source + ": node_parameters.crtp_link." + k + ": unknown key (loss, seed)");
      }
    }
    const double loss = link_over.has("loss") ? link_over.get_double("loss") : 0.0;
    if (!(loss >= 0.0 && loss < 1.0)) {
      throw std::runtime_error(ctx.scenario.source + ": node_parameters.crtp_link.loss: must be in [0, 1)");
    }
    // A seed is any 64-bit value, used as its uint64 bit pattern.
    const uint64_t seed = link_over.has("seed") ? static_cast<uint64_t>(link_over.get_int64("seed", std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max())) : ctx.seed;

    // Firmware side, fed by the simulator's topics on the outer bus.
    Host& outer = ctx.host;
    outer_ = &outer;
    crazyflie_bridge::SimulatedCrazyflieFirmware::Options fo;
    fo.loss_rate = loss;
    fo.status_log = false;  // the TOC of the reference runs (see the bridge below)
    fw_ = std::make_unique<crazyflie_bridge::SimulatedCrazyflieFirmware>(fo);
    for (const char* t : {"/whisker/left/pressure", "/whisker/right/pressure"}) {
      outer.bus().subscribe<tactile_msgs::msg::WhiskerPressure>(t, [this](const auto& m) { fw_->on_pressure(m); });
    }
    outer.bus().subscribe<nav_msgs::msg::Odometry>("/odom", [this](const auto& m) { fw_->on_estimate(m); });
    outer.bus().subscribe<nav_msgs::msg::Odometry>("/ground_truth/odom", [this](const auto& m) { fw_->on_truth(m); });
    auto link = std::make_unique<crazyflie_bridge::LoopbackLink>(fw_->emulator(), loss, seed);
    link_ = link.get();

    // Pipeline on its own host (same nodes and topics as whisker_fsm).
    add_whisker_front_end(inner_, ctx.overrides("tdorc_filter"), ctx.overrides("tactile_depth"));
    tactile_common::ParamMap extra;
    if (auto t = ctx.target()) {
      extra.set("target_x", t->x());
      extra.set("target_y", t->y());
    }
    fsm_ = add_whisker_fsm(inner_, ctx.overrides("whisker_fsm", extra));
    const auto& fp = fsm_->params().fsm;
    eval_ = std::make_unique<WallFollowingEvaluation>(inner_, *ctx.whisker_truth, fp.t_min, fp.t_max, fp.whisker_spacing);

    // The bridge (connects now, at simulated time 0). The graph flies without
    // an operator: autostart forwards the FSM as soon as its setpoints and the
    // log are fresh; no status log block (its packets would change the seeded
    // loss pattern: same numbers run for run as before the operator surface).
    // A scenario's node_parameters.crazyflie_bridge may set either.
    auto bridge_over = ctx.overrides("crazyflie_bridge");
    if (!bridge_over.has("autostart")) bridge_over.set("autostart", true);
    if (!bridge_over.has("status_vars")) bridge_over.set("status_vars", std::vector<std::string>{});
    const auto bp = CrazyflieBridgeLogic::params_from(inner_.load_parameters(
        "", CrazyflieBridgeLogic::kNodeName, CrazyflieBridgeLogic::default_parameters(), bridge_over));
    tick_ns_ = static_cast<int64_t>(1e9 / bp.setpoint_rate_hz);
    crazyflie_bridge::ClientOptions co;
    co.retries = 50;  // lost requests are resent at once (no simulated time passes)
    runner_ = std::make_unique<crazyflie_bridge::BridgeRunner>(bp, co, std::move(link));
    inner_.bus().subscribe<tactile_msgs::msg::HoverSetpoint>(
        CrazyflieBridgeLogic::kSetpointTopic, [this](const tactile_msgs::msg::HoverSetpoint& m) {
          runner_->on_hover_setpoint(m, now_ns_);
          outer_->bus().publish("/crtp/cmd_hover", m, now_ns_);  // the pipeline's request, for the bag
        });
    sinks_.left = [this](const auto& m) { publish_both(CrazyflieBridgeLogic::kLeftPressureTopic, m); };
    sinks_.right = [this](const auto& m) { publish_both(CrazyflieBridgeLogic::kRightPressureTopic, m); };
    sinks_.odom = [this](const auto& m) { publish_both(CrazyflieBridgeLogic::kOdomTopic, m); };
    // Pipeline outputs are mirrored on the outer bus (bag, top view).
    forward<tactile_msgs::msg::WhiskerSignal>("/whisker/left/signal");
    forward<tactile_msgs::msg::WhiskerSignal>("/whisker/right/signal");
    forward<tactile_msgs::msg::TactileDepth>("/whisker/depth");
    forward<tactile_msgs::msg::FsmState>("/fsm_state");

    outer.executor().add_timer(
        kFirmwareTickNs, [this](int64_t now) { step(now); }, outer.executor().now_ns());
    outer.add_reporter([this] {
      const auto s = runner_->logic_stats();
      return NodeReport{"/crazyflie_bridge",
                        {{"log_samples", s.log_samples}, {"setpoints_in", s.setpoints_in},
                         {"setpoints_clamped", s.setpoints_clamped}, {"packets_out", s.packets_out},
                         {"stale_events", s.stale_events}, {"landings", s.landings},
                         {"dropped_nonfinite", s.dropped_nonfinite}}};
    });
  }

  nlohmann::json metrics() const override {
    nlohmann::json m = eval_->metrics();
    m["target"] = {fsm_->params().target_x, fsm_->params().target_y};
    m["reached_target"] = *reached_goal();
    const auto& ls = link_->statistics();
    const auto cs = runner_->client_stats();
    const auto bs = runner_->logic_stats();
    m["link_packets_sent"] = ls.packets_sent;
    m["link_packets_received"] = ls.packets_received;
    // Injected on the wire, both directions (exact); the bridge's own estimate
    // of the lost log packets (timestamp gaps) is link_log_missed.
    m["link_packets_lost"] = link_->dropped_uplink() + link_->dropped_downlink();
    m["link_log_missed"] = cs.log_missed;
    m["link_log_dropped"] = link_->dropped_log_packets();
    m["link_resends"] = cs.resends;
    m["bridge_mode"] = crazyflie_bridge::to_string(runner_->mode());
    m["bridge_stale_events"] = bs.stale_events;
    m["bridge_setpoints_clamped"] = bs.setpoints_clamped;
    m["firmware_setpoints"] = fw_->emulator().stats().setpoints;
    // Link truth: the bridge's per-block sequence gaps, and what the two
    // tdorc_filters made of them (missing samples bridged in the window).
    m["bridge_log_samples_missed"] = bs.log_samples_missed;
    uint64_t missing = 0, bridged = 0;
    for (const auto& r : inner_.reports()) {
      if (r.name.find("tdorc_filter") == std::string::npos) continue;
      for (const auto& [k, v] : r.counters) {
        if (k == "samples_missing") missing += v;
        if (k == "gaps_bridged") bridged += v;
      }
    }
    m["tdorc_samples_missing"] = missing;
    m["tdorc_gaps_bridged"] = bridged;
    return m;
  }

  std::optional<bool> reached_goal() const override {
    const auto state = fsm_->fsm().state();
    return state == tactile_fsm::FsmState::kLanding || state == tactile_fsm::FsmState::kLanded;
  }

  void decorate(TopView& view) const override { view.targets.emplace_back(fsm_->params().target_x, fsm_->params().target_y); }

 private:
  template <class T>
  void publish_both(const std::string& topic, const T& m) {
    inner_.bus().publish(topic, m, now_ns_);
    outer_->bus().publish("/crtp" + root_topic(topic), m, now_ns_);  // what came over the link, for the bag
  }
  template <class T>
  void forward(const std::string& topic) {
    inner_.bus().subscribe<T>(topic, [this, topic](const T& m) { outer_->bus().publish(topic, m, now_ns_); });
  }

  void step(int64_t now) {
    now_ns_ = now;
    link_->set_time_ms(static_cast<uint32_t>(now / 1'000'000));
    link_->tick();
    if (now % tick_ns_ != 0) return;
    runner_->pump(std::chrono::milliseconds(0), [this] { return now_ns_; }, sinks_);
    inner_.executor().run_until(now);
    runner_->on_timer(now);
    const auto c = fw_->command(now, tactile_common::to_seconds(tick_ns_));
    if (c.hover) outer_->bus().publish(tactile_sim::SimLogic::kHoverSetpointTopic, *c.hover, now);
    if (c.position) outer_->bus().publish(tactile_sim::SimLogic::kPositionSetpointTopic, *c.position, now);
  }

  Host inner_;
  Host* outer_ = nullptr;
  std::unique_ptr<crazyflie_bridge::SimulatedCrazyflieFirmware> fw_;
  crazyflie_bridge::LoopbackLink* link_ = nullptr;
  std::unique_ptr<crazyflie_bridge::BridgeRunner> runner_;
  crazyflie_bridge::BridgeRunner::Sinks sinks_;
  std::shared_ptr<tactile_fsm::WhiskerFsmLogic> fsm_;
  std::unique_ptr<WallFollowingEvaluation> eval_;
  int64_t now_ns_ = 0;
  int64_t tick_ns_ = 20'000'000;
};

}  // namespace

GraphInfo whisker_fsm_crtp_graph() {
  GraphInfo g;
  g.name = "whisker_fsm_crtp";
  g.description = "whisker_fsm flown through crazyflie_bridge and CRTP (simulated firmware, loopback wire, seeded loss)";
  g.vehicles = {tactile_sim::VehicleType::kWhiskerCrazyflie};
  g.nodes = {"tdorc_filter", "tactile_depth", "whisker_fsm", "crazyflie_bridge", "crtp_link"};
  g.metrics_key = "fsm";
  g.build = [](GraphContext& ctx) { return std::make_unique<WhiskerFsmCrtpGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
