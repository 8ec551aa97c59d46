#include "crazyflie_bridge/bridge_runner.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

namespace crazyflie_bridge {

BridgeRunner::BridgeRunner(const CrazyflieBridgeLogic::Params& params, ClientOptions client_options,
                           std::unique_ptr<Link> link, bool stream)
    : link_(link ? std::move(link) : open_link(params.uri)),
      logic_(params),
      tick_(static_cast<int64_t>(std::llround(1e9 / params.setpoint_rate_hz))) {
  client_ = std::make_unique<CrazyflieClient>(*link_, client_options);
  client_->connect();
  logic_.set_protocol_version(client_->protocol_version());  // setpoint generation (cflib's threshold)
  const uint8_t w = client_->create_log_block(logic_.whisker_block(), static_cast<uint16_t>(params.whisker_period_ms));
  // Attitude block before the state block: a lower id, so a firmware that
  // sends the blocks due at one tick in id order delivers it first.
  bool variances = true;
  for (const auto& n : AttitudeBlock::variance_vars()) variances = variances && client_->log_item(n) != nullptr;
  const uint8_t a = client_->create_log_block(logic_.attitude_block(variances), static_cast<uint16_t>(params.state_period_ms));
  const uint8_t s = client_->create_log_block(logic_.state_block(), static_cast<uint16_t>(params.state_period_ms));
  logic_.set_block_ids(w, s);
  logic_.set_attitude_block_id(a);
  block_ids_ = {w, a, s};
  // Status block: what the firmware's TOC has of status_vars; a missing one is
  // a warning, never a failed connect (battery / supervisor are for display
  // and the low-battery guard, not for flying).
  std::vector<std::string> have;
  for (const auto& n : params.status_vars) {
    if (client_->log_item(n)) {
      have.push_back(n);
    } else {
      warnings_.push_back("crazyflie_bridge: status variable " + n + " is not in the firmware's log TOC: not logged");
    }
  }
  uint8_t st = 0;
  bool status_block = false;
  if (!have.empty()) {
    try {
      st = client_->create_log_block(have, static_cast<uint16_t>(params.status_period_ms));
      status_block = true;
    } catch (const ClientError& e) {
      warnings_.push_back(std::string("crazyflie_bridge: status log block not created: ") + e.what());
    }
  }
  if (status_block) {
    logic_.set_status_block(st, have);
    status_block_id_ = st;
  }
  if (stream) start_streaming();
}

void BridgeRunner::start_streaming() {
  if (streaming_) return;
  // In creation order (whisker, attitude, state, then status), as before the split.
  for (uint8_t id : block_ids_) client_->start_created_log_block(id);
  if (status_block_id_) {
    try {
      client_->start_created_log_block(*status_block_id_);
    } catch (const ClientError& e) {  // display and the low-battery guard only: never a failed connect
      warnings_.push_back(std::string("crazyflie_bridge: status log block not started: ") + e.what());
    }
  }
  streaming_ = true;
}

bool BridgeRunner::stop_streaming() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (logic_.airborne()) return false;  // never blind a flying vehicle: land first
  }
  if (!streaming_) return true;
  for (uint8_t id : block_ids_) client_->stop_log_block(id);
  if (status_block_id_) {
    try {
      client_->stop_log_block(*status_block_id_);
    } catch (const ClientError& e) {  // it may never have started
      warnings_.push_back(std::string("crazyflie_bridge: status log block not stopped: ") + e.what());
    }
  }
  streaming_ = false;
  return true;
}

void BridgeRunner::flush_outbox() {
  for (const auto& pk : logic_.take_outbox()) client_->send(pk);
}

int BridgeRunner::pump(std::chrono::milliseconds timeout, const std::function<int64_t()>& now_ns, const Sinks& sinks) {
  int n = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    // The client is used by this thread only (receive side); sends go through the mutex.
    auto s = client_->poll(std::max(left, std::chrono::milliseconds(0)));
    if (!s) break;
    CrazyflieBridgeLogic::LogOutputs out;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      out = logic_.on_log_sample(*s, now_ns());
      if (out.odom) {
        last_state_rx_ = s->received;
        state_pending_ = true;
      }
      if ((out.left || out.right) && !whisker_pending_) {  // the oldest whisker sample not yet answered
        last_whisker_rx_ = s->received;
        whisker_pending_ = true;
      }
    }
    ++n;
    if (out.left && sinks.left) sinks.left(*out.left);
    if (out.right && sinks.right) sinks.right(*out.right);
    if (out.odom && sinks.odom) sinks.odom(*out.odom);
    // Past the deadline poll() no longer waits but still drains what already
    // arrived (a backlog must not build up); bounded against a flood.
    if (n >= kMaxSamplesPerPump) break;
  }
  return n;
}

bool BridgeRunner::on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  logic_.on_hover_setpoint(msg, now_ns);
  // Only in forward mode is the behaviour's setpoint what goes out; every other mode
  // (take-off, hover, go-to, landing, hold, stop) is paced by the watchdog.
  if (logic_.mode() != Mode::kForward || !tick_.on_event(now_ns)) return false;
  return step(now_ns);
}

bool BridgeRunner::on_timer(int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Only forward mode is driven by arrivals: there the watchdog stays quiet while setpoints
  // step the logic. Every other mode steps on every call, also the first one after leaving
  // forward (a land, a hold, the emergency stop and its repeat go out at once).
  const bool quiet = !tick_.on_watchdog();
  if (quiet && logic_.mode() == Mode::kForward) {
    flush_outbox();
    return false;
  }
  return step(now_ns);
}

bool BridgeRunner::step(int64_t now_ns) {
  flush_outbox();
  const bool behaviour_flies = logic_.mode() == Mode::kForward;
  auto pk = logic_.on_timer(now_ns);
  flush_outbox();
  if (!pk) return false;
  client_->send(*pk);
  const auto sent = std::chrono::steady_clock::now();
  if (state_pending_) {
    latency_.add(std::chrono::duration<double>(sent - last_state_rx_).count());
    state_pending_ = false;
  }
  if (whisker_pending_) {
    // The pipeline's reaction time only where the packet is the behaviour's setpoint.
    if (behaviour_flies) whisker_latency_.add(std::chrono::duration<double>(sent - last_whisker_rx_).count());
    whisker_pending_ = false;
  }
  return true;
}

#define TACTILE_BRIDGE_COMMAND(call)   \
  std::lock_guard<std::mutex> lock(mutex_); \
  auto r = logic_.call;                     \
  flush_outbox();                           \
  return r;

BridgeRunner::CommandResult BridgeRunner::arm(bool on, int64_t now_ns) { TACTILE_BRIDGE_COMMAND(arm(on, now_ns)) }
BridgeRunner::CommandResult BridgeRunner::takeoff(double h, double d, int64_t now_ns) {
  TACTILE_BRIDGE_COMMAND(takeoff(h, d, now_ns))
}
BridgeRunner::CommandResult BridgeRunner::land(double h, double d, int64_t now_ns) { TACTILE_BRIDGE_COMMAND(land(h, d, now_ns)) }
BridgeRunner::CommandResult BridgeRunner::go_to(double x, double y, double z, double yaw, double d, bool rel, int64_t now_ns) {
  TACTILE_BRIDGE_COMMAND(go_to(x, y, z, yaw, d, rel, now_ns))
}
BridgeRunner::CommandResult BridgeRunner::start_behaviour(int64_t now_ns) { TACTILE_BRIDGE_COMMAND(start_behaviour(now_ns)) }
BridgeRunner::CommandResult BridgeRunner::notify_setpoints_stop(uint32_t ms, int64_t now_ns) {
  TACTILE_BRIDGE_COMMAND(notify_setpoints_stop(ms, now_ns))
}
BridgeRunner::CommandResult BridgeRunner::emergency_stop(int64_t now_ns) { TACTILE_BRIDGE_COMMAND(emergency_stop(now_ns)) }
#undef TACTILE_BRIDGE_COMMAND

bool BridgeRunner::land_and_stop(std::chrono::milliseconds timeout, const std::function<int64_t()>& now_ns,
                                 const Sinks& sinks, const std::function<bool()>& abort) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const CrazyflieBridgeLogic::Params& p = logic_.params();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const Mode m = logic_.mode();
    if (!logic_.airborne()) return m != Mode::kEmergency;  // on the ground already (kEmergency: it was not a landing)
    if (m != Mode::kLanding) {
      logic_.land(0.0, p.land_duration_s, now_ns());
      flush_outbox();
    }
  }
  const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / p.setpoint_rate_hz));
  auto next = std::chrono::steady_clock::now();
  for (;;) {
    if ((abort && abort()) || std::chrono::steady_clock::now() >= deadline) {
      emergency_stop(now_ns());  // sends the stop packet now
      on_timer(now_ns());        // and the latched one once more
      return false;
    }
    next += period;
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - std::chrono::steady_clock::now());
    pump(std::max(wait, std::chrono::milliseconds(0)), now_ns, sinks);
    const bool sent = on_timer(now_ns());
    // Landed once the stop packet and its repeats are out (the logic sends
    // nothing after them).
    if (mode() == Mode::kStopped && !sent) return true;
  }
}

BridgeRunner::Status BridgeRunner::status(int64_t now_ns) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Status st = logic_.status(now_ns);
  const LinkStatistics ls = link_->statistics();
  // ACK rate of a radio link (UDP / USB have no ACKs: unknown, NaN).
  st.link_quality = ls.acks + ls.ack_missing > 0 ? ls.ack_rate() : NAN;
  st.packets_lost = ls.ack_missing;
  // RSSI: the firmware's radio.rssi log where logged, else the radio ACK's.
  if (st.rssi_dbm < 0) st.rssi_dbm = ls.uplink_rssi;
  st.log_blocks_missed = client_->stats().log_missed;
  return st;
}

std::vector<CrazyflieBridgeLogic::Transition> BridgeRunner::history() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return logic_.history();
}

CrazyflieBridgeLogic::Mode BridgeRunner::mode() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return logic_.mode();
}
CrazyflieBridgeLogic::Stats BridgeRunner::logic_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return logic_.stats();
}
LinkStatistics BridgeRunner::link_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return link_->statistics();
}
CrazyflieClient::Stats BridgeRunner::client_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return client_->stats();
}
BridgeRunner::LatencyStats BridgeRunner::latency() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latency_;
}
BridgeRunner::LatencyStats BridgeRunner::whisker_latency() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return whisker_latency_;
}
tactile_common::EventTick::Stats BridgeRunner::tick_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return tick_.stats();
}

void BridgeRunner::LatencyStats::add(double s) {
  ++count;
  sum_s += s;
  max_s = std::max(max_s, s);
  const double b = std::floor(std::max(0.0, s) / kBinS);
  ++bins[b >= static_cast<double>(kBins) ? kBins - 1 : static_cast<std::size_t>(b)];
}

double BridgeRunner::LatencyStats::quantile_s(double q) const {
  if (count == 0) return 0.0;
  const auto rank = static_cast<uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count)));
  uint64_t seen = 0;
  for (std::size_t i = 0; i < kBins; ++i) {
    seen += bins[i];
    if (seen >= std::max<uint64_t>(rank, 1)) return i + 1 == kBins ? max_s : static_cast<double>(i + 1) * kBinS;
  }
  return max_s;
}

}  // namespace crazyflie_bridge
