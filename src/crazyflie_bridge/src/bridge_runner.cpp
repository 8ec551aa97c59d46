#include "crazyflie_bridge/bridge_runner.hpp"

namespace crazyflie_bridge {

BridgeRunner::BridgeRunner(const CrazyflieBridgeLogic::Params& params, ClientOptions client_options,
                           std::unique_ptr<Link> link)
    : link_(link ? std::move(link) : open_link(params.uri)), logic_(params) {
  client_ = std::make_unique<CrazyflieClient>(*link_, client_options);
  client_->connect();
  logic_.set_protocol_version(client_->protocol_version());  // setpoint generation (cflib's threshold)
  const uint8_t w = client_->start_log_block(logic_.whisker_block(), static_cast<uint16_t>(params.whisker_period_ms));
  // Attitude block before the state block: a lower id, so a firmware that
  // sends the blocks due at one tick in id order delivers it first.
  bool variances = true;
  for (const auto& n : AttitudeBlock::variance_vars()) variances = variances && client_->log_item(n) != nullptr;
  const uint8_t a = client_->start_log_block(logic_.attitude_block(variances), static_cast<uint16_t>(params.state_period_ms));
  const uint8_t s = client_->start_log_block(logic_.state_block(), static_cast<uint16_t>(params.state_period_ms));
  logic_.set_block_ids(w, s);
  logic_.set_attitude_block_id(a);
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

void BridgeRunner::on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  logic_.on_hover_setpoint(msg, now_ns);
}

bool BridgeRunner::on_timer(int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto pk = logic_.on_timer(now_ns);
  if (!pk) return false;
  client_->send(*pk);
  if (state_pending_) {
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_state_rx_).count();
    ++latency_.count;
    latency_.sum_s += dt;
    latency_.max_s = std::max(latency_.max_s, dt);
    state_pending_ = false;
  }
  return true;
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

}  // namespace crazyflie_bridge
