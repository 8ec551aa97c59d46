// CRTP (Crazy RealTime Protocol) packets: one header byte and up to 30 bytes
// of payload. Header = port << 4 | link bits (3..2) | channel (1..0), as in the
// Crazyflie firmware (crtp.h) and cflib (crtp/crtpstack.py). The two link
// bits are set to 1 for legacy bootloader support, exactly like cflib's
// CRTPPacket; the Crazyradio link overwrites them with the safelink toggle
// bits (radio.hpp). Header 0xFF with no payload is the null packet used to
// poll the radio (port 15, channel 3).
//
// Core layer: no ROS, no messages, no allocation per packet.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace crazyflie_bridge {

/// Malformed CRTP input; the message names the byte offset and the reason.
class CrtpError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// CRTP ports (cflib crtpstack.CRTPPort, firmware crtp.h).
namespace port {
constexpr uint8_t kConsole = 0x0;
constexpr uint8_t kParam = 0x2;
constexpr uint8_t kCommander = 0x3;
constexpr uint8_t kMem = 0x4;
constexpr uint8_t kLog = 0x5;
constexpr uint8_t kLocalization = 0x6;
constexpr uint8_t kCommanderGeneric = 0x7;
constexpr uint8_t kSetpointHl = 0x8;
constexpr uint8_t kSupervisor = 0x9;
constexpr uint8_t kPlatform = 0xD;
constexpr uint8_t kLinkCtrl = 0xF;
}  // namespace port

constexpr size_t kCrtpMaxPayload = 30;
constexpr uint8_t kNullHeader = 0xFF;
/// Bits 3..2 of the header: 1 for legacy support (cflib), safelink toggles on the radio.
constexpr uint8_t kLinkBits = 0x0C;

struct CrtpPacket {
  uint8_t port = 0;     ///< 0..15
  uint8_t channel = 0;  ///< 0..3
  uint8_t size = 0;     ///< payload bytes used, 0..30
  std::array<uint8_t, kCrtpMaxPayload> data{};

  CrtpPacket() = default;
  CrtpPacket(uint8_t port_, uint8_t channel_) : port(port_ & 0x0F), channel(channel_ & 0x03) {}
  CrtpPacket(uint8_t port_, uint8_t channel_, std::initializer_list<uint8_t> bytes);

  /// The null packet (header 0xFF, no payload).
  static CrtpPacket null_packet() { return CrtpPacket(0xF, 0x3); }
  bool is_null() const { return port == 0xF && channel == 0x3 && size == 0; }

  /// port << 4 | 0x0C | channel.
  uint8_t header() const { return static_cast<uint8_t>((port << 4) | kLinkBits | channel); }

  /// Appends little-endian values; throw CrtpError when the payload would exceed 30 bytes.
  CrtpPacket& u8(uint8_t v);
  CrtpPacket& u16(uint16_t v);
  CrtpPacket& u32(uint32_t v);
  CrtpPacket& f32(float v);
  CrtpPacket& bytes(const void* p, size_t n);
  size_t available() const { return kCrtpMaxPayload - size; }

  /// Wire form: header then payload (1..31 bytes); `out` must hold 31 bytes.
  size_t encode(uint8_t* out) const;
  std::vector<uint8_t> encode() const;

  /// Parses one wire packet (1..31 bytes). Throws CrtpError on an empty or
  /// oversized buffer. The link bits of the header are ignored.
  static CrtpPacket decode(const uint8_t* bytes, size_t n);
  /// As decode() without throwing.
  static std::optional<CrtpPacket> try_decode(const uint8_t* bytes, size_t n) noexcept;

  bool operator==(const CrtpPacket& o) const {
    return port == o.port && channel == o.channel && size == o.size &&
           std::memcmp(data.data(), o.data.data(), size) == 0;
  }
  bool operator!=(const CrtpPacket& o) const { return !(*this == o); }
  /// "port 5 ch 1 [03 01 02]" for logs and errors.
  std::string to_string() const;
};

/// Bounds-checked little-endian reader of a payload. Errors name `what`, the
/// byte offset and the number of bytes missing.
class PayloadReader {
 public:
  PayloadReader(const uint8_t* data, size_t size, const char* what) : p_(data), n_(size), what_(what) {}
  explicit PayloadReader(const CrtpPacket& pk, const char* what) : PayloadReader(pk.data.data(), pk.size, what) {}
  uint8_t u8();
  uint16_t u16();
  uint32_t u24();
  uint32_t u32();
  float f32();
  double f64();
  int8_t i8() { return static_cast<int8_t>(u8()); }
  int16_t i16() { return static_cast<int16_t>(u16()); }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  /// NUL-terminated string (the terminator is consumed).
  std::string cstring();
  size_t offset() const { return off_; }
  size_t remaining() const { return n_ - off_; }
  const uint8_t* here() const { return p_ + off_; }
  void skip(size_t k);

 private:
  void need(size_t k) const;
  const uint8_t* p_;
  size_t n_;
  size_t off_ = 0;
  const char* what_;
};

/// IEEE 754 half precision (the FP16 log/param type) <-> float.
float half_to_float(uint16_t h);
uint16_t float_to_half(float f);

}  // namespace crazyflie_bridge
