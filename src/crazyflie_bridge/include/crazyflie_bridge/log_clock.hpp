// Firmware time of the log stream -> sequence numbers and host stamps.
//
// Every log data packet carries the firmware's 24-bit millisecond tick (log.c:
// xTaskGetTickCount() & 0xFFFFFF, wrapping every 4.66 h). A block is sampled
// every `period_ms`, so its k-th sample since the first one carries
// t_first + k * period (+- a tick of scheduling jitter). LogClock turns that
// into
//   sequence = round((t - t_first) / period)   per block (unwrapped t),
// so a log packet lost on the radio is a gap in the sequence (the message
// contract of WhiskerPressure.sequence), and
//   stamp = t + offset,  offset = min over samples of (receive time - t),
// the host-clock instant the sample was taken, up to the smallest one-way
// delay seen (receive times carry the radio's queueing and the host's
// scheduling; their minimum is the least-delayed packet). The minimum may
// only grow by kMaxDriftPpm of the elapsed receive time, so a firmware clock
// slower than the host's is followed (STM32 HSE crystal tolerance is tens of
// ppm); a faster one lowers the minimum by itself.
// A firmware time more than kRestartBackwardMs behind the newest one is a
// firmware restart: every block and the offset are re-based (restarts()).
#pragma once

#include <cstdint>
#include <map>

namespace crazyflie_bridge {

class LogClock {
 public:
  static constexpr double kMaxDriftPpm = 200.0;
  static constexpr int64_t kRestartBackwardMs = 1000;

  struct Stamp {
    uint32_t sequence = 0;  ///< round((t - t_first) / period) of the block
    int64_t stamp_ns = 0;   ///< firmware time on the host clock
    uint32_t missed = 0;    ///< sequence numbers skipped since the block's previous sample
    bool restart = false;   ///< this sample re-based the clock (firmware restart)
  };

  /// Registers a block and its period (> 0; throws std::invalid_argument).
  void add_block(uint8_t block_id, uint32_t period_ms);
  bool has_block(uint8_t block_id) const { return blocks_.count(block_id) != 0; }
  /// One sample of `block_id` (registered; throws std::out_of_range otherwise)
  /// with firmware timestamp `timestamp_ms` (24 bit), received at `receive_ns`
  /// on the host clock.
  Stamp on_sample(uint8_t block_id, uint32_t timestamp_ms, int64_t receive_ns);
  /// Current estimate of host time - firmware time [ns].
  int64_t offset_ns() const { return offset_ns_; }
  uint64_t restarts() const { return restarts_; }

 private:
  struct Block {
    uint32_t period_ms = 0;
    bool have_first = false;
    int64_t first_ms = 0;
    int64_t last_sequence = -1;
  };
  void rebase();
  std::map<uint8_t, Block> blocks_;
  bool have_time_ = false;
  uint32_t newest_raw_ = 0;
  int64_t newest_ms_ = 0;  ///< unwrapped firmware time of the newest sample
  bool have_offset_ = false;
  int64_t offset_ns_ = 0, offset_at_ns_ = 0;
  uint64_t restarts_ = 0;
};

}  // namespace crazyflie_bridge
