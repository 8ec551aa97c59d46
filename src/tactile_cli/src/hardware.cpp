#include "tactile_cli/hardware.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <thread>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/sitl_endpoint.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/sim_graph.hpp"
#include "tactile_cli/whisker_eval.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

namespace {

using Clock = std::chrono::steady_clock;
std::atomic<bool> g_interrupted{false};
void on_sigint(int) { g_interrupted = true; }

struct SigintGuard {
  void (*old)(int);
  SigintGuard() : old(std::signal(SIGINT, on_sigint)) { g_interrupted = false; }
  ~SigintGuard() { std::signal(SIGINT, old); }
};

void write_json(const std::filesystem::path& p, const nlohmann::json& j) {
  std::ofstream out(p);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(p.string() + ": cannot write");
}

nlohmann::json node_reports(const Host& host) {
  nlohmann::json nodes = nlohmann::json::object();
  for (const auto& r : host.reports()) {
    nlohmann::json c = nlohmann::json::object();
    for (const auto& [k, v] : r.counters) c[k] = v;
    nodes[r.name] = c;
  }
  return nodes;
}

}  // namespace

nlohmann::json run_fly(const FlyOptions& o) {
  namespace fs = std::filesystem;
  using crazyflie_bridge::CrazyflieBridgeLogic;
  const fs::path dir(o.out_dir);
  fs::create_directories(dir);
  Host host(o.config_dir);

  // Pipeline nodes, with a scenario's node parameters and target when given.
  std::optional<tactile_sim::Scenario> scenario;
  const std::string scenario_path = !o.sim_scenario.empty() ? o.sim_scenario : o.scenario;
  if (!scenario_path.empty()) scenario = tactile_sim::load_scenario(scenario_path);
  // The simulated Crazyflie, in a thread of this process, on a free UDP port.
  std::unique_ptr<crazyflie_bridge::SitlEndpoint> sitl;
  std::atomic<bool> sitl_stop{false};
  std::thread sitl_thread;
  struct Joiner {
    std::atomic<bool>& stop;
    std::thread& t;
    ~Joiner() {
      stop = true;
      if (t.joinable()) t.join();
    }
  } joiner{sitl_stop, sitl_thread};
  std::string uri = o.uri;
  if (!o.sim_scenario.empty()) {
    crazyflie_bridge::SitlEndpointOptions eo;
    eo.port = 0;
    eo.loss_rate = o.sim_loss;
    eo.record_whisker_truth = true;  // the sweep's depth in band (fsm.*)
    sitl = std::make_unique<crazyflie_bridge::SitlEndpoint>(*scenario, scenario->seed, eo);
    uri = "udp://127.0.0.1:" + std::to_string(sitl->port());
    sitl_thread = std::thread([&] { sitl->run(0.0, &sitl_stop); });
  }
  auto overrides = [&](const std::string& node, tactile_common::ParamMap extra = {}) {
    if (!scenario) return extra;
    GraphContext ctx{*scenario, host, nullptr, scenario->seed, 0.0, dir, nullptr};
    return ctx.overrides(node, extra);
  };
  add_tdorc_filter(host, "whisker/left", overrides("tdorc_filter"));
  add_tdorc_filter(host, "whisker/right", overrides("tdorc_filter"));
  add_tactile_depth(host, overrides("tactile_depth"));
  tactile_common::ParamMap fsm_extra;
  if (scenario) {
    GraphContext ctx{*scenario, host, nullptr, scenario->seed, 0.0, dir, nullptr};
    if (auto t = ctx.target()) {
      fsm_extra.set("target_x", t->x());
      fsm_extra.set("target_y", t->y());
    }
  }
  auto fsm = add_whisker_fsm(host, overrides("whisker_fsm", fsm_extra));
  // Wall-following sweeps, as in the SITL evaluation; against the simulated
  // Crazyflie also the whiskers' true depth in band (filled after the run).
  WhiskerTruth truth;
  const auto& fp = fsm->params().fsm;
  const WallFollowingEvaluation sweeps(host, truth, fp.t_min, fp.t_max, fp.whisker_spacing);

  // The bridge: parameters from config/crazyflie_bridge.yaml, --uri wins.
  tactile_common::ParamMap bridge_over;
  if (!uri.empty()) bridge_over.set("uri", uri);
  const auto bridge_params = CrazyflieBridgeLogic::params_from(
      host.load_parameters("", CrazyflieBridgeLogic::kNodeName, CrazyflieBridgeLogic::default_parameters(), bridge_over));
  crazyflie_bridge::ClientOptions co;
  const fs::path cache = dir / "toc_cache";
  fs::create_directories(cache);
  co.toc_cache_dir = cache.string();
  if (sitl) co.reply_timeout = std::chrono::milliseconds(50);  // local UDP: answers within a few ms

  std::unique_ptr<BagRecorder> recorder;
  if (o.write_bag) {
    recorder = std::make_unique<BagRecorder>((dir / "bag").string());
    host.bus().add_tap(recorder.get());
  }
  SigintGuard guard;
  const auto t_connect = Clock::now();
  crazyflie_bridge::BridgeRunner runner(bridge_params, co);
  const double connect_s = std::chrono::duration<double>(Clock::now() - t_connect).count();
  if (o.progress) {
    std::printf("connected to %s in %.2f s (log TOC %zu variables%s, protocol %d)\n", bridge_params.uri.c_str(), connect_s,
                runner.client().log_toc().size(), runner.client().log_toc_from_cache() ? ", cached" : "",
                runner.client().protocol_version());
    std::fflush(stdout);
  }

  const auto t0 = Clock::now();
  auto now_ns = [&] { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count(); };
  host.bus().subscribe<tactile_msgs::msg::HoverSetpoint>(
      CrazyflieBridgeLogic::kSetpointTopic,
      [&](const tactile_msgs::msg::HoverSetpoint& m) { runner.on_hover_setpoint(m, now_ns()); });
  crazyflie_bridge::BridgeRunner::Sinks sinks;
  // Messages keep the bridge's stamps; the bag time is the host clock.
  sinks.left = [&](const auto& m) { host.bus().publish(CrazyflieBridgeLogic::kLeftPressureTopic, m, now_ns()); };
  sinks.right = [&](const auto& m) { host.bus().publish(CrazyflieBridgeLogic::kRightPressureTopic, m, now_ns()); };
  sinks.odom = [&](const auto& m) { host.bus().publish(CrazyflieBridgeLogic::kOdomTopic, m, now_ns()); };

  const int64_t tick_ns = static_cast<int64_t>(1e9 / bridge_params.setpoint_rate_hz);
  const int64_t end_ns = static_cast<int64_t>(o.duration_s * 1e9);
  const int64_t hard_end_ns = end_ns + 15'000'000'000LL;
  bool pipeline_on = true;
  int64_t pipeline_end_ns = -1;
  int64_t next = 0;
  int64_t last_print = 0;
  while (!g_interrupted) {
    next += tick_ns;
    const auto wait = std::chrono::nanoseconds(std::max<int64_t>(0, next - now_ns()));
    runner.pump(std::chrono::duration_cast<std::chrono::milliseconds>(wait), now_ns, sinks);
    const int64_t now = now_ns();
    // The pipeline stops at the end of the run: the bridge then hovers, lands, stops.
    if (now >= end_ns && pipeline_on) {
      pipeline_on = false;
      pipeline_end_ns = now;
    }
    if (pipeline_on) host.executor().run_until(now);
    runner.on_timer(now);
    if (runner.mode() == CrazyflieBridgeLogic::Mode::kStopped && (!pipeline_on || now > 2'000'000'000LL)) {
      if (runner.logic_stats().packets_out > 0) break;
    }
    if (now >= hard_end_ns) break;
    if (o.progress && now - last_print >= 1'000'000'000LL) {
      last_print = now;
      std::printf("\r  t=%5.1f s  bridge %-10s  fsm %-16s  log samples %llu", static_cast<double>(now) * 1e-9,
                  crazyflie_bridge::to_string(runner.mode()), tactile_fsm::to_string(fsm->fsm().state()),
                  static_cast<unsigned long long>(runner.client_stats().log_samples));
      std::fflush(stdout);
    }
  }
  if (o.progress) std::printf("\n");
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  if (recorder) recorder->close();

  const auto link = runner.link_stats();
  const auto cs = runner.client_stats();
  const auto ls = runner.logic_stats();
  const auto lat = runner.latency();
  nlohmann::json m;
  m["uri"] = bridge_params.uri;
  m["connect_s"] = connect_s;
  m["wall_time_s"] = elapsed;
  m["interrupted"] = g_interrupted.load();
  m["bridge_mode"] = crazyflie_bridge::to_string(runner.mode());
  m["fsm_state"] = tactile_fsm::to_string(fsm->fsm().state());
  const int64_t fsm_end_ns = pipeline_end_ns >= 0 ? pipeline_end_ns : now_ns();
  m["link_packets_sent"] = link.packets_sent;
  m["link_packets_received"] = link.packets_received;
  // Log packets missing from the firmware timestamps of each block (exact
  // downlink loss) plus radio transfers never acknowledged.
  m["link_packets_lost"] = cs.log_missed + link.ack_missing;
  m["link_ack_rate"] = link.ack_rate();
  m["link_uplink_rssi"] = link.uplink_rssi;  // -dBm, -1: not reported (UDP)
  m["link_retries"] = link.retries;
  m["link_malformed"] = link.malformed;
  m["client_resends"] = cs.resends;
  m["log_samples"] = cs.log_samples;
  m["log_decode_errors"] = cs.log_decode_errors;
  m["setpoints_in"] = ls.setpoints_in;
  m["setpoints_clamped"] = ls.setpoints_clamped;
  m["setpoint_packets_out"] = ls.packets_out;
  m["stale_events"] = ls.stale_events;
  m["landings"] = ls.landings;
  m["dropped_nonfinite"] = ls.dropped_nonfinite;
  m["latency_mean_ms"] = lat.count ? 1e3 * lat.sum_s / static_cast<double>(lat.count) : 0.0;
  m["latency_max_ms"] = 1e3 * lat.max_s;
  m["bag_messages"] = recorder ? recorder->message_count() : 0;
  nlohmann::json published = nlohmann::json::object();
  for (const auto& [topic, n] : host.bus().published_counts()) published[topic] = n;
  m["published"] = published;
  m["nodes"] = node_reports(host);
  if (sitl) {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let the vehicle settle
    sitl_stop = true;
    sitl_thread.join();
    nlohmann::json s;
    for (const auto& [k, v] : sitl->sim().summary()) s[k] = v;
    s["collisions"] = sitl->sim().collisions().size();
    s["collision_events"] = nlohmann::json::array();  // simulator time
    for (const auto& c : sitl->sim().collisions()) {
      s["collision_events"].push_back({{"t", c.time_s}, {"part", c.part}, {"impact_speed", c.impact_speed}});
    }
    s["sim_time_s"] = static_cast<double>(sitl->sim_time_ns()) * 1e-9;
    s["scenario"] = scenario->name;
    s["injected_loss_uplink"] = sitl->stats().dropped_in;
    s["injected_loss_downlink"] = sitl->stats().dropped_out;
    s["firmware_log_packets"] = sitl->firmware().stats().log_packets;
    s["firmware_setpoints"] = sitl->firmware().stats().setpoints;
    // Simulated time runs from the endpoint's start in wall-clock time (speed
    // 1): host time = simulated time - clock_offset.
    const int64_t offset_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t0 - sitl->start_time()).count();
    s["clock_offset_s"] = static_cast<double>(offset_ns) * 1e-9;
    m["sitl"] = s;
    for (const auto& w : sitl->whisker_truth()) truth.add(w.side, w.sim_ns - offset_ns, {w.contact, w.depth});
    // Same goal as graph whisker_fsm: the FSM reached the target (landing).
    const auto st = fsm->fsm().state();
    m["reached_target"] = st == tactile_fsm::FsmState::kLanding || st == tactile_fsm::FsmState::kLanded;
  }
  // First wall-following episode (000 Fig. 6 sweep), host time; a sweep still
  // running when the pipeline stopped lasts until then. With the simulated
  // Crazyflie: depth in band and heading error from its truth, as `tactile sim`.
  m["fsm"] = sweeps.metrics(fsm_end_ns);
  write_json(dir / "metrics.json", m);
  return m;
}

nlohmann::json run_bench(const BenchOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir(o.out_dir);
  fs::create_directories(dir);
  Host host(o.config_dir);
  std::vector<std::pair<std::string, std::string>> sides{{"left", o.left_port}};
  if (!o.right_port.empty()) sides.emplace_back("right", o.right_port);
  std::vector<std::shared_ptr<whisker_driver::WhiskerDriverLogic>> drivers;
  for (const auto& [side, port] : sides) {
    tactile_common::ParamMap over;
    over.set("source", std::string("serial"));
    over.set("device", port);
    drivers.push_back(add_whisker_driver(host, "whisker/" + side, over));  // throws naming the device
    add_tdorc_filter(host, "whisker/" + side, {});
  }
  std::unique_ptr<BagRecorder> recorder;
  if (o.write_bag) {
    recorder = std::make_unique<BagRecorder>((dir / "bag").string());
    host.bus().add_tap(recorder.get());
  }
  SigintGuard guard;
  const auto t0 = Clock::now();
  const int64_t end_ns = static_cast<int64_t>(o.duration_s * 1e9);
  int64_t now = 0;
  while (!g_interrupted && now < end_ns) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    now = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
    host.executor().run_until(now);
  }
  if (recorder) recorder->close();
  nlohmann::json m;
  m["ports"] = nlohmann::json::array();
  for (const auto& [side, port] : sides) m["ports"].push_back(port);
  m["wall_time_s"] = std::chrono::duration<double>(Clock::now() - t0).count();
  m["interrupted"] = g_interrupted.load();
  m["bag_messages"] = recorder ? recorder->message_count() : 0;
  nlohmann::json published = nlohmann::json::object();
  for (const auto& [topic, n] : host.bus().published_counts()) published[topic] = n;
  m["published"] = published;
  m["nodes"] = node_reports(host);
  write_json(dir / "metrics.json", m);
  return m;
}

std::vector<std::string> run_scan(const std::string& udp_host) {
  std::vector<std::string> lines;
  for (const auto& d : crazyflie_bridge::scan(udp_host)) {
    lines.push_back((d.uri.empty() ? std::string("-") : d.uri) + "  " + d.description);
  }
  return lines;
}

}  // namespace tactile_cli
