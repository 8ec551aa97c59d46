#include "crazyflie_bridge/sitl_endpoint.hpp"

#include <cmath>
#include <thread>

#include "tactile_common/time.hpp"

namespace crazyflie_bridge {

using Clock = std::chrono::steady_clock;

namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kDegToRad = M_PI / 180.0;

double yaw_of(const geometry_msgs::msg::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}
}  // namespace

SitlEndpoint::SitlEndpoint(const tactile_sim::Scenario& scenario, uint64_t seed, const SitlEndpointOptions& options)
    : opt_(options),
      sim_(std::make_unique<tactile_sim::SimLogic>(scenario, seed)),
      server_(options.port, options.bind_address),
      rng_(options.fault_seed) {
  if (!(opt_.speed > 0.0) || !std::isfinite(opt_.speed)) throw std::invalid_argument("SitlEndpointOptions.speed: must be > 0");
  if (!(opt_.loss_rate >= 0.0 && opt_.loss_rate < 1.0)) throw std::invalid_argument("SitlEndpointOptions.loss_rate: must be in [0, 1)");
  using logp::Type;
  id_left_ = fw_.add_log_variable("Whisker", "Barometer1_1", Type::kFloat);
  fw_.add_log_variable("Whisker", "Barometer1_2", Type::kFloat);
  fw_.add_log_variable("Whisker", "Barometer1_3", Type::kFloat);
  id_right_ = fw_.add_log_variable("Whisker1", "Barometer2_1", Type::kFloat);
  fw_.add_log_variable("Whisker1", "Barometer2_2", Type::kFloat);
  fw_.add_log_variable("Whisker1", "Barometer2_3", Type::kFloat);
  id_state_ = fw_.add_log_variable("stateEstimate", "x", Type::kFloat);
  for (const char* n : {"y", "z", "yaw", "vx", "vy", "vz"}) fw_.add_log_variable("stateEstimate", n, Type::kFloat);
  id_vbat_ = fw_.add_log_variable("pm", "vbat", Type::kFloat);
  fw_.set_log_value(id_vbat_, 4.0);
  id_truth_ = fw_.add_log_variable("sitl", "truthX", Type::kFloat);
  fw_.add_log_variable("sitl", "truthY", Type::kFloat);
  fw_.add_log_variable("sitl", "truthZ", Type::kFloat);
  fw_.add_param("deck", "bcWhisker", param::kUint8, 1, true);
  fw_.add_param("commander", "enHighLevel", param::kUint8, 0, false);
  p_stop_ = fw_.add_param("stabilizer", "stop", param::kUint8, 0, false);
  p_loss_ = fw_.add_param("sitl", "lossPct", param::kUint8, std::round(opt_.loss_rate * 100.0), false);
  fw_.on_param_written = [this](uint16_t id, double v) {
    if (id == p_loss_) opt_.loss_rate = std::clamp(v / 100.0, 0.0, 0.99);
  };
  next_spike_ = Clock::now();
}

SitlEndpoint::~SitlEndpoint() = default;

tactile_sim::Vec3 SitlEndpoint::truth_position() const {
  std::lock_guard<std::mutex> lock(truth_mutex_);
  return truth_;
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
  for (const auto& p : out_.pressure) {
    const uint16_t base = p.msg.whisker_id == tactile_msgs::msg::WhiskerPressure::WHISKER_LEFT ? id_left_ : id_right_;
    for (uint16_t i = 0; i < 3; ++i) fw_.set_log_value(static_cast<uint16_t>(base + i), p.msg.pressure[i]);
  }
  for (const auto& o : out_.odometry) {
    const auto& pose = o.msg.pose.pose;
    const double yaw = yaw_of(pose.orientation);
    if (o.topic == "/odom") {
      const tactile_sim::Quat q(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z);
      const tactile_sim::Vec3 vb(o.msg.twist.twist.linear.x, o.msg.twist.twist.linear.y, o.msg.twist.twist.linear.z);
      const tactile_sim::Vec3 vw = q * vb;
      const double vals[7] = {pose.position.x, pose.position.y, pose.position.z, yaw * kRadToDeg, vw.x(), vw.y(), vw.z()};
      for (uint16_t i = 0; i < 7; ++i) fw_.set_log_value(static_cast<uint16_t>(id_state_ + i), vals[i]);
    } else if (o.topic == "/ground_truth/odom") {
      {
        std::lock_guard<std::mutex> lock(truth_mutex_);
        truth_ = tactile_sim::Vec3(pose.position.x, pose.position.y, pose.position.z);
      }
      fw_.set_log_value(id_truth_, pose.position.x);
      fw_.set_log_value(static_cast<uint16_t>(id_truth_ + 1), pose.position.y);
      fw_.set_log_value(static_cast<uint16_t>(id_truth_ + 2), pose.position.z);
    }
  }
}

void SitlEndpoint::apply_commander() {
  const uint32_t now_ms = static_cast<uint32_t>(now_ns_ / 1000000);
  auto c = fw_.commander(now_ms);
  if (fw_.param_value(p_stop_) != 0) c.mode = FirmwareEmulator::CommanderOutput::Mode::kShutdown;
  tactile_msgs::msg::HoverSetpoint hs;
  tactile_common::to_stamp(now_ns_, hs.header.stamp);
  using Mode = FirmwareEmulator::CommanderOutput::Mode;
  using Kind = commander::Setpoint::Kind;
  const int mode = static_cast<int>(c.mode);
  switch (c.mode) {
    case Mode::kIdle:
      return;  // motors off until the first setpoint
    case Mode::kSetpoint: {
      const auto& s = c.setpoint;
      if (s.kind == Kind::kHover) {
        hs.vx = s.a;
        hs.vy = s.b;
        hs.yaw_rate = s.c * kDegToRad;  // type 10: deg/s, CCW positive
        hs.height = s.d;
        height_cmd_ = s.d;
        if (hs.height <= 0.0) hs.land = true;
      } else if (s.kind == Kind::kVelocityWorld) {
        // World velocity -> body-yaw frame; vz integrates the height setpoint.
        const auto& tr = sim_->trajectory();
        double yaw = 0.0;
        if (!tr.empty()) {
          const tactile_sim::Vec3 x = tr.back().estimate.orientation * tactile_sim::Vec3::UnitX();
          yaw = std::atan2(x.y(), x.x());
        }
        hs.vx = std::cos(yaw) * s.a + std::sin(yaw) * s.b;
        hs.vy = -std::sin(yaw) * s.a + std::cos(yaw) * s.b;
        height_cmd_ = std::max(0.0, height_cmd_ + s.c * tactile_common::to_seconds(sim_->period_ns()));
        hs.height = height_cmd_;
        hs.yaw_rate = s.d * kDegToRad;
      } else if (s.kind == Kind::kPosition) {
        geometry_msgs::msg::PoseStamped ps;
        ps.header.stamp = hs.header.stamp;
        ps.pose.position.x = s.a;
        ps.pose.position.y = s.b;
        ps.pose.position.z = s.c;
        ps.pose.orientation.z = std::sin(s.d * kDegToRad / 2);
        ps.pose.orientation.w = std::cos(s.d * kDegToRad / 2);
        if (mode != last_mode_ || now_ns_ % 10000000 == 0) sim_->on_position_setpoint(ps);
        last_mode_ = mode;
        return;
      }
      break;
    }
    case Mode::kStabilize:
      hs.height = height_cmd_;  // level out: hold position and height
      break;
    case Mode::kShutdown:
      hs.land = true;  // motors off (the simulated vehicle descends and stops)
      hs.height = 0.0;
      break;
  }
  sim_->on_hover_setpoint(hs);
  last_mode_ = mode;
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
      fw_.on_packet(h.pk, static_cast<uint32_t>(now_ns_ / 1000000), replies_);
    } else {
      server_.send(h.pk);
    }
  }
}

void SitlEndpoint::run(double duration_s, const std::atomic<bool>* stop) {
  const auto t0 = Clock::now();
  const int64_t period = sim_->period_ns();
  const int64_t end_ns = duration_s > 0.0 ? tactile_common::from_seconds(duration_s) : INT64_MAX;
  while (!(stop && stop->load()) && now_ns_ <= end_ns) {
    if (const double p = loss_request_.exchange(-1.0); p >= 0.0) opt_.loss_rate = std::clamp(p, 0.0, 0.99);
    const auto wall = Clock::now();
    const int64_t target_ns = static_cast<int64_t>(std::chrono::duration<double>(wall - t0).count() * opt_.speed * 1e9);
    int steps = 0;
    while (now_ns_ <= target_ns && now_ns_ <= end_ns && steps < 200) {
      apply_commander();
      step_physics();
      fw_.tick(static_cast<uint32_t>(now_ns_ / 1000000), replies_);
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
          fw_.on_packet(*pk, static_cast<uint32_t>(now_ns_ / 1000000), replies_);
        }
      }
      flush(now);
    }
  }
}

}  // namespace crazyflie_bridge
