#include "crazyflie_bridge/log_clock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace crazyflie_bridge {

namespace {
constexpr uint32_t kMask24 = 0xFFFFFF;
constexpr uint32_t kHalf24 = 0x800000;
}  // namespace

void LogClock::add_block(uint8_t block_id, uint32_t period_ms) {
  if (period_ms == 0) {
    throw std::invalid_argument("LogClock: block " + std::to_string(block_id) + ": period must be > 0 ms");
  }
  Block b;
  b.period_ms = period_ms;
  blocks_[block_id] = b;
}

void LogClock::rebase() {
  for (auto& [id, b] : blocks_) {
    b.have_first = false;
    b.last_sequence = -1;
  }
  have_time_ = false;
  have_offset_ = false;
}

LogClock::Stamp LogClock::on_sample(uint8_t block_id, uint32_t timestamp_ms, int64_t receive_ns) {
  auto it = blocks_.find(block_id);
  if (it == blocks_.end()) throw std::out_of_range("LogClock: block " + std::to_string(block_id) + " not registered");
  Stamp st;
  const uint32_t raw = timestamp_ms & kMask24;
  // Unwrap against the newest firmware time: forward steps of less than half
  // the 24-bit range are forward (across the wrap too), others backward.
  int64_t ms = raw;
  if (have_time_) {
    const uint32_t fwd = (raw - newest_raw_) & kMask24;
    ms = fwd < kHalf24 ? newest_ms_ + fwd : newest_ms_ - static_cast<int64_t>((newest_raw_ - raw) & kMask24);
    if (ms < newest_ms_ - kRestartBackwardMs) {
      rebase();
      ++restarts_;
      st.restart = true;
      ms = raw;
    }
  }
  if (!have_time_ || ms > newest_ms_) {
    newest_ms_ = ms;
    newest_raw_ = raw;
    have_time_ = true;
  }
  Block& b = it->second;
  if (!b.have_first) {
    b.have_first = true;
    b.first_ms = ms;
  }
  const double k = std::round(static_cast<double>(ms - b.first_ms) / b.period_ms);
  const int64_t seq = static_cast<int64_t>(k);
  st.sequence = static_cast<uint32_t>(seq);  // mod 2^32, as the message field
  if (b.last_sequence >= 0 && seq > b.last_sequence + 1) st.missed = static_cast<uint32_t>(seq - b.last_sequence - 1);
  if (seq > b.last_sequence) b.last_sequence = seq;

  const int64_t fw_ns = ms * 1000000;
  const int64_t rel = receive_ns - fw_ns;
  if (!have_offset_) {
    offset_ns_ = rel;
    have_offset_ = true;
  } else {
    const int64_t relax = static_cast<int64_t>(static_cast<double>(receive_ns - offset_at_ns_) * kMaxDriftPpm * 1e-6);
    offset_ns_ = std::min(offset_ns_ + std::max<int64_t>(relax, 0), rel);
  }
  offset_at_ns_ = receive_ns;
  st.stamp_ns = fw_ns + offset_ns_;
  return st;
}

}  // namespace crazyflie_bridge
