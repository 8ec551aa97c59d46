// CRTP services: encoders and decoders of the packets the ground station and
// the firmware exchange. Sources (byte layouts): cflib crazyflie/toc.py,
// log.py, param.py, commander.py, platformservice.py, mem/__init__.py,
// link_statistics.py; the firmware's log.c / param.c / crtp_commander_generic.c
// (documented in the Crazyflie firmware docs, "CRTP" pages).
// All multi-byte values are little endian. Decoders throw CrtpError naming the
// packet kind, the byte offset and the reason.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "crazyflie_bridge/crtp.hpp"

namespace crazyflie_bridge {

// ----------------------------------------------------------------------------
// TOC (log port 5 and param port 2, channel 0), protocol v2 (u16 ids)
namespace toc {
constexpr uint8_t kChannel = 0;
constexpr uint8_t kCmdElementV1 = 0;
constexpr uint8_t kCmdInfoV1 = 1;
constexpr uint8_t kCmdItemV2 = 2;
constexpr uint8_t kCmdInfoV2 = 3;

struct Info {
  uint16_t count = 0;
  uint32_t crc = 0;
  uint8_t max_packets = 0;  ///< log only (firmware LOG_MAX_BLOCKS); 0 if absent
  uint8_t max_ops = 0;      ///< log only (firmware LOG_MAX_OPS); 0 if absent
};
struct Item {
  uint16_t id = 0;
  uint8_t type_byte = 0;  ///< raw type/flags byte (log: type; param: type | flags)
  std::string group, name;
  std::string full_name() const { return group + "." + name; }
};

CrtpPacket info_request(uint8_t port);                 ///< [3]
CrtpPacket item_request(uint8_t port, uint16_t id);    ///< [2, id lo, id hi]
CrtpPacket info_reply(uint8_t port, const Info& info); ///< [3, count u16, crc u32, max_packets, max_ops]
CrtpPacket item_reply(uint8_t port, const Item& item); ///< [2, id u16, type, group\0, name\0]
Info decode_info(const CrtpPacket& pk);
Item decode_item(const CrtpPacket& pk);
/// CRC-32 (IEEE, as zlib) of a byte range; used by the simulated firmware to
/// identify its TOC (the client caches TOCs by this value).
uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc = 0);
}  // namespace toc

// ----------------------------------------------------------------------------
// Log (port 5): channel 1 = control, channel 2 = data
namespace logp {
constexpr uint8_t kChanToc = 0;
constexpr uint8_t kChanSettings = 1;
constexpr uint8_t kChanData = 2;
constexpr uint8_t kCmdCreateBlock = 0;
constexpr uint8_t kCmdAppendBlock = 1;
constexpr uint8_t kCmdDeleteBlock = 2;
constexpr uint8_t kCmdStartBlock = 3;  ///< period u8 in 10 ms units (what cflib sends)
constexpr uint8_t kCmdStopBlock = 4;
constexpr uint8_t kCmdReset = 5;
constexpr uint8_t kCmdCreateBlockV2 = 6;
constexpr uint8_t kCmdAppendBlockV2 = 7;
constexpr uint8_t kCmdStartBlockV2 = 8;  ///< period u16 in ms (firmware log.c)
constexpr size_t kMaxBlockBytes = 26;     ///< 30 - block id - 3-byte timestamp

/// Log variable types (cflib LogTocElement.types; firmware log.h).
enum class Type : uint8_t { kUint8 = 1, kUint16 = 2, kUint32 = 3, kInt8 = 4, kInt16 = 5, kInt32 = 6, kFloat = 7, kFP16 = 8 };
/// Size in bytes; throws CrtpError for an unknown type code.
size_t type_size(uint8_t type);
bool valid_type(uint8_t type);
const char* type_name(uint8_t type);

struct BlockVariable {
  uint16_t id = 0;   ///< TOC id
  Type fetch_as = Type::kFloat;
  Type stored_as = Type::kFloat;  ///< firmware storage type (cflib: same as fetch when not given)
};

/// Create (then append) packets of a v2 block: [6|7, block id, (stored<<4|fetch, id u16)...].
std::vector<CrtpPacket> create_block_v2(uint8_t block_id, const std::vector<BlockVariable>& vars);
CrtpPacket start_block_v1(uint8_t block_id, uint8_t period_10ms);  ///< [3, id, period/10 ms]
CrtpPacket start_block_v2(uint8_t block_id, uint16_t period_ms);   ///< [8, id, period u16]
CrtpPacket stop_block(uint8_t block_id);                           ///< [4, id]
CrtpPacket delete_block(uint8_t block_id);                         ///< [2, id]
CrtpPacket reset();                                                ///< [5]

/// Firmware answer on the control channel: [cmd, block id, status (0 or errno)].
struct ControlReply {
  uint8_t cmd = 0, block_id = 0, status = 0;
};
CrtpPacket control_reply(const ControlReply& r);
ControlReply decode_control_reply(const CrtpPacket& pk);

/// Log data: [block id, timestamp u24 (ms), values...].
struct Data {
  uint8_t block_id = 0;
  uint32_t timestamp_ms = 0;  ///< 24-bit firmware tick, wraps every 4.66 h
  std::array<uint8_t, kCrtpMaxPayload> values{};  ///< copied: Data outlives the packet
  size_t values_size = 0;
};
Data decode_data(const CrtpPacket& pk);
/// Values of `data` fetched as `types`, as doubles. Throws CrtpError when the
/// payload is shorter than the types need (trailing bytes are an error too).
void decode_values(const Data& data, const std::vector<Type>& types, std::vector<double>& out);
/// Firmware side: [block id, t u24, values] from doubles converted to `types`.
CrtpPacket data_packet(uint8_t block_id, uint32_t timestamp_ms, const std::vector<Type>& types,
                       const std::vector<double>& values);
/// Appends one value converted to `type` (saturating integers, FP16 rounding).
void append_value(CrtpPacket& pk, Type type, double value);
double read_value(PayloadReader& r, Type type);
}  // namespace logp

// ----------------------------------------------------------------------------
// Param (port 2): 0 = TOC, 1 = read, 2 = write, 3 = misc
namespace param {
constexpr uint8_t kChanToc = 0;
constexpr uint8_t kChanRead = 1;
constexpr uint8_t kChanWrite = 2;
constexpr uint8_t kChanMisc = 3;
/// Type codes (cflib ParamTocElement.types): low nibble of the TOC type byte.
constexpr uint8_t kInt8 = 0x00, kInt16 = 0x01, kInt32 = 0x02, kInt64 = 0x03, kFP16 = 0x05, kFloat = 0x06,
                  kDouble = 0x07, kUint8 = 0x08, kUint16 = 0x09, kUint32 = 0x0A, kUint64 = 0x0B;
constexpr uint8_t kFlagExtended = 0x10;
constexpr uint8_t kFlagReadOnly = 0x40;
size_t type_size(uint8_t type);  ///< low nibble; throws CrtpError for unknown codes
bool valid_type(uint8_t type);
bool is_float_type(uint8_t type);

CrtpPacket read_request(uint16_t id);  ///< ch 1: [id u16]
/// ch 1 reply: [id u16, status, value]; status 0 = ok.
struct ReadReply {
  uint16_t id = 0;
  uint8_t status = 0;
  double value = 0;
};
CrtpPacket read_reply(uint16_t id, uint8_t type, double value, uint8_t status = 0);
/// Decodes with the TOC type of the id (use reply_id() first to look it up).
ReadReply decode_read_reply(const CrtpPacket& pk, uint8_t type);
uint16_t reply_id(const CrtpPacket& pk);  ///< id u16 at byte 0 of read/write packets

CrtpPacket write_request(uint16_t id, uint8_t type, double value);  ///< ch 2: [id u16, value]
struct WriteRequest {
  uint16_t id = 0;
  double value = 0;
};
/// Firmware side; the reply is the request echoed (param.c).
WriteRequest decode_write(const CrtpPacket& pk, uint8_t type);
void append_value(CrtpPacket& pk, uint8_t type, double value);
double read_value(PayloadReader& r, uint8_t type);
}  // namespace param

// ----------------------------------------------------------------------------
// Generic commander (port 7): channel 0 setpoints, channel 1 meta commands
namespace commander {
constexpr uint8_t kChanSetpoint = 0;
constexpr uint8_t kChanMeta = 1;
constexpr uint8_t kTypeStop = 0;
constexpr uint8_t kTypeHoverLegacy = 5;  ///< yaw rate negated (protocol <= 8)
constexpr uint8_t kTypePosition = 7;
constexpr uint8_t kTypeVelocityWorld = 8;
constexpr uint8_t kTypeHover = 10;
constexpr uint8_t kMetaNotifySetpointStop = 0;

/// Hover: vx, vy [m/s] body-yaw frame, yaw rate [deg/s] (CCW positive in type
/// 10), height [m]: [10, f32 x4] (cflib send_hover_setpoint).
CrtpPacket hover(float vx, float vy, float yaw_rate_deg, float z);
CrtpPacket velocity_world(float vx, float vy, float vz, float yaw_rate_deg);  ///< [8, f32 x4]
CrtpPacket position(float x, float y, float z, float yaw_deg);                ///< [7, f32 x4]
CrtpPacket stop();                                                             ///< [0]
CrtpPacket notify_setpoint_stop(uint32_t remain_valid_ms);                     ///< ch 1: [0, u32]

struct Setpoint {
  enum class Kind { kStop, kHover, kVelocityWorld, kPosition, kNotifyStop, kOther };
  Kind kind = Kind::kOther;
  uint8_t type = 0;
  float a = 0, b = 0, c = 0, d = 0;  ///< hover: vx vy yawrate(deg/s, CCW) z; vel: vx vy vz yawrate; pos: x y z yaw
  uint32_t remain_valid_ms = 0;      ///< notify stop
};
/// Decodes port 7 packets (legacy hover 5 is converted to the type-10 sign).
Setpoint decode(const CrtpPacket& pk);
}  // namespace commander

// ----------------------------------------------------------------------------
// Platform (port 13) and link control (port 15)
namespace platform {
constexpr uint8_t kChanCommand = 0;
constexpr uint8_t kChanVersion = 1;
constexpr uint8_t kVersionGetProtocol = 0;
constexpr uint8_t kVersionGetFirmware = 1;
constexpr uint8_t kVersionGetDeviceType = 2;
constexpr uint8_t kLinkChanEcho = 0;
constexpr uint8_t kLinkChanSource = 1;
constexpr uint8_t kLinkChanSink = 2;
constexpr const char* kSourceMagic = "Bitcraze Crazyflie";

CrtpPacket link_source_request();                         ///< port 15 ch 1: [0]
CrtpPacket link_source_reply();                           ///< "Bitcraze Crazyflie" (18 bytes)
CrtpPacket protocol_version_request();                    ///< port 13 ch 1: [0]
CrtpPacket protocol_version_reply(uint8_t version);       ///< [0, version]
/// Protocol version from a reply; throws if the packet is not one.
uint8_t decode_protocol_version(const CrtpPacket& pk);
CrtpPacket firmware_version_request();                    ///< [1]
CrtpPacket firmware_version_reply(const std::string& v);  ///< [1, text]
}  // namespace platform

// ----------------------------------------------------------------------------
// Memory (port 4): the simulated firmware answers "0 memories".
namespace mem {
constexpr uint8_t kChanInfo = 0;
constexpr uint8_t kCmdInfoNbr = 1;
CrtpPacket count_request();             ///< [1]
CrtpPacket count_reply(uint8_t count);  ///< [1, count]
}  // namespace mem

// ----------------------------------------------------------------------------
// Arming (cflib crazyflie/supervisor.py Supervisor.send_arming_request):
// CRTP protocol >= 12: supervisor port 9, channel 1 (SUPERVISOR_CH_COMMAND),
// [CMD_ARM_SYSTEM = 0x01, do_arm]; older firmware: the legacy platform port 13,
// channel 0 (PLATFORM_COMMAND), [PLATFORM_REQUEST_ARMING = 1, do_arm]
// (cflib crazyflie/platformservice.py).
namespace arming {
constexpr uint8_t kSupervisorProtocolVersion = 12;  ///< cflib Supervisor._is_legacy_firmware: version < 12
constexpr uint8_t kSupervisorChanCommand = 1;
constexpr uint8_t kCmdArmSystem = 0x01;
constexpr uint8_t kPlatformRequestArming = 1;
/// The arming request cflib sends to a firmware of `protocol_version`.
CrtpPacket request(bool arm, uint8_t protocol_version);
/// Firmware side: is `pk` an arming request (either generation)? Sets `arm`.
bool decode_request(const CrtpPacket& pk, bool& arm);
}  // namespace arming

}  // namespace crazyflie_bridge
