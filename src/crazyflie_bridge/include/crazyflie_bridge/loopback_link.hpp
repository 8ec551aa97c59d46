// A Link whose far end is a FirmwareEmulator in the same thread, on a clock
// the owner advances: the bridge and a simulated Crazyflie in lockstep on a
// simulated clock (tactile sim's whisker_fsm_crtp graph), reproducible for a
// seed. Every packet crosses as bytes (encode -> decode, as on a wire), with
// seeded independent loss in each direction. receive() never waits.
#pragma once

#include <deque>
#include <random>

#include "crazyflie_bridge/firmware.hpp"
#include "crazyflie_bridge/link.hpp"

namespace crazyflie_bridge {

class LoopbackLink : public Link {
 public:
  LoopbackLink(FirmwareEmulator& firmware, double loss_rate, uint64_t seed);

  void set_time_ms(uint32_t now_ms) { now_ms_ = now_ms; }
  /// Firmware side: log data of the blocks due now onto the downlink.
  void tick();

  void send(const CrtpPacket& pk) override;
  std::optional<CrtpPacket> receive(std::chrono::milliseconds timeout) override;
  const LinkStatistics& statistics() const override { return stats_; }
  std::string uri() const override { return "loopback://simulated-crazyflie"; }

  uint64_t dropped_uplink() const { return dropped_up_; }
  uint64_t dropped_downlink() const { return dropped_down_; }
  uint64_t dropped_log_packets() const { return dropped_log_; }

 private:
  bool drop();
  void downlink(const CrtpPacket& pk);
  FirmwareEmulator& fw_;
  double loss_;
  std::mt19937_64 rng_;
  uint32_t now_ms_ = 0;
  std::deque<CrtpPacket> down_;
  std::vector<CrtpPacket> scratch_;
  uint64_t dropped_up_ = 0, dropped_down_ = 0, dropped_log_ = 0;
  LinkStatistics stats_;
};

}  // namespace crazyflie_bridge
