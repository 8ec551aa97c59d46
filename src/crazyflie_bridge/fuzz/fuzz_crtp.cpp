// libFuzzer harness of the CRTP decoders: arbitrary bytes as a wire packet,
// then through the log-data, TOC, param, commander and platform decoders and
// the firmware emulator. Decoding must succeed or throw CrtpError: no crash,
// no sanitizer report. Build: -DCRAZYFLIE_BRIDGE_FUZZ=ON with CXX=clang++
// (scripts/fuzz.sh).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "crazyflie_bridge/firmware.hpp"
#include "crazyflie_bridge/protocol.hpp"

using namespace crazyflie_bridge;

namespace {
FirmwareEmulator& firmware() {
  static FirmwareEmulator fw = [] {
    FirmwareEmulator f;
    f.add_log_variable("a", "f", logp::Type::kFloat);
    f.add_log_variable("a", "h", logp::Type::kFP16);
    f.add_log_variable("a", "i", logp::Type::kInt8);
    f.add_param("p", "u8", param::kUint8, 1, false);
    f.add_param("p", "d", param::kDouble, 1, false);
    f.add_param("p", "ro", param::kInt64, 1, true);
    return f;
  }();
  return fw;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  // First byte selects the log layout (types 1..8, up to 6 values).
  std::vector<logp::Type> layout;
  for (size_t i = 0; i < (data[0] & 0x07) && i + 1 < size; ++i) {
    layout.push_back(static_cast<logp::Type>(1 + data[1 + i] % 8));
  }
  try {
    const CrtpPacket pk = CrtpPacket::decode(data + 1, size - 1);
    try {
      std::vector<double> v;
      logp::decode_values(logp::decode_data(pk), layout, v);
    } catch (const CrtpError&) {
    }
    try { toc::decode_item(pk); } catch (const CrtpError&) {}
    try { toc::decode_info(pk); } catch (const CrtpError&) {}
    try { logp::decode_control_reply(pk); } catch (const CrtpError&) {}
    try { commander::decode(pk); } catch (const CrtpError&) {}
    try { commander::decode_for_firmware(pk, 8); } catch (const CrtpError&) {}
    try { commander::decode_for_firmware(pk, 10); } catch (const CrtpError&) {}
    try { commander::for_protocol(pk, 8); } catch (const CrtpError&) {}
    if (size >= 4) {
      uint32_t comp = 0;
      for (int i = 0; i < 4; ++i) comp |= static_cast<uint32_t>(data[i]) << (8 * i);
      // Any 32 bits decode to finite components (non-unit for bit patterns
      // quatcompress never produces; AttitudeBlock rejects those).
      const auto q = quatz::decompress(comp);
      if (!__builtin_isfinite(q.x + q.y + q.z + q.w)) __builtin_trap();
    }
    try { param::decode_read_reply(pk, data[0] & 0x0F); } catch (const CrtpError&) {}
    try { param::decode_write(pk, data[0] & 0x0F); } catch (const CrtpError&) {}
    try { platform::decode_protocol_version(pk); } catch (const CrtpError&) {}
    std::vector<CrtpPacket> out;
    firmware().on_packet(pk, 0, out);  // never throws: bad input is counted
    firmware().tick(1000, out);
  } catch (const CrtpError&) {
  }
  return 0;
}
