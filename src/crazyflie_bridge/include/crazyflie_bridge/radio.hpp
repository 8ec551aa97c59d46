// Crazyradio PA / 2.0 protocol pieces that need no USB: vendor requests and
// the init sequence (cflib drivers/crazyradio.py), the ACK status byte of a
// bulk IN transfer, and safelink (cflib crtp/radiodriver.py
// _send_packet_safe): 1-bit up/down counters in header bits 3 and 2 so that
// no downlink payload is lost and no uplink packet is duplicated.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "crazyflie_bridge/uri.hpp"

namespace crazyflie_bridge::radio {

constexpr uint16_t kVendorId = 0x1915;
constexpr uint16_t kProductId = 0x7777;
constexpr uint16_t kCfUsbVendorId = 0x0483;  ///< Crazyflie 2.x on USB
constexpr uint16_t kCfUsbProductId = 0x5740;
constexpr uint8_t kEndpointOut = 0x01;
constexpr uint8_t kEndpointIn = 0x81;

// Vendor requests (bmRequestType 0x40, host to device)
constexpr uint8_t kSetRadioChannel = 0x01;
constexpr uint8_t kSetRadioAddress = 0x02;
constexpr uint8_t kSetDataRate = 0x03;
constexpr uint8_t kSetRadioPower = 0x04;
constexpr uint8_t kSetRadioArd = 0x05;
constexpr uint8_t kSetRadioArc = 0x06;
constexpr uint8_t kAckEnable = 0x10;
constexpr uint8_t kSetContCarrier = 0x20;
constexpr uint8_t kPower0dBm = 3;
constexpr int kDefaultArc = 3;           ///< cflib _nr_of_arc_retries
constexpr int kRetriesBeforeDisconnect = 100;  ///< cflib _nr_of_retries

struct VendorRequest {
  uint8_t request = 0;
  uint16_t value = 0;
  uint16_t index = 0;
  std::vector<uint8_t> data;
  bool operator==(const VendorRequest& o) const {
    return request == o.request && value == o.value && index == o.index && data == o.data;
  }
};

/// What cflib does when it opens a dongle (Crazyradio.__init__ for firmware
/// >= 0.4) and connects (RadioDriver.connect: channel, data rate, address,
/// ARC), with cflib's "only if changed" caching of channel/rate/address.
/// `version_bcd` is bcdDevice (0x0004 = 0.4 ... ).
std::vector<VendorRequest> init_sequence(uint16_t version_bcd, const LinkUri& uri);

/// Parsed status of one bulk IN transfer after a packet was sent.
struct AckStatus {
  bool ack = false;        ///< bit 0
  bool power_det = false;  ///< bit 1
  int retry = 0;           ///< bits 7..4 (ARC when byte 0 is 0)
  std::vector<uint8_t> data;  ///< downlink CRTP packet (may be empty)
};
/// `arc` is what cflib reports as retries when the status byte is 0.
AckStatus parse_ack(const uint8_t* in, size_t n, int arc = kDefaultArc);

/// Uplink RSSI carried by an empty link-control ACK (cflib
/// radio_link_statistics: data[0] & 0xF3 == 0xF3, data[1] == 0x01, RSSI =
/// data[2], the magnitude of the dBm value); nullopt when the ACK has none.
std::optional<int> uplink_rssi(const AckStatus& a);

/// The safelink enable request and its expected echo: FF 05 01.
constexpr std::array<uint8_t, 3> kSafelinkEnable{{0xFF, 0x05, 0x01}};
bool is_safelink_echo(const AckStatus& a);

class SafeLink {
 public:
  /// Before the handshake cflib starts with up = 0, down = 1; after it both are 0.
  void enable() { enabled_ = true, up_ = 0, down_ = 0; }
  bool enabled() const { return enabled_; }
  /// Header byte with bits 3..2 replaced by the counters (no-op when disabled).
  uint8_t apply(uint8_t header) const {
    return enabled_ ? static_cast<uint8_t>((header & 0xF3) | (up_ << 3) | (down_ << 2)) : header;
  }
  /// Updates the counters from the answer to a packet sent with apply(),
  /// exactly as cflib: down toggles when the answer carries data whose bit 2
  /// equals it, up toggles on every ACK. Returns false when data arrived with
  /// the other down bit (counted by the link; the data is still delivered,
  /// as cflib does).
  bool on_ack(const AckStatus& a);
  int up() const { return up_; }
  int down() const { return down_; }

 private:
  bool enabled_ = false;
  int up_ = 0, down_ = 1;
};

}  // namespace crazyflie_bridge::radio
