#include "crazyflie_bridge/protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace crazyflie_bridge {
namespace {

template <class T>
T saturate(double v) {
  if (!std::isfinite(v)) return 0;
  const double lo = static_cast<double>(std::numeric_limits<T>::lowest());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::clamp(std::round(v), lo, hi));
}

void expect_port(const CrtpPacket& pk, uint8_t port, uint8_t channel, const char* what) {
  if (pk.port != port || pk.channel != channel) {
    throw CrtpError(std::string(what) + ": header: expected port " + std::to_string(port) + " channel " +
                    std::to_string(channel) + ", got " + pk.to_string());
  }
}

}  // namespace

// ---------------------------------------------------------------------------
namespace toc {

CrtpPacket info_request(uint8_t port) { return CrtpPacket(port, kChannel, {kCmdInfoV2}); }
CrtpPacket item_request(uint8_t port, uint16_t id) {
  return CrtpPacket(port, kChannel, {kCmdItemV2, static_cast<uint8_t>(id & 0xFF), static_cast<uint8_t>(id >> 8)});
}
CrtpPacket info_reply(uint8_t port, const Info& info) {
  CrtpPacket pk(port, kChannel);
  pk.u8(kCmdInfoV2).u16(info.count).u32(info.crc).u8(info.max_packets).u8(info.max_ops);
  return pk;
}
CrtpPacket item_reply(uint8_t port, const Item& item) {
  CrtpPacket pk(port, kChannel);
  pk.u8(kCmdItemV2).u16(item.id).u8(item.type_byte);
  pk.bytes(item.group.c_str(), item.group.size() + 1);
  pk.bytes(item.name.c_str(), item.name.size() + 1);
  return pk;
}
Info decode_info(const CrtpPacket& pk) {
  PayloadReader r(pk, "TOC info reply");
  if (pk.channel != kChannel) throw CrtpError("TOC info reply: header: channel " + std::to_string(pk.channel) + ", expected 0");
  const uint8_t cmd = r.u8();
  if (cmd != kCmdInfoV2) throw CrtpError("TOC info reply: byte 0: command " + std::to_string(cmd) + ", expected 3 (info v2)");
  Info info;
  info.count = r.u16();
  info.crc = r.u32();
  if (r.remaining() >= 2) {
    info.max_packets = r.u8();
    info.max_ops = r.u8();
  }
  return info;
}
Item decode_item(const CrtpPacket& pk) {
  PayloadReader r(pk, "TOC item reply");
  if (pk.channel != kChannel) throw CrtpError("TOC item reply: header: channel " + std::to_string(pk.channel) + ", expected 0");
  const uint8_t cmd = r.u8();
  if (cmd != kCmdItemV2) throw CrtpError("TOC item reply: byte 0: command " + std::to_string(cmd) + ", expected 2 (item v2)");
  Item it;
  it.id = r.u16();
  it.type_byte = r.u8();
  it.group = r.cstring();
  it.name = r.cstring();
  return it;
}
uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc) {
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

}  // namespace toc

// ---------------------------------------------------------------------------
namespace logp {

bool valid_type(uint8_t t) { return t >= 1 && t <= 8; }
size_t type_size(uint8_t t) {
  switch (t) {
    case 1: case 4: return 1;
    case 2: case 5: case 8: return 2;
    case 3: case 6: case 7: return 4;
    default: throw CrtpError("log variable type " + std::to_string(t) + ": unknown (valid 1..8)");
  }
}
const char* type_name(uint8_t t) {
  static const char* names[] = {"?", "uint8_t", "uint16_t", "uint32_t", "int8_t", "int16_t", "int32_t", "float", "FP16"};
  return valid_type(t) ? names[t] : "?";
}

std::vector<CrtpPacket> create_block_v2(uint8_t block_id, const std::vector<BlockVariable>& vars) {
  std::vector<CrtpPacket> out;
  CrtpPacket pk(port::kLog, kChanSettings, {kCmdCreateBlockV2, block_id});
  for (const auto& v : vars) {
    if (pk.available() < 3) {  // cflib: a full packet continues with APPEND
      out.push_back(pk);
      pk = CrtpPacket(port::kLog, kChanSettings, {kCmdAppendBlockV2, block_id});
    }
    pk.u8(static_cast<uint8_t>(static_cast<uint8_t>(v.fetch_as) | (static_cast<uint8_t>(v.stored_as) << 4)));
    pk.u16(v.id);
  }
  out.push_back(pk);
  return out;
}
CrtpPacket start_block_v1(uint8_t block_id, uint8_t period_10ms) {
  return CrtpPacket(port::kLog, kChanSettings, {kCmdStartBlock, block_id, period_10ms});
}
CrtpPacket start_block_v2(uint8_t block_id, uint16_t period_ms) {
  CrtpPacket pk(port::kLog, kChanSettings, {kCmdStartBlockV2, block_id});
  pk.u16(period_ms);
  return pk;
}
CrtpPacket stop_block(uint8_t block_id) { return CrtpPacket(port::kLog, kChanSettings, {kCmdStopBlock, block_id}); }
CrtpPacket delete_block(uint8_t block_id) { return CrtpPacket(port::kLog, kChanSettings, {kCmdDeleteBlock, block_id}); }
CrtpPacket reset() { return CrtpPacket(port::kLog, kChanSettings, {kCmdReset}); }

CrtpPacket control_reply(const ControlReply& r) {
  return CrtpPacket(port::kLog, kChanSettings, {r.cmd, r.block_id, r.status});
}
ControlReply decode_control_reply(const CrtpPacket& pk) {
  expect_port(pk, port::kLog, kChanSettings, "log control reply");
  PayloadReader r(pk, "log control reply");
  ControlReply c;
  c.cmd = r.u8();
  c.block_id = r.u8();
  c.status = r.u8();
  return c;
}

Data decode_data(const CrtpPacket& pk) {
  expect_port(pk, port::kLog, kChanData, "log data");
  PayloadReader r(pk, "log data");
  Data d;
  d.block_id = r.u8();
  d.timestamp_ms = r.u24();
  d.values_size = r.remaining();
  std::memcpy(d.values.data(), r.here(), d.values_size);
  return d;
}

double read_value(PayloadReader& r, Type type) {
  switch (type) {
    case Type::kUint8: return r.u8();
    case Type::kUint16: return r.u16();
    case Type::kUint32: return r.u32();
    case Type::kInt8: return r.i8();
    case Type::kInt16: return r.i16();
    case Type::kInt32: return r.i32();
    case Type::kFloat: return r.f32();
    case Type::kFP16: return half_to_float(r.u16());
  }
  throw CrtpError("log value: unknown type " + std::to_string(static_cast<int>(type)));
}

void decode_values(const Data& data, const std::vector<Type>& types, std::vector<double>& out) {
  out.clear();
  PayloadReader r(data.values.data(), data.values_size, "log data values");
  for (Type t : types) out.push_back(read_value(r, t));
  if (r.remaining() != 0) {
    throw CrtpError("log data values: byte " + std::to_string(r.offset()) + ": " + std::to_string(r.remaining()) +
                    " trailing byte(s) for block " + std::to_string(data.block_id) + " (layout mismatch)");
  }
}

void append_value(CrtpPacket& pk, Type type, double v) {
  switch (type) {
    case Type::kUint8: pk.u8(saturate<uint8_t>(v)); return;
    case Type::kUint16: pk.u16(saturate<uint16_t>(v)); return;
    case Type::kUint32: pk.u32(saturate<uint32_t>(v)); return;
    case Type::kInt8: pk.u8(static_cast<uint8_t>(saturate<int8_t>(v))); return;
    case Type::kInt16: pk.u16(static_cast<uint16_t>(saturate<int16_t>(v))); return;
    case Type::kInt32: pk.u32(static_cast<uint32_t>(saturate<int32_t>(v))); return;
    case Type::kFloat: pk.f32(static_cast<float>(v)); return;
    case Type::kFP16: pk.u16(float_to_half(static_cast<float>(v))); return;
  }
  throw CrtpError("log value: unknown type " + std::to_string(static_cast<int>(type)));
}

CrtpPacket data_packet(uint8_t block_id, uint32_t timestamp_ms, const std::vector<Type>& types,
                       const std::vector<double>& values) {
  CrtpPacket pk(port::kLog, kChanData);
  pk.u8(block_id);
  pk.u8(static_cast<uint8_t>(timestamp_ms)).u8(static_cast<uint8_t>(timestamp_ms >> 8)).u8(static_cast<uint8_t>(timestamp_ms >> 16));
  for (size_t i = 0; i < types.size(); ++i) append_value(pk, types[i], i < values.size() ? values[i] : 0.0);
  return pk;
}

}  // namespace logp

// ---------------------------------------------------------------------------
namespace param {

bool valid_type(uint8_t t) {
  t &= 0x0F;
  return t != 0x04 && t <= 0x0B;
}
bool is_float_type(uint8_t t) {
  t &= 0x0F;
  return t == kFP16 || t == kFloat || t == kDouble;
}
size_t type_size(uint8_t t) {
  switch (t & 0x0F) {
    case kInt8: case kUint8: return 1;
    case kInt16: case kUint16: case kFP16: return 2;
    case kInt32: case kUint32: case kFloat: return 4;
    case kInt64: case kUint64: case kDouble: return 8;
    default: throw CrtpError("param type " + std::to_string(t & 0x0F) + ": unknown");
  }
}

void append_value(CrtpPacket& pk, uint8_t type, double v) {
  switch (type & 0x0F) {
    case kInt8: pk.u8(static_cast<uint8_t>(saturate<int8_t>(v))); return;
    case kInt16: pk.u16(static_cast<uint16_t>(saturate<int16_t>(v))); return;
    case kInt32: pk.u32(static_cast<uint32_t>(saturate<int32_t>(v))); return;
    case kInt64: {
      const auto x = static_cast<uint64_t>(saturate<int64_t>(v));
      pk.u32(static_cast<uint32_t>(x)).u32(static_cast<uint32_t>(x >> 32));
      return;
    }
    case kUint8: pk.u8(saturate<uint8_t>(v)); return;
    case kUint16: pk.u16(saturate<uint16_t>(v)); return;
    case kUint32: pk.u32(saturate<uint32_t>(v)); return;
    case kUint64: {
      const auto x = saturate<uint64_t>(v);
      pk.u32(static_cast<uint32_t>(x)).u32(static_cast<uint32_t>(x >> 32));
      return;
    }
    case kFP16: pk.u16(float_to_half(static_cast<float>(v))); return;
    case kFloat: pk.f32(static_cast<float>(v)); return;
    case kDouble: {
      uint64_t x;
      std::memcpy(&x, &v, 8);
      pk.u32(static_cast<uint32_t>(x)).u32(static_cast<uint32_t>(x >> 32));
      return;
    }
    default: throw CrtpError("param value: unknown type " + std::to_string(type & 0x0F));
  }
}

double read_value(PayloadReader& r, uint8_t type) {
  switch (type & 0x0F) {
    case kInt8: return r.i8();
    case kInt16: return r.i16();
    case kInt32: return r.i32();
    case kInt64: {
      const uint64_t lo = r.u32();
      const uint64_t hi = r.u32();
      return static_cast<double>(static_cast<int64_t>(lo | (hi << 32)));
    }
    case kUint8: return r.u8();
    case kUint16: return r.u16();
    case kUint32: return r.u32();
    case kUint64: {
      const uint64_t lo = r.u32();
      const uint64_t hi = r.u32();
      return static_cast<double>(lo | (hi << 32));
    }
    case kFP16: return half_to_float(r.u16());
    case kFloat: return r.f32();
    case kDouble: return r.f64();
    default: throw CrtpError("param value: unknown type " + std::to_string(type & 0x0F));
  }
}

CrtpPacket read_request(uint16_t id) {
  CrtpPacket pk(port::kParam, kChanRead);
  pk.u16(id);
  return pk;
}
CrtpPacket read_reply(uint16_t id, uint8_t type, double value, uint8_t status) {
  CrtpPacket pk(port::kParam, kChanRead);
  pk.u16(id).u8(status);
  if (status == 0) append_value(pk, type, value);
  return pk;
}
uint16_t reply_id(const CrtpPacket& pk) {
  PayloadReader r(pk, "param reply");
  return r.u16();
}
ReadReply decode_read_reply(const CrtpPacket& pk, uint8_t type) {
  expect_port(pk, port::kParam, kChanRead, "param read reply");
  PayloadReader r(pk, "param read reply");
  ReadReply rr;
  rr.id = r.u16();
  rr.status = r.u8();
  if (rr.status == 0) rr.value = read_value(r, type);
  return rr;
}
CrtpPacket write_request(uint16_t id, uint8_t type, double value) {
  CrtpPacket pk(port::kParam, kChanWrite);
  pk.u16(id);
  append_value(pk, type, value);
  return pk;
}
WriteRequest decode_write(const CrtpPacket& pk, uint8_t type) {
  expect_port(pk, port::kParam, kChanWrite, "param write");
  PayloadReader r(pk, "param write");
  WriteRequest w;
  w.id = r.u16();
  w.value = read_value(r, type);
  return w;
}

}  // namespace param

// ---------------------------------------------------------------------------
namespace commander {
namespace {
CrtpPacket four(uint8_t type, float a, float b, float c, float d) {
  CrtpPacket pk(port::kCommanderGeneric, kChanSetpoint);
  pk.u8(type).f32(a).f32(b).f32(c).f32(d);
  return pk;
}
}  // namespace
CrtpPacket hover(float vx, float vy, float yaw_rate_deg, float z) { return four(kTypeHover, vx, vy, yaw_rate_deg, z); }
CrtpPacket velocity_world(float vx, float vy, float vz, float yr) { return four(kTypeVelocityWorld, vx, vy, vz, yr); }
CrtpPacket position(float x, float y, float z, float yaw) { return four(kTypePosition, x, y, z, yaw); }
CrtpPacket stop() { return CrtpPacket(port::kCommanderGeneric, kChanSetpoint, {kTypeStop}); }
CrtpPacket notify_setpoint_stop(uint32_t remain_valid_ms) {
  CrtpPacket pk(port::kCommanderGeneric, kChanMeta);
  pk.u8(kMetaNotifySetpointStop).u32(remain_valid_ms);
  return pk;
}

Setpoint decode(const CrtpPacket& pk) {
  if (pk.port != port::kCommanderGeneric) throw CrtpError("generic setpoint: header: not port 7: " + pk.to_string());
  PayloadReader r(pk, "generic setpoint");
  Setpoint s;
  s.type = r.u8();
  if (pk.channel == kChanMeta) {
    if (s.type != kMetaNotifySetpointStop) return s;
    s.kind = Setpoint::Kind::kNotifyStop;
    s.remain_valid_ms = r.u32();
    return s;
  }
  if (pk.channel != kChanSetpoint) return s;
  switch (s.type) {
    case kTypeStop: s.kind = Setpoint::Kind::kStop; return s;
    case kTypeHover: case kTypeHoverLegacy: s.kind = Setpoint::Kind::kHover; break;
    case kTypeVelocityWorld: s.kind = Setpoint::Kind::kVelocityWorld; break;
    case kTypePosition: s.kind = Setpoint::Kind::kPosition; break;
    default: return s;
  }
  s.a = r.f32();
  s.b = r.f32();
  s.c = r.f32();
  s.d = r.f32();
  if (s.type == kTypeHoverLegacy) s.c = -s.c;  // cflib sends -yawrate for type 5
  return s;
}
}  // namespace commander

// ---------------------------------------------------------------------------
namespace platform {
CrtpPacket link_source_request() { return CrtpPacket(port::kLinkCtrl, kLinkChanSource, {0}); }
CrtpPacket link_source_reply() {
  CrtpPacket pk(port::kLinkCtrl, kLinkChanSource);
  pk.bytes(kSourceMagic, 18);
  return pk;
}
CrtpPacket protocol_version_request() { return CrtpPacket(port::kPlatform, kChanVersion, {kVersionGetProtocol}); }
CrtpPacket protocol_version_reply(uint8_t v) { return CrtpPacket(port::kPlatform, kChanVersion, {kVersionGetProtocol, v}); }
uint8_t decode_protocol_version(const CrtpPacket& pk) {
  expect_port(pk, port::kPlatform, kChanVersion, "protocol version reply");
  PayloadReader r(pk, "protocol version reply");
  const uint8_t cmd = r.u8();
  if (cmd != kVersionGetProtocol) throw CrtpError("protocol version reply: byte 0: command " + std::to_string(cmd) + ", expected 0");
  return r.u8();
}
CrtpPacket firmware_version_request() { return CrtpPacket(port::kPlatform, kChanVersion, {kVersionGetFirmware}); }
CrtpPacket firmware_version_reply(const std::string& v) {
  CrtpPacket pk(port::kPlatform, kChanVersion, {kVersionGetFirmware});
  pk.bytes(v.data(), std::min(v.size(), pk.available()));
  return pk;
}
}  // namespace platform

namespace mem {
CrtpPacket count_request() { return CrtpPacket(port::kMem, kChanInfo, {kCmdInfoNbr}); }
CrtpPacket count_reply(uint8_t count) { return CrtpPacket(port::kMem, kChanInfo, {kCmdInfoNbr, count}); }
}  // namespace mem

namespace arming {
CrtpPacket request(bool arm, uint8_t protocol_version) {
  const uint8_t on = arm ? 1 : 0;
  if (protocol_version >= kSupervisorProtocolVersion) {
    return CrtpPacket(port::kSupervisor, kSupervisorChanCommand, {kCmdArmSystem, on});
  }
  return CrtpPacket(port::kPlatform, platform::kChanCommand, {kPlatformRequestArming, on});
}
bool decode_request(const CrtpPacket& pk, bool& arm) {
  const bool supervisor = pk.port == port::kSupervisor && pk.channel == kSupervisorChanCommand && pk.size >= 2 &&
                          pk.data[0] == kCmdArmSystem;
  const bool legacy = pk.port == port::kPlatform && pk.channel == platform::kChanCommand && pk.size >= 2 &&
                      pk.data[0] == kPlatformRequestArming;
  if (!supervisor && !legacy) return false;
  arm = pk.data[1] != 0;
  return true;
}
}  // namespace arming

}  // namespace crazyflie_bridge
