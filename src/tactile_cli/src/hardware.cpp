#include "tactile_cli/hardware.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <thread>

#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "crazyflie_bridge/sitl_endpoint.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/host_ports.hpp"
#include "tactile_cli/sim_graph.hpp"
#include "tactile_cli/whisker_eval.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

namespace {

using Clock = std::chrono::steady_clock;
// SIGINT / SIGTERM: counted (the first lands, a second stops the motors now);
// the handler only touches lock-free atomics (async-signal-safe).
std::atomic<int> g_signals{0};
std::atomic<int> g_first_signal{0};
void on_signal(int sig) {
  int none = 0;
  g_first_signal.compare_exchange_strong(none, sig);
  g_signals.fetch_add(1);
}

struct SignalGuard {
  void (*old_int)(int);
  void (*old_term)(int);
  SignalGuard() {
    g_signals = 0;
    g_first_signal = 0;
    old_int = std::signal(SIGINT, on_signal);
    old_term = std::signal(SIGTERM, on_signal);
  }
  ~SignalGuard() {
    std::signal(SIGINT, old_int);
    std::signal(SIGTERM, old_term);
  }
};
static_assert(std::atomic<int>::is_always_lock_free, "signal handler needs lock-free atomics");

/// Keystroke teleop: stdin without line buffering and echo while it lives
/// (signals stay on: Ctrl-C still lands). Inactive when stdin is no terminal.
class RawStdin {
 public:
  explicit RawStdin(bool want) {
    if (!want || !::isatty(STDIN_FILENO) || ::tcgetattr(STDIN_FILENO, &old_) != 0) return;
    termios raw = old_;
    raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    active_ = ::tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
  }
  ~RawStdin() {
    if (active_) ::tcsetattr(STDIN_FILENO, TCSANOW, &old_);
  }
  RawStdin(const RawStdin&) = delete;
  RawStdin& operator=(const RawStdin&) = delete;
  bool active() const { return active_; }
  /// The keys typed since the last call (never waits).
  std::string keys() {
    std::string k;
    if (!active_) return k;
    pollfd p{STDIN_FILENO, POLLIN, 0};
    char buf[64];
    while (::poll(&p, 1, 0) > 0 && (p.revents & POLLIN)) {
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n <= 0) break;
      k.append(buf, static_cast<size_t>(n));
    }
    return k;
  }

 private:
  termios old_{};
  bool active_ = false;
};

const char* signal_name(int sig) { return sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : "signal"; }

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
  add_whisker_front_end(host, overrides("tdorc_filter"), overrides("tactile_depth"));
  tactile_common::ParamMap fsm_extra;
  if (scenario) {
    GraphContext ctx{*scenario, host, nullptr, scenario->seed, 0.0, dir, nullptr};
    if (auto t = ctx.target()) {
      fsm_extra.set("target_x", t->x());
      fsm_extra.set("target_y", t->y());
    }
  }
  bool pipeline_on = true;  // until the run's end: the pipeline's setpoints reach the bridge
  // The pipeline's clock: wall time since t0 (set when the link is up and the loop
  // starts; no log data arrives before). The FSM steps on each depth's arrival on it.
  Clock::time_point t0{};
  auto now_ns = [&t0] { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count(); };
  auto fsm = add_whisker_fsm(host, overrides("whisker_fsm", fsm_extra), now_ns);
  // Wall-following sweeps, as in the SITL evaluation; against the simulated
  // Crazyflie also the whiskers' true depth in band (filled after the run).
  WhiskerTruth truth;
  const auto& fp = fsm->params().fsm;
  const WallFollowingEvaluation sweeps(host, truth, fp.t_min, fp.t_max, fp.whisker_spacing);

  // The bridge: parameters from config/crazyflie_bridge.yaml, --uri (and
  // --autostart) win.
  tactile_common::ParamMap bridge_over;
  if (!uri.empty()) bridge_over.set("uri", uri);
  if (o.autostart) bridge_over.set("autostart", true);
  if (o.takeoff_height > 0.0) bridge_over.set("takeoff_height", o.takeoff_height);
  const auto bridge_params = CrazyflieBridgeLogic::params_from(
      host.load_parameters("", CrazyflieBridgeLogic::kNodeName, CrazyflieBridgeLogic::default_parameters(), bridge_over));
  if (o.takeoff && bridge_params.autostart) {
    throw std::invalid_argument("tactile fly: --takeoff with crazyflie_bridge autostart: true: choose one (autostart "
                                "flies on connect without an operator)");
  }
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
  SignalGuard guard;
  RawStdin keyboard(o.teleop);
  const auto t_connect = Clock::now();
  crazyflie_bridge::BridgeRunner runner(bridge_params, co);
  const double connect_s = std::chrono::duration<double>(Clock::now() - t_connect).count();
  for (const auto& w : runner.warnings()) std::fprintf(stderr, "tactile fly: warning: %s\n", w.c_str());
  if (o.progress) {
    std::printf("connected to %s in %.2f s (log TOC %zu variables%s, protocol %d)\n", bridge_params.uri.c_str(), connect_s,
                runner.client().log_toc().size(), runner.client().log_toc_from_cache() ? ", cached" : "",
                runner.client().protocol_version());
    std::printf(o.takeoff ? "take-off requested: %.2f m\n"
                          : bridge_params.autostart ? "autostart: the behaviour flies as soon as it publishes\n"
                                                    : "no --takeoff: on the ground, recording sensors\n",
                bridge_params.takeoff_height);
    if (keyboard.active()) std::printf("keys: t take off, l land, space EMERGENCY STOP, a arm; Ctrl-C lands and quits\n");
    std::fflush(stdout);
  }

  t0 = Clock::now();
  // The bridge's ports, as its rclcpp component wires them (BridgeRunner::wire), on the
  // host clock: messages keep the bridge's stamps; the bag time is the host clock.
  HostPorts bridge_ports(host, "", {}, now_ns);
  const crazyflie_bridge::BridgeRunner::Sinks sinks =
      crazyflie_bridge::BridgeRunner::wire(bridge_ports, [&](const tactile_msgs::msg::HoverSetpoint& m) {
        // The FSM steps on each depth's arrival, also while the shutdown landing pumps the
        // link: after the run its setpoints no longer reach the bridge (as none did when
        // it stepped on the host's timer, which stops with the pipeline).
        if (pipeline_on) runner.on_hover_setpoint(m, now_ns());
      });

  // Operator commands and their answers, in metrics.json and on the console.
  nlohmann::json commands = nlohmann::json::array();
  auto command = [&](const char* name, const CrazyflieBridgeLogic::CommandResult& r) {
    commands.push_back({{"t_s", static_cast<double>(now_ns()) * 1e-9}, {"command", name}, {"accepted", r.accepted},
                        {"reason", r.reason}});
    if (o.progress || !r.accepted) {
      std::fprintf(r.accepted ? stdout : stderr, "\n%s: %s\n", name, r.reason.c_str());
      std::fflush(r.accepted ? stdout : stderr);
    }
    return r.accepted;
  };
  size_t printed_transitions = 0;
  auto print_transitions = [&] {
    if (!o.progress) return;
    const auto h = runner.history();
    for (; printed_transitions < h.size(); ++printed_transitions) {
      const auto& tr = h[printed_transitions];
      std::printf("\n[%6.2f s] bridge %s -> %s (%s: %s)\n", static_cast<double>(tr.t_ns) * 1e-9,
                  crazyflie_bridge::to_string(tr.from), crazyflie_bridge::to_string(tr.to), tr.guard.c_str(),
                  tr.reason.c_str());
    }
    std::fflush(stdout);
  };
  auto airborne = [](CrazyflieBridgeLogic::Mode md) {
    using M = CrazyflieBridgeLogic::Mode;
    return md != M::kGrounded && md != M::kStopped && md != M::kEmergency;
  };

  const int64_t tick_ns = static_cast<int64_t>(1e9 / bridge_params.setpoint_rate_hz);
  const int64_t end_ns = static_cast<int64_t>(o.duration_s * 1e9);
  const int64_t hard_end_ns = end_ns + 15'000'000'000LL;
  int64_t pipeline_end_ns = -1;
  int64_t next = 0;
  int64_t last_print = 0;
  enum class Operator { kWaitLog, kArming, kTakingOff, kHandedOver, kDone } op = o.takeoff ? Operator::kWaitLog : Operator::kDone;
  int64_t arm_sent_ns = 0;
  bool arm_on_takeoff = o.arm;
  std::string end_reason;
  bool takeoff_refused = false;
  std::exception_ptr failure;
  double max_truth_z = 0.0;
  try {
    for (;;) {
      if (g_signals > 0) {
        end_reason = signal_name(g_first_signal.load());
        break;
      }
      next += tick_ns;
      const auto wait = std::chrono::nanoseconds(std::max<int64_t>(0, next - now_ns()));
      runner.pump(std::chrono::duration_cast<std::chrono::milliseconds>(wait), now_ns, sinks);
      const int64_t now = now_ns();
      // The run ends after its duration: the pipeline stops and, if flying, the bridge lands.
      if (now >= end_ns && pipeline_on) {
        pipeline_on = false;
        pipeline_end_ns = now;
        if (end_reason.empty()) end_reason = "duration";
        if (airborne(runner.mode()) && runner.mode() != CrazyflieBridgeLogic::Mode::kLanding) {
          command("land", runner.land(0.0, bridge_params.land_duration_s, now));
        }
      }
      if (pipeline_on) host.executor().run_until(now);
      if (o.on_tick) o.on_tick(now, crazyflie_bridge::to_string(runner.mode()));
      // Keystrokes (the same commands as the flags; an emergency stop at once).
      for (const char key : keyboard.keys()) {
        if (key == ' ') {
          command("emergency_stop", runner.emergency_stop(now));
        } else if (key == 'l') {
          command("land", runner.land(0.0, bridge_params.land_duration_s, now));
        } else if (key == 'a') {
          command("arm", runner.arm(true, now));
        } else if (key == 't' && pipeline_on && op == Operator::kDone && !airborne(runner.mode())) {
          op = Operator::kWaitLog;  // the --takeoff sequence: (--arm,) take off, then hand over
        }
      }
      // Operator sequence of --takeoff (or key t): (arm,) take off, hand over to the behaviour.
      const auto st = runner.status(now);
      switch (op) {
        case Operator::kWaitLog:
          if (pipeline_on && std::isfinite(st.log_age_s) && st.log_age_s <= bridge_params.log_timeout_s) {
            if (arm_on_takeoff) {
              command("arm", runner.arm(true, now));
              arm_sent_ns = now;
              op = Operator::kArming;
            } else {
              op = Operator::kArming;
              arm_sent_ns = now - 1'000'000'000LL;
            }
          }
          break;
        case Operator::kArming:
          // The supervisor reports the arming in its next status sample.
          if (!arm_on_takeoff || st.armed || st.supervisor_info < 0 || now - arm_sent_ns >= 1'000'000'000LL) {
            op = command("takeoff", runner.takeoff(bridge_params.takeoff_height, bridge_params.takeoff_duration_s, now))
                     ? Operator::kTakingOff
                     : Operator::kDone;
            if (op == Operator::kDone) {
              end_reason = "takeoff refused";
              takeoff_refused = true;
            }
          }
          break;
        case Operator::kTakingOff:
          if (runner.mode() == CrazyflieBridgeLogic::Mode::kHovering) {
            // Refused only while the behaviour's setpoints are not fresh: retried next tick.
            const auto r = runner.start_behaviour(now);
            if (r.accepted) {
              command("start_behaviour", r);
              op = Operator::kHandedOver;
            }
          } else if (!airborne(runner.mode())) {
            op = Operator::kDone;  // landed or stopped before the hand-over (low battery, emergency)
          }
          break;
        case Operator::kHandedOver:
        case Operator::kDone:
          break;
      }
      const bool sent = runner.on_timer(now);
      print_transitions();
      if (sitl) max_truth_z = std::max(max_truth_z, sitl->truth_position().z());
      const auto md = runner.mode();
      // On the ground with nothing left to send (stop packets out), after the
      // run, or after a flight that ended by itself.
      const bool flew = runner.logic_stats().packets_out > 0;
      if (!airborne(md) && (!sent || md == CrazyflieBridgeLogic::Mode::kEmergency) &&
          (!pipeline_on || (flew && op != Operator::kWaitLog && op != Operator::kArming))) {
        if (pipeline_on) end_reason = std::string("flight ended: ") + crazyflie_bridge::to_string(md);
        break;
      }
      if (takeoff_refused) break;  // the operator asked to fly and the bridge said no: nothing more to do
      if (now >= hard_end_ns) {
        end_reason = "hard_end";
        break;
      }
      if (o.progress && now - last_print >= 1'000'000'000LL) {
        last_print = now;
        std::printf("\r  t=%5.1f s  bridge %-10s  fsm %-16s  log samples %llu  battery %.2f V", static_cast<double>(now) * 1e-9,
                    crazyflie_bridge::to_string(md), tactile_fsm::to_string(fsm->fsm().state()),
                    static_cast<unsigned long long>(runner.client_stats().log_samples), st.battery_v);
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    end_reason = std::string("exception: ") + e.what();
    failure = std::current_exception();
  }
  if (pipeline_end_ns < 0) pipeline_end_ns = now_ns();
  // Shutdown path (signal, exception, hard end): airborne -> land first,
  // bounded; a second signal (or the bound) -> emergency stop.
  nlohmann::json shutdown = {{"land_attempted", false}, {"landed", nullptr}};
  if (airborne(runner.mode())) {
    shutdown["land_attempted"] = true;
    if (o.progress) {
      std::printf("\n%s: landing (a second Ctrl-C stops the motors at once)\n", end_reason.c_str());
      std::fflush(stdout);
    }
    try {
      const bool landed = runner.land_and_stop(
          std::chrono::milliseconds(static_cast<int64_t>(bridge_params.shutdown_land_timeout_s * 1e3)), now_ns, sinks,
          [] { return g_signals >= 2; });
      shutdown["landed"] = landed;
      if (!landed) shutdown["emergency_reason"] = g_signals >= 2 ? "second signal" : "shutdown_land_timeout_s";
    } catch (const std::exception& e) {
      shutdown["landed"] = false;
      shutdown["error"] = e.what();
      std::fprintf(stderr, "tactile fly: shutdown landing failed: %s (the firmware's commander watchdog stops the motors "
                           "2 s after the last setpoint)\n", e.what());
    }
    print_transitions();
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
  m["interrupted"] = g_signals > 0;
  m["end_reason"] = end_reason;
  m["bridge_mode"] = crazyflie_bridge::to_string(runner.mode());
  m["takeoff_requested"] = o.takeoff;
  m["autostart"] = bridge_params.autostart;
  m["operator_commands"] = commands;
  m["shutdown"] = shutdown;
  nlohmann::json history = nlohmann::json::array();
  for (const auto& tr : runner.history()) {
    history.push_back({{"t_s", static_cast<double>(tr.t_ns) * 1e-9}, {"from", crazyflie_bridge::to_string(tr.from)},
                       {"to", crazyflie_bridge::to_string(tr.to)}, {"guard", tr.guard}, {"reason", tr.reason}});
  }
  m["mode_history"] = history;
  {
    const auto st = runner.status(now_ns());
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    m["status"] = {{"armed", st.armed}, {"emergency_latched", st.emergency_latched}, {"battery_v", num(st.battery_v)},
                   {"pm_state", st.pm_state}, {"supervisor_info", st.supervisor_info}, {"rssi_dbm", st.rssi_dbm},
                   {"link_quality", num(st.link_quality)}, {"packets_lost", st.packets_lost},
                   {"log_blocks_missed", st.log_blocks_missed}, {"low_battery_events", st.low_battery_events}};
  }
  m["warnings"] = runner.warnings();
  m["fsm_state"] = tactile_fsm::to_string(fsm->fsm().state());
  const int64_t fsm_end_ns = pipeline_end_ns;
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
  m["emergency_stops"] = ls.emergency_stops;
  m["low_battery_events"] = ls.low_battery_events;
  m["status_samples"] = ls.status_samples;
  m["attitude_samples"] = ls.attitude_samples;
  m["odom_without_attitude"] = ls.odom_without_attitude;  // state samples whose attitude sample was lost
  m["log_samples_missed"] = ls.log_samples_missed;        // gaps in the per-block firmware sequences
  m["dropped_nonfinite"] = ls.dropped_nonfinite;
  m["latency_mean_ms"] = 1e3 * lat.mean_s();
  m["latency_max_ms"] = 1e3 * lat.max_s;
  // Whisker log sample received -> next setpoint sent: the pipeline's reaction time.
  const auto wl = runner.whisker_latency();
  m["whisker_latency"] = {{"samples", wl.count},           {"mean_ms", 1e3 * wl.mean_s()},
                          {"p50_ms", 1e3 * wl.quantile_s(0.5)}, {"p99_ms", 1e3 * wl.quantile_s(0.99)},
                          {"max_ms", 1e3 * wl.max_s}};
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
    s["motors_ever_on"] = sitl->first_motors_on_ns() >= 0;
    s["motors_on_at_end"] = sitl->motors_on();
    s["max_truth_z_m"] = max_truth_z;
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
  if (failure) std::rethrow_exception(failure);
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
  SignalGuard guard;
  const auto t0 = Clock::now();
  const int64_t end_ns = static_cast<int64_t>(o.duration_s * 1e9);
  int64_t now = 0;
  while (g_signals == 0 && now < end_ns) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    now = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
    host.executor().run_until(now);
  }
  if (recorder) recorder->close();
  nlohmann::json m;
  m["ports"] = nlohmann::json::array();
  for (const auto& [side, port] : sides) m["ports"].push_back(port);
  m["wall_time_s"] = std::chrono::duration<double>(Clock::now() - t0).count();
  m["interrupted"] = g_signals > 0;
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
