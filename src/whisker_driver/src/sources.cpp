#include "whisker_driver/sources.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "tactile_common/time.hpp"

namespace whisker_driver {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr size_t kReadChunk = 512;
constexpr size_t kMaxBytesPerPoll = 16384;  // ~1.4 s of data at 115200 baud
}  // namespace

// ------------------------------------------------------------------- serial

SerialSource::SerialSource(SerialPort port, Protocol protocol, SampleIdentity id,
                           int64_t sample_period_ns, int baud)
    : port_(std::move(port)), device_(port_.device()), baud_(baud), parser_(make_parser(protocol)),
      id_(std::move(id)), period_ns_(sample_period_ns) {
  if (!port_.is_open()) throw SerialError("SerialSource: serial port is not open");
  frames_.reserve(64);
  buf_.resize(kReadChunk);
}

void SerialSource::poll(int64_t now_ns, std::vector<WhiskerPressure>& out) {
  frames_.clear();
  if (!port_.is_open()) {
    if (now_ns < next_reopen_ns_) return;
    try {
      port_.open(device_, baud_);
      parser_->reset();  // a partial line from before the disconnect is lost
    } catch (const SerialError& e) {
      ++errors_;
      last_error_ = e.what();
      next_reopen_ns_ = now_ns + kReopenIntervalNs;
      return;
    }
  }
  size_t total = 0;
  try {
    while (total < kMaxBytesPerPoll) {
      const size_t n = port_.read_some(buf_.data(), buf_.size(), 0);
      if (n == 0) break;
      total += n;
      parser_->feed(buf_.data(), n, frames_);
    }
  } catch (const SerialError& e) {
    ++errors_;
    last_error_ = e.what();
    port_.close();
    next_reopen_ns_ = now_ns + kReopenIntervalNs;
  }
  const size_t count = frames_.size();
  for (size_t i = 0; i < count; ++i) {
    const WhiskerFrame& f = frames_[i];
    WhiskerPressure msg;
    tactile_common::to_stamp(now_ns - static_cast<int64_t>(count - 1 - i) * period_ns_, msg.header.stamp);
    msg.header.frame_id = id_.frame_id;
    msg.whisker_id = id_.whisker_id;
    for (int c = 0; c < 3; ++c) {
      msg.pressure[c] = f.pressure[c];
      msg.temperature[c] = f.temperature[c];
    }
    msg.sequence = f.sequence;
    out.push_back(std::move(msg));
  }
}

// --------------------------------------------------------------------- sim

double SimScenario::load(double t) const {
  double m = 0.0;
  for (const auto& c : contacts) {
    if (c.duration_s > 0.0 && t >= c.start_s && t < c.start_s + c.duration_s) {
      m += c.peak_load_nm * std::sin(kPi * (t - c.start_s) / c.duration_s);
    }
  }
  return m;
}

SimSource::SimSource(const tactile_sim::WhiskerBarometerParams& model, uint64_t seed,
                     SimScenario scenario, SampleIdentity id, double rate_hz)
    : model_(model, seed), scenario_(std::move(scenario)), id_(std::move(id)) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("SimSource: rate_hz must be > 0");
  }
  period_ns_ = static_cast<int64_t>(std::llround(1e9 / rate_hz));
  if (period_ns_ <= 0) throw std::invalid_argument("SimSource: rate_hz too high");
}

void SimSource::poll(int64_t now_ns, std::vector<WhiskerPressure>& out) {
  if (!started_) {
    started_ = true;
    t0_ns_ = now_ns;
    k_ = 0;
  }
  const double dt = static_cast<double>(period_ns_) * 1e-9;
  for (int n = 0; n < kMaxSamplesPerPoll; ++n) {
    const int64_t stamp = t0_ns_ + static_cast<int64_t>(k_) * period_ns_;
    if (stamp > now_ns) break;
    const double t = static_cast<double>(k_) * dt;  // scenario time of this sample
    const auto s = model_.step(dt, scenario_.load(t), scenario_.motors_on(t));
    WhiskerPressure msg;
    tactile_common::to_stamp(stamp, msg.header.stamp);
    msg.header.frame_id = id_.frame_id;
    msg.whisker_id = id_.whisker_id;
    for (int c = 0; c < 3; ++c) {
      msg.pressure[c] = s.pressure[c];
      msg.temperature[c] = s.temperature[c];
    }
    msg.sequence = static_cast<uint32_t>(k_);
    out.push_back(std::move(msg));
    ++k_;
  }
}

}  // namespace whisker_driver
