// CRTP links: UDP (one packet per datagram, cflib udpdriver / CrazySim),
// Crazyradio PA / 2.0 and Crazyflie USB through libusb. Synchronous and
// single-threaded: send() transmits, receive() waits up to a timeout (the
// radio polls the Crazyflie with null packets meanwhile, as cflib does).
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "crazyflie_bridge/crtp.hpp"
#include "crazyflie_bridge/radio.hpp"
#include "crazyflie_bridge/uri.hpp"

namespace crazyflie_bridge {

/// Link failures: device missing, busy, unplugged, socket errors. The message
/// names the URI / device and the reason.
class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LinkStatistics {
  uint64_t packets_sent = 0;       ///< CRTP packets handed to the link (not null polls)
  uint64_t packets_received = 0;   ///< CRTP packets delivered (not null packets)
  uint64_t null_received = 0;      ///< null packets received (UDP keep-alive / scan answers)
  uint64_t null_sent = 0;          ///< radio poll packets
  uint64_t acks = 0;               ///< radio: transfers acknowledged
  uint64_t ack_missing = 0;        ///< radio: transfers not acknowledged (after ARC retries)
  uint64_t retries = 0;            ///< radio: sum of the retry counts of the ACK status
  uint64_t safelink_out_of_sequence = 0;
  int uplink_rssi = -1;            ///< radio: last RSSI reported in an ACK (-dBm), -1 if none
  uint64_t rssi_reports = 0;
  uint64_t malformed = 0;          ///< datagrams that are not CRTP packets (dropped)
  uint64_t send_errors = 0;
  double ack_rate() const {
    const double n = static_cast<double>(acks + ack_missing);
    return n > 0 ? static_cast<double>(acks) / n : 1.0;
  }
};

class Link {
 public:
  virtual ~Link() = default;
  virtual void send(const CrtpPacket& pk) = 0;
  /// Next packet, waiting at most `timeout` (0: only what is already there).
  virtual std::optional<CrtpPacket> receive(std::chrono::milliseconds timeout) = 0;
  virtual const LinkStatistics& statistics() const = 0;
  virtual std::string uri() const = 0;
};

/// Opens the link a URI names. Throws UriError / LinkError.
std::unique_ptr<Link> open_link(const std::string& uri);

// ---------------------------------------------------------------------------
/// Ground side of a UDP link (cflib udpdriver): connected socket to host:port.
class UdpLink : public Link {
 public:
  explicit UdpLink(const LinkUri& uri);
  ~UdpLink() override;
  void send(const CrtpPacket& pk) override;
  std::optional<CrtpPacket> receive(std::chrono::milliseconds timeout) override;
  const LinkStatistics& statistics() const override { return stats_; }
  std::string uri() const override { return to_string(uri_); }
  /// Raw datagram (tests: handshake bytes, garbage).
  void send_raw(const uint8_t* data, size_t n);

 private:
  LinkUri uri_;
  int fd_ = -1;
  LinkStatistics stats_;
};

/// Firmware side of a UDP link: bound to a port, answers the last peer.
/// 0xF3 / 0xF4 single-byte datagrams (CrazySim connect / disconnect) are
/// reported through peer_events() and not delivered as packets.
class UdpServer {
 public:
  /// A client that sent nothing for this long gives the link up to the next one [ms]
  /// (our choice: 2.5 x the firmware's 2 s commander shutdown watchdog is well past any
  /// flight; a client that says goodbye (0xF4) gives it up at once).
  static constexpr int kPeerIdleMs = 5000;

  /// port 0 picks a free port (see port()). Throws LinkError (e.g. port busy).
  explicit UdpServer(uint16_t port, const std::string& bind_address = "127.0.0.1");
  ~UdpServer();
  UdpServer(const UdpServer&) = delete;
  UdpServer& operator=(const UdpServer&) = delete;
  uint16_t port() const { return port_; }
  /// Waits up to timeout for one datagram of the client that owns the link; returns a
  /// packet or nothing. Like a Crazyflie's radio, the link serves one client: the first
  /// sender of a handshake or CRTP packet owns it until it says goodbye (0xF4) or is idle
  /// for kPeerIdleMs. A null packet (0xFF: cflib's scan, `tactile scan`) from anyone else
  /// is answered to its sender and does not take the link; another sender's other
  /// datagrams are dropped and counted (foreign_datagrams()).
  std::optional<CrtpPacket> receive(std::chrono::microseconds timeout);
  /// Sends to the client that owns the link (dropped and counted if none yet).
  void send(const CrtpPacket& pk);
  const LinkStatistics& statistics() const { return stats_; }
  uint64_t connects() const { return connects_; }
  uint64_t disconnects() const { return disconnects_; }
  uint64_t foreign_datagrams() const { return foreign_; }
  bool has_peer() const { return has_peer_; }

 private:
  int fd_ = -1;
  uint16_t port_ = 0;
  bool has_peer_ = false;
  unsigned char peer_[128] = {};
  unsigned peer_len_ = 0;
  std::chrono::steady_clock::time_point peer_heard_{};
  uint64_t connects_ = 0, disconnects_ = 0, foreign_ = 0;
  LinkStatistics stats_;
};

// ---------------------------------------------------------------------------
/// One found device (tactile scan).
struct FoundDevice {
  std::string uri;
  std::string description;
};
/// Crazyradios and Crazyflies on USB (libusb) and simulated Crazyflies
/// answering a null packet on UDP ports 19850..19859 of `udp_host` (cflib
/// udpdriver.scan_interface). Radio channels are not scanned (a Crazyflie on
/// the air is found with its URI, e.g. from the cfclient).
std::vector<FoundDevice> scan(const std::string& udp_host = "127.0.0.1");

/// The LinkError message of a failed libusb call `what` with libusb error
/// code `rc` (LIBUSB_ERROR_*): the libusb name and text, and for a missing
/// permission, a busy device or an unplugged one what happened and what to do.
std::string usb_error_message(const std::string& what, int rc);

/// Crazyradio link (libusb). Throws LinkError when no dongle matches, the
/// dongle is claimed by another process (busy), or it is unplugged (any later
/// send/receive then throws).
class CrazyradioLink : public Link {
 public:
  explicit CrazyradioLink(const LinkUri& uri);
  ~CrazyradioLink() override;
  void send(const CrtpPacket& pk) override;
  std::optional<CrtpPacket> receive(std::chrono::milliseconds timeout) override;
  const LinkStatistics& statistics() const override { return stats_; }
  std::string uri() const override { return to_string(uri_); }
  uint16_t firmware_version_bcd() const { return version_; }

 private:
  /// One transfer (packet or null poll); queues any downlink packet.
  void transfer(const std::vector<uint8_t>& out);
  struct Usb;
  std::unique_ptr<Usb> usb_;
  LinkUri uri_;
  uint16_t version_ = 0;
  radio::SafeLink safelink_;
  int lost_in_a_row_ = 0;
  std::deque<CrtpPacket> in_;
  LinkStatistics stats_;
};

/// Crazyflie 2.x on USB (0x0483:0x5740): CRTP over bulk endpoints after the
/// vendor request that switches the firmware to CRTP-over-USB.
class CfUsbLink : public Link {
 public:
  explicit CfUsbLink(const LinkUri& uri);
  ~CfUsbLink() override;
  void send(const CrtpPacket& pk) override;
  std::optional<CrtpPacket> receive(std::chrono::milliseconds timeout) override;
  const LinkStatistics& statistics() const override { return stats_; }
  std::string uri() const override { return to_string(uri_); }

 private:
  struct Usb;
  std::unique_ptr<Usb> usb_;
  LinkUri uri_;
  LinkStatistics stats_;
};

}  // namespace crazyflie_bridge
