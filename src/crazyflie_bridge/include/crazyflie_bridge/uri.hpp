// Link URIs, parsed exactly like cflib (crtp/radiodriver.py parse_uri,
// crtp/usbdriver.py, crtp/udpdriver.py):
//   radio://<devid or serial>[/<channel>[/<250K|1M|2M>[/<address hex>]]][?safelink=0|1&rate_limit=N]
//   usb://<devid>
//   udp://<host>:<port>[?handshake=1]
// Radio defaults as cflib: channel 2, 2M, address E7E7E7E7E7 (hex digits
// left-padded with zeros to 10, first pair = first address byte).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace crazyflie_bridge {

class UriError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class DataRate : uint8_t { k250K = 0, k1M = 1, k2M = 2 };  ///< Crazyradio SET_DATA_RATE values

struct LinkUri {
  enum class Kind { kRadio, kUsb, kUdp };
  Kind kind = Kind::kUdp;
  std::string text;  ///< the URI as given
  // radio / usb
  int devid = 0;            ///< index of the dongle or Crazyflie (-1 when `serial` names it)
  std::string serial;       ///< radio given by serial number (upper case)
  int channel = 2;          ///< 0..125
  DataRate datarate = DataRate::k2M;
  std::array<uint8_t, 5> address{{0xE7, 0xE7, 0xE7, 0xE7, 0xE7}};
  bool safelink = true;     ///< try to enable safelink (cflib always tries)
  std::optional<int> rate_limit;  ///< packets/s (cflib rate_limit)
  // udp
  std::string host;
  uint16_t port = 0;
  bool handshake = false;   ///< send 0xF3 on connect / 0xF4 on close (CrazySim)
};

/// Throws UriError naming the URI, the part and the reason.
LinkUri parse_uri(const std::string& uri);
/// Canonical text (radio addresses in upper-case hex, all parts present).
std::string to_string(const LinkUri& uri);
const char* to_string(DataRate r);

}  // namespace crazyflie_bridge
