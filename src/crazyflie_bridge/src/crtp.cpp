#include "crazyflie_bridge/crtp.hpp"

#include <cmath>
#include <cstdio>

namespace crazyflie_bridge {

CrtpPacket::CrtpPacket(uint8_t port_, uint8_t channel_, std::initializer_list<uint8_t> b)
    : CrtpPacket(port_, channel_) {
  for (uint8_t v : b) u8(v);
}

CrtpPacket& CrtpPacket::bytes(const void* p, size_t n) {
  if (n > available()) {
    throw CrtpError("CRTP payload overflow: " + std::to_string(size) + " + " + std::to_string(n) +
                    " bytes > 30 (" + to_string() + ")");
  }
  std::memcpy(data.data() + size, p, n);
  size = static_cast<uint8_t>(size + n);
  return *this;
}

CrtpPacket& CrtpPacket::u8(uint8_t v) { return bytes(&v, 1); }
CrtpPacket& CrtpPacket::u16(uint16_t v) {
  const uint8_t b[2] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)};
  return bytes(b, 2);
}
CrtpPacket& CrtpPacket::u32(uint32_t v) {
  const uint8_t b[4] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v >> 16),
                        static_cast<uint8_t>(v >> 24)};
  return bytes(b, 4);
}
CrtpPacket& CrtpPacket::f32(float v) {
  uint32_t u;
  std::memcpy(&u, &v, 4);
  return u32(u);
}

size_t CrtpPacket::encode(uint8_t* out) const {
  out[0] = is_null() ? kNullHeader : header();
  std::memcpy(out + 1, data.data(), size);
  return size + 1u;
}

std::vector<uint8_t> CrtpPacket::encode() const {
  std::vector<uint8_t> v(size + 1u);
  encode(v.data());
  return v;
}

CrtpPacket CrtpPacket::decode(const uint8_t* b, size_t n) {
  if (n == 0 || b == nullptr) throw CrtpError("CRTP packet: byte 0: empty packet (no header)");
  if (n > kCrtpMaxPayload + 1) {
    throw CrtpError("CRTP packet: byte 31: " + std::to_string(n) + " bytes, at most 31 (header + 30)");
  }
  CrtpPacket p(static_cast<uint8_t>(b[0] >> 4), static_cast<uint8_t>(b[0] & 0x03));
  p.size = static_cast<uint8_t>(n - 1);
  std::memcpy(p.data.data(), b + 1, n - 1);
  return p;
}

std::optional<CrtpPacket> CrtpPacket::try_decode(const uint8_t* b, size_t n) noexcept {
  if (n == 0 || b == nullptr || n > kCrtpMaxPayload + 1) return std::nullopt;
  return decode(b, n);
}

std::string CrtpPacket::to_string() const {
  std::string s = "port " + std::to_string(port) + " ch " + std::to_string(channel) + " [";
  char buf[4];
  for (size_t i = 0; i < size; ++i) {
    std::snprintf(buf, sizeof buf, i ? " %02x" : "%02x", data[i]);
    s += buf;
  }
  return s + "]";
}

void PayloadReader::need(size_t k) const {
  if (off_ + k > n_) {
    throw CrtpError(std::string(what_) + ": byte " + std::to_string(off_) + ": truncated, need " +
                    std::to_string(k) + " byte(s), " + std::to_string(n_ - off_) + " left");
  }
}
void PayloadReader::skip(size_t k) {
  need(k);
  off_ += k;
}
uint8_t PayloadReader::u8() {
  need(1);
  return p_[off_++];
}
uint16_t PayloadReader::u16() {
  need(2);
  const uint16_t v = static_cast<uint16_t>(p_[off_] | (p_[off_ + 1] << 8));
  off_ += 2;
  return v;
}
uint32_t PayloadReader::u24() {
  need(3);
  const uint32_t v = static_cast<uint32_t>(p_[off_]) | (static_cast<uint32_t>(p_[off_ + 1]) << 8) |
                     (static_cast<uint32_t>(p_[off_ + 2]) << 16);
  off_ += 3;
  return v;
}
uint32_t PayloadReader::u32() {
  need(4);
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p_[off_ + static_cast<size_t>(i)];
  off_ += 4;
  return v;
}
float PayloadReader::f32() {
  const uint32_t u = u32();
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
double PayloadReader::f64() {
  need(8);
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p_[off_ + static_cast<size_t>(i)];
  off_ += 8;
  double d;
  std::memcpy(&d, &v, 8);
  return d;
}
std::string PayloadReader::cstring() {
  const size_t start = off_;
  while (off_ < n_ && p_[off_] != 0) ++off_;
  if (off_ >= n_) {
    throw CrtpError(std::string(what_) + ": byte " + std::to_string(start) + ": string not NUL-terminated");
  }
  std::string s(reinterpret_cast<const char*>(p_ + start), off_ - start);
  ++off_;
  return s;
}

float half_to_float(uint16_t h) {
  const int sign = (h >> 15) & 1;
  const int exp = (h >> 10) & 0x1F;
  const int mant = h & 0x3FF;
  double v;
  if (exp == 0) {
    v = std::ldexp(static_cast<double>(mant), -24);
  } else if (exp == 31) {
    v = mant ? NAN : INFINITY;
  } else {
    v = std::ldexp(static_cast<double>(mant | 0x400), exp - 25);
  }
  return static_cast<float>(sign ? -v : v);
}

uint16_t float_to_half(float f) {
  uint32_t x;
  std::memcpy(&x, &f, 4);
  const uint16_t sign = static_cast<uint16_t>((x >> 16) & 0x8000);
  const int exp = static_cast<int>((x >> 23) & 0xFF);
  uint32_t mant = x & 0x7FFFFF;
  if (exp == 0xFF) return static_cast<uint16_t>(sign | 0x7C00 | (mant ? 0x200 : 0));
  int e = exp - 127 + 15;
  if (e >= 31) return static_cast<uint16_t>(sign | 0x7C00);
  if (e <= 0) {
    if (e < -10) return sign;
    mant |= 0x800000;
    const int shift = 14 - e;
    uint32_t m = mant >> shift;
    const uint32_t rem = mant & ((1u << shift) - 1);
    const uint32_t half = 1u << (shift - 1);
    if (rem > half || (rem == half && (m & 1))) ++m;
    return static_cast<uint16_t>(sign | m);
  }
  uint32_t m = mant >> 13;
  const uint32_t rem = mant & 0x1FFF;
  uint32_t out = (static_cast<uint32_t>(e) << 10) | m;
  if (rem > 0x1000 || (rem == 0x1000 && (m & 1))) ++out;  // may carry into the exponent: correct
  return static_cast<uint16_t>(sign | out);
}

}  // namespace crazyflie_bridge
