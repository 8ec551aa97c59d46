#include "crazyflie_bridge/radio.hpp"

namespace crazyflie_bridge::radio {

std::vector<VendorRequest> init_sequence(uint16_t version_bcd, const LinkUri& uri) {
  std::vector<VendorRequest> seq;
  // Crazyradio.__init__: data rate 2M, channel 2 (current_* cache starts empty).
  seq.push_back({kSetDataRate, static_cast<uint16_t>(DataRate::k2M), 0, {}});
  seq.push_back({kSetRadioChannel, 2, 0, {}});
  const bool v04 = version_bcd >= 0x0004;
  if (v04) {
    seq.push_back({kSetContCarrier, 0, 0, {}});
    seq.push_back({kSetRadioAddress, 0, 0, {0xE7, 0xE7, 0xE7, 0xE7, 0xE7}});
    seq.push_back({kSetRadioPower, kPower0dBm, 0, {}});
    seq.push_back({kSetRadioArc, kDefaultArc, 0, {}});
    seq.push_back({kSetRadioArd, 0x80 | 32, 0, {}});  // set_ard_bytes(32)
    seq.push_back({kAckEnable, 1, 0, {}});
  }
  // RadioDriver.connect: set_channel, set_data_rate, set_address (cached), then ARC.
  if (uri.channel != 2) seq.push_back({kSetRadioChannel, static_cast<uint16_t>(uri.channel), 0, {}});
  if (uri.datarate != DataRate::k2M) seq.push_back({kSetDataRate, static_cast<uint16_t>(uri.datarate), 0, {}});
  const std::array<uint8_t, 5> def{{0xE7, 0xE7, 0xE7, 0xE7, 0xE7}};
  if (!v04 || uri.address != def) {
    seq.push_back({kSetRadioAddress, 0, 0, std::vector<uint8_t>(uri.address.begin(), uri.address.end())});
  }
  if (v04) seq.push_back({kSetRadioArc, kDefaultArc, 0, {}});
  return seq;
}

AckStatus parse_ack(const uint8_t* in, size_t n, int arc) {
  AckStatus a;
  if (n == 0) {
    a.retry = arc;
    return a;
  }
  if (in[0] != 0) {
    a.ack = (in[0] & 0x01) != 0;
    a.power_det = (in[0] & 0x02) != 0;
    a.retry = in[0] >> 4;
    a.data.assign(in + 1, in + n);
  } else {
    a.retry = arc;
  }
  return a;
}

std::optional<int> uplink_rssi(const AckStatus& a) {
  if (a.ack && a.data.size() > 2 && (a.data[0] & 0xF3) == 0xF3 && a.data[1] == 0x01) return a.data[2];
  return std::nullopt;
}

bool is_safelink_echo(const AckStatus& a) {
  return a.ack && a.data.size() == 3 && a.data[0] == 0xFF && a.data[1] == 0x05 && a.data[2] == 0x01;
}

bool SafeLink::on_ack(const AckStatus& a) {
  if (!enabled_) return true;
  bool in_sequence = true;
  if (a.ack && !a.data.empty()) {
    if ((a.data[0] & 0x04) == (down_ << 2)) {
      down_ = 1 - down_;
    } else {
      in_sequence = false;
    }
  }
  if (a.ack) up_ = 1 - up_;
  return in_sequence;
}

}  // namespace crazyflie_bridge::radio
