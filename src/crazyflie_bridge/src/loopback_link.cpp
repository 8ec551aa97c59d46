#include "crazyflie_bridge/loopback_link.hpp"

#include <stdexcept>

namespace crazyflie_bridge {

LoopbackLink::LoopbackLink(FirmwareEmulator& firmware, double loss_rate, uint64_t seed)
    : fw_(firmware), loss_(loss_rate), rng_(seed) {
  if (!(loss_rate >= 0.0 && loss_rate < 1.0)) {
    throw std::invalid_argument("LoopbackLink.loss_rate: must be in [0, 1), got " + std::to_string(loss_rate));
  }
}

bool LoopbackLink::drop() { return loss_ > 0.0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < loss_; }

void LoopbackLink::downlink(const CrtpPacket& pk) {
  if (drop()) {
    ++dropped_down_;
    if (pk.port == port::kLog && pk.channel == logp::kChanData) ++dropped_log_;
    return;
  }
  uint8_t wire[32];
  const size_t n = pk.encode(wire);
  down_.push_back(CrtpPacket::decode(wire, n));
}

void LoopbackLink::tick() {
  scratch_.clear();
  fw_.tick(now_ms_, scratch_);
  for (const auto& pk : scratch_) downlink(pk);
}

void LoopbackLink::send(const CrtpPacket& pk) {
  ++stats_.packets_sent;
  if (drop()) {
    ++dropped_up_;
    return;
  }
  uint8_t wire[32];
  const size_t n = pk.encode(wire);
  scratch_.clear();
  fw_.on_packet(CrtpPacket::decode(wire, n), now_ms_, scratch_);
  for (const auto& r : scratch_) downlink(r);
}

std::optional<CrtpPacket> LoopbackLink::receive(std::chrono::milliseconds) {
  if (down_.empty()) return std::nullopt;
  CrtpPacket pk = down_.front();
  down_.pop_front();
  ++stats_.packets_received;
  return pk;
}

}  // namespace crazyflie_bridge
