// Prints "<name> <hex bytes>" for a fixed set of packets built with our
// encoders; test/python/test_cflib_vectors.py builds the same packets with
// cflib's own classes and compares byte for byte.
#include <cstdio>
#include <string>

#include "crazyflie_bridge/protocol.hpp"

using namespace crazyflie_bridge;

static void print(const char* name, const CrtpPacket& pk) {
  std::printf("%s", name);
  for (uint8_t b : pk.encode()) std::printf(" %02x", b);
  std::printf("\n");
}

int main() {
  print("hover", commander::hover(0.5f, -0.25f, 30.0f, 0.4f));
  print("hover2", commander::hover(-0.1f, 0.2f, -12.5f, 1.25f));
  print("velocity_world", commander::velocity_world(0.1f, -0.2f, 0.3f, 45.0f));
  print("position", commander::position(1.0f, 2.0f, 0.5f, 90.0f));
  print("stop", commander::stop());
  // Legacy generation (cflib with get_protocol_version() <= 8).
  print("hover_legacy", commander::hover_for_protocol(8, 0.5f, -0.25f, 30.0f, 0.4f));
  print("hover_v9", commander::hover_for_protocol(9, 0.5f, -0.25f, 30.0f, 0.4f));
  print("velocity_world_legacy", commander::for_protocol(commander::velocity_world(0.1f, -0.2f, 0.3f, 45.0f), 8));
  // Compressed quaternions (x, y, z, w), as u32 little endian.
  const quatz::Quat quats[] = {{0, 0, 0, 1}, {0, 0, 0.7071067811865476, 0.7071067811865476},
                               {0, 0, -0.7071067811865476, 0.7071067811865476}, {0.5, 0, 0, 0.8660254037844386},
                               {0.1, -0.2, 0.3, 0.9273618495495703}, {-0.6, 0.5, 0.4, -0.4795831523312719}};
  for (size_t i = 0; i < sizeof quats / sizeof quats[0]; ++i) {
    const uint32_t c = quatz::compress(quats[i]);
    std::printf("quat%zu %02x %02x %02x %02x\n", i, c & 0xFF, (c >> 8) & 0xFF, (c >> 16) & 0xFF, c >> 24);
  }
  print("notify_stop", commander::notify_setpoint_stop(250));
  print("log_create", logp::create_block_v2(1, {{3, logp::Type::kFloat, logp::Type::kFloat},
                                                {258, logp::Type::kUint16, logp::Type::kUint16},
                                                {4, logp::Type::kInt8, logp::Type::kInt8}})[0]);
  print("log_start_v1", logp::start_block_v1(1, 2));
  print("log_reset", logp::reset());
  print("param_read", param::read_request(261));
  print("param_write_u8", param::write_request(2, param::kUint8, 1));
  print("param_write_float", param::write_request(7, param::kFloat, 0.75));
  print("param_write_i32", param::write_request(300, param::kInt32, -123456));
  print("toc_info_log", toc::info_request(port::kLog));
  print("toc_item_param", toc::item_request(port::kParam, 513));
  print("link_source", platform::link_source_request());
  print("protocol_version", platform::protocol_version_request());
  print("mem_count", mem::count_request());
  return 0;
}
