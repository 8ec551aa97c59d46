#include "crazyflie_bridge/sitl_endpoint.hpp"

#include <cmath>
#include <thread>

#include "tactile_common/geometry.hpp"
#include "tactile_common/time.hpp"

namespace crazyflie_bridge {

using Clock = std::chrono::steady_clock;


SitlEndpoint::SitlEndpoint(const tactile_sim::Scenario& scenario, uint64_t seed, const SitlEndpointOptions& options)
    : opt_(options),
      sim_(std::make_unique<tactile_sim::SimLogic>(scenario, seed)),
      fw_([&options] {
        SimulatedCrazyflieFirmware::Options f;
        f.loss_rate = options.loss_rate;
        f.protocol_version = options.protocol_version;
        f.require_arming = options.require_arming;
        return f;
      }()),
      server_(options.port, options.bind_address),
      rng_(options.fault_seed) {
  if (!(opt_.speed > 0.0) || !std::isfinite(opt_.speed)) throw std::invalid_argument("SitlEndpointOptions.speed: must be > 0");
  if (!(opt_.loss_rate >= 0.0 && opt_.loss_rate < 1.0)) throw std::invalid_argument("SitlEndpointOptions.loss_rate: must be in [0, 1)");
  param_loss_ = fw_.loss_rate();
  next_spike_ = Clock::now();
}

SitlEndpoint::~SitlEndpoint() = default;

tactile_sim::Vec3 SitlEndpoint::truth_position() const {
  std::lock_guard<std::mutex> lock(truth_mutex_);
  return truth_;
}
double SitlEndpoint::truth_yaw() const {
  std::lock_guard<std::mutex> lock(truth_mutex_);
  return truth_yaw_;
}

bool SitlEndpoint::drop() {
  return opt_.loss_rate > 0.0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < opt_.loss_rate;
}

double SitlEndpoint::extra_latency(Clock::time_point now) {
  if (opt_.spike_rate_hz <= 0.0) return 0.0;
  while (now >= next_spike_) {
    const double gap = std::exponential_distribution<double>(opt_.spike_rate_hz)(rng_);
    const auto start = next_spike_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(gap));
    next_spike_ = start;
    if (start <= now) {
      spike_until_ = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt_.spike_duration_s));
      ++stats_.spikes;
    } else {
      break;
    }
  }
  return now < spike_until_ ? opt_.spike_latency_s : 0.0;
}

void SitlEndpoint::step_physics() {
  out_.clear();
  sim_->step(now_ns_, out_);
  ++stats_.sim_steps;
  for (const auto& p : out_.pressure) fw_.on_pressure(p.msg);
  if (opt_.record_whisker_truth) {
    for (const auto& w : out_.whisker_truth) {
      const int side = w.topic.find("/right/") != std::string::npos ? 1 : 0;
      whisker_truth_.push_back({tactile_common::from_stamp(w.msg.header.stamp), side, w.msg.contact, w.msg.depth});
    }
  }
  for (const auto& o : out_.odometry) {
    if (o.topic == "odom") {
      fw_.on_estimate(o.msg);
    } else if (o.topic == "ground_truth/odom") {
      fw_.on_truth(o.msg);
      std::lock_guard<std::mutex> lock(truth_mutex_);
      const auto& q = o.msg.pose.pose.position;
      truth_ = tactile_sim::Vec3(q.x, q.y, q.z);
      truth_yaw_ = tactile_common::yaw_of(o.msg.pose.pose.orientation);
    }
  }
}

void SitlEndpoint::apply_commander() {
  if (vbat_pending_.exchange(false)) fw_.set_battery_voltage(vbat_request_.load());
  const auto c = fw_.command(now_ns_, tactile_common::to_seconds(sim_->period_ns()));
  const bool on = fw_.emulator().motors_on(static_cast<uint32_t>(now_ns_ / 1000000));
  motors_on_ = on;
  if (on && first_motors_on_ns_ < 0) first_motors_on_ns_ = now_ns_;
  if (c.hover) sim_->on_hover_setpoint(*c.hover);
  if (c.position) sim_->on_position_setpoint(*c.position);
}

void SitlEndpoint::flush(Clock::time_point now) {
  // Outgoing replies and log data: loss and latency spikes apply.
  for (auto& pk : replies_) {
    if (drop()) {
      ++stats_.dropped_out;
      continue;
    }
    const double lat = extra_latency(now);
    if (lat > 0.0 || !held_.empty()) {
      if (lat > 0.0) ++stats_.delayed;
      held_.push_back({now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lat)), pk, false});
    } else {
      server_.send(pk);
    }
  }
  replies_.clear();
  // Release held packets in order (a spike delays everything behind it).
  while (!held_.empty() && held_.front().release <= now) {
    auto h = held_.front();
    held_.pop_front();
    if (h.inbound) {
      fw_.emulator().on_packet(h.pk, static_cast<uint32_t>(now_ns_ / 1000000), replies_);
    } else {
      server_.send(h.pk);
    }
  }
}

void SitlEndpoint::run(double duration_s, const std::atomic<bool>* stop) {
  const auto t0 = Clock::now();
  start_ticks_ = t0.time_since_epoch().count();
  const int64_t period = sim_->period_ns();
  const int64_t end_ns = duration_s > 0.0 ? tactile_common::from_seconds(duration_s) : INT64_MAX;
  while (!(stop && stop->load()) && now_ns_ <= end_ns) {
    if (const double p = loss_request_.exchange(-1.0); p >= 0.0) {
      opt_.loss_rate = std::clamp(p, 0.0, 0.99);
    } else if (fw_.loss_rate() != param_loss_) {
      opt_.loss_rate = param_loss_ = fw_.loss_rate();  // sitl.lossPct written over CRTP
    }
    const auto wall = Clock::now();
    const int64_t target_ns = static_cast<int64_t>(std::chrono::duration<double>(wall - t0).count() * opt_.speed * 1e9);
    int steps = 0;
    while (now_ns_ <= target_ns && now_ns_ <= end_ns && steps < 200) {
      apply_commander();
      step_physics();
      fw_.emulator().tick(static_cast<uint32_t>(now_ns_ / 1000000), replies_);
      now_ns_ += period;
      ++steps;
    }
    flush(Clock::now());
    // Wait for uplink packets until the next physics step is due.
    const double next_wall_s = static_cast<double>(now_ns_) / 1e9 / opt_.speed;
    auto wait = std::chrono::duration_cast<std::chrono::microseconds>(
        t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(next_wall_s)) - Clock::now());
    if (wait.count() < 0) wait = std::chrono::microseconds(0);
    if (auto pk = server_.receive(wait)) {
      const auto now = Clock::now();
      if (drop()) {
        ++stats_.dropped_in;
      } else {
        const double lat = extra_latency(now);
        if (lat > 0.0) {
          ++stats_.delayed;
          held_.push_back({now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(lat)), *pk, true});
        } else {
          fw_.emulator().on_packet(*pk, static_cast<uint32_t>(now_ns_ / 1000000), replies_);
        }
      }
      flush(now);
    }
  }
}

}  // namespace crazyflie_bridge
