// Byte-exact CRTP vectors. Every expected byte string is derived by hand from
// cflib's packing code (struct formats quoted next to each vector) and the
// firmware's packet layouts; test/python/test_cflib_vectors.py checks the
// same encoders against cflib's own classes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "crazyflie_bridge/crtp.hpp"
#include "crazyflie_bridge/protocol.hpp"
#include "crazyflie_bridge/radio.hpp"
#include "crazyflie_bridge/uri.hpp"

using namespace crazyflie_bridge;
using Bytes = std::vector<uint8_t>;

TEST(Crtp, HeaderAndNullPacket) {
  // cflib CRTPPacket: header = port << 4 | 0x3 << 2 | channel.
  EXPECT_EQ(CrtpPacket(port::kLog, 1).header(), 0x5D);
  EXPECT_EQ(CrtpPacket(port::kCommanderGeneric, 0).header(), 0x7C);
  EXPECT_EQ(CrtpPacket(port::kParam, 2).header(), 0x2E);
  EXPECT_EQ(CrtpPacket::null_packet().encode(), Bytes{0xFF});
  const auto n = CrtpPacket::decode(Bytes{0xFF}.data(), 1);
  EXPECT_TRUE(n.is_null());
  // The link bits are ignored on decode: 0x70 and 0x7C are both port 7 ch 0.
  const uint8_t a[] = {0x70, 0x01};
  const auto p = CrtpPacket::decode(a, 2);
  EXPECT_EQ(p.port, 7);
  EXPECT_EQ(p.channel, 0);
  EXPECT_EQ(p.size, 1);
}

TEST(Crtp, DecodeRejectsEmptyAndOversized) {
  EXPECT_THROW(CrtpPacket::decode(nullptr, 0), CrtpError);
  Bytes big(32, 0x00);
  try {
    CrtpPacket::decode(big.data(), big.size());
    FAIL();
  } catch (const CrtpError& e) {
    EXPECT_NE(std::string(e.what()).find("32 bytes"), std::string::npos);
  }
  EXPECT_FALSE(CrtpPacket::try_decode(big.data(), big.size()));
  Bytes max(31, 0xAB);
  EXPECT_EQ(CrtpPacket::decode(max.data(), max.size()).size, 30);
}

TEST(Crtp, PayloadOverflowThrows) {
  CrtpPacket p(port::kLog, 2);
  for (int i = 0; i < 30; ++i) p.u8(1);
  EXPECT_THROW(p.u8(1), CrtpError);
  EXPECT_THROW(CrtpPacket(port::kLog, 2).bytes(Bytes(31).data(), 31), CrtpError);
}

TEST(Crtp, HoverSetpointVector) {
  // cflib commander.send_hover_setpoint: struct.pack('<Bffff', 10, vx, vy, yawrate, zdistance)
  const auto b = commander::hover(0.5f, -0.25f, 30.0f, 0.4f).encode();
  EXPECT_EQ(b, (Bytes{0x7C, 0x0A, 0x00, 0x00, 0x00, 0x3F, 0x00, 0x00, 0x80, 0xBE, 0x00, 0x00, 0xF0, 0x41, 0xCD, 0xCC,
                      0xCC, 0x3E}));
  const auto s = commander::decode(CrtpPacket::decode(b.data(), b.size()));
  EXPECT_EQ(s.kind, commander::Setpoint::Kind::kHover);
  EXPECT_FLOAT_EQ(s.a, 0.5f);
  EXPECT_FLOAT_EQ(s.b, -0.25f);
  EXPECT_FLOAT_EQ(s.c, 30.0f);
  EXPECT_FLOAT_EQ(s.d, 0.4f);
}

TEST(Crtp, LegacyHoverNegatesYawRate) {
  // cflib for protocol <= 8: pack('<Bffff', 5, vx, vy, -yawrate, z)
  CrtpPacket p(port::kCommanderGeneric, 0);
  p.u8(5).f32(0.f).f32(0.f).f32(-30.f).f32(0.3f);
  EXPECT_FLOAT_EQ(commander::decode(p).c, 30.f);
}

TEST(Crtp, StopNotifyVelocityPositionVectors) {
  EXPECT_EQ(commander::stop().encode(), (Bytes{0x7C, 0x00}));  // pack('<B', 0)
  // pack('<BI', 0, 1000) on channel 1 (META_COMMAND_CHANNEL)
  EXPECT_EQ(commander::notify_setpoint_stop(1000).encode(), (Bytes{0x7D, 0x00, 0xE8, 0x03, 0x00, 0x00}));
  EXPECT_EQ(commander::velocity_world(1.f, 0.f, 0.f, 0.f).encode(),
            (Bytes{0x7C, 0x08, 0x00, 0x00, 0x80, 0x3F, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(commander::position(0.f, 0.f, 2.f, 0.f).encode(),
            (Bytes{0x7C, 0x07, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0x00, 0x40, 0, 0, 0, 0}));
  const auto n = commander::decode(commander::notify_setpoint_stop(1000));
  EXPECT_EQ(n.kind, commander::Setpoint::Kind::kNotifyStop);
  EXPECT_EQ(n.remain_valid_ms, 1000u);
}

TEST(Crtp, LogCreateAndStartVectors) {
  // cflib LogConfig.create (v2): [CMD_CREATE_BLOCK_V2=6, id, fetch|stored<<4, id lo, id hi, ...]
  const auto pks = logp::create_block_v2(
      1, {{3, logp::Type::kFloat, logp::Type::kFloat}, {0x0102, logp::Type::kUint16, logp::Type::kUint16}});
  ASSERT_EQ(pks.size(), 1u);
  EXPECT_EQ(pks[0].encode(), (Bytes{0x5D, 0x06, 0x01, 0x77, 0x03, 0x00, 0x22, 0x02, 0x01}));
  // v2 start (firmware CONTROL_START_BLOCK_V2 = 8, u16 period in ms)
  EXPECT_EQ(logp::start_block_v2(1, 20).encode(), (Bytes{0x5D, 0x08, 0x01, 0x14, 0x00}));
  EXPECT_EQ(logp::start_block_v2(2, 1000).encode(), (Bytes{0x5D, 0x08, 0x02, 0xE8, 0x03}));
  // cflib start: (CMD_START_LOGGING=3, id, period_in_ms / 10)
  EXPECT_EQ(logp::start_block_v1(1, 2).encode(), (Bytes{0x5D, 0x03, 0x01, 0x02}));
  EXPECT_EQ(logp::reset().encode(), (Bytes{0x5D, 0x05}));
  EXPECT_EQ(logp::stop_block(4).encode(), (Bytes{0x5D, 0x04, 0x04}));
  EXPECT_EQ(logp::delete_block(4).encode(), (Bytes{0x5D, 0x02, 0x04}));
}

TEST(Crtp, LogCreateSplitsIntoAppend) {
  // 10 variables * 3 bytes + 2 = 32 > 30: create with 9, append with 1 (cflib "Packet is full").
  std::vector<logp::BlockVariable> vars(10, {7, logp::Type::kUint8, logp::Type::kUint8});
  const auto pks = logp::create_block_v2(3, vars);
  ASSERT_EQ(pks.size(), 2u);
  EXPECT_EQ(pks[0].data[0], logp::kCmdCreateBlockV2);
  EXPECT_EQ(pks[0].size, 2 + 9 * 3);
  EXPECT_EQ(pks[1].encode(), (Bytes{0x5D, 0x07, 0x03, 0x11, 0x07, 0x00}));
}

TEST(Crtp, LogDataVector) {
  // [block id, timestamp <BBB, values]: block 1, t = 10000 ms, float 1.5, int16 -2, uint8 200
  const Bytes b{0x5E, 0x01, 0x10, 0x27, 0x00, 0x00, 0x00, 0xC0, 0x3F, 0xFE, 0xFF, 0xC8};
  const auto d = logp::decode_data(CrtpPacket::decode(b.data(), b.size()));
  EXPECT_EQ(d.block_id, 1);
  EXPECT_EQ(d.timestamp_ms, 10000u);
  std::vector<double> v;
  logp::decode_values(d, {logp::Type::kFloat, logp::Type::kInt16, logp::Type::kUint8}, v);
  EXPECT_EQ(v, (std::vector<double>{1.5, -2.0, 200.0}));
  // Round trip through the firmware-side encoder gives the same bytes.
  EXPECT_EQ(logp::data_packet(1, 10000, {logp::Type::kFloat, logp::Type::kInt16, logp::Type::kUint8}, v).encode(), b);
  // 24-bit timestamp: the top byte of a 32-bit tick is not sent.
  EXPECT_EQ(logp::decode_data(logp::data_packet(1, 0x12345678, {}, {})).timestamp_ms, 0x345678u);
}

TEST(Crtp, LogDataTruncatedAndTrailing) {
  const Bytes b{0x5E, 0x01, 0x10, 0x27, 0x00, 0x00, 0x00, 0xC0};
  const auto d = logp::decode_data(CrtpPacket::decode(b.data(), b.size()));
  std::vector<double> v;
  try {
    logp::decode_values(d, {logp::Type::kFloat}, v);
    FAIL();
  } catch (const CrtpError& e) {
    EXPECT_NE(std::string(e.what()).find("byte 0: truncated, need 4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(logp::decode_values(d, {logp::Type::kUint8}, v), CrtpError);  // 2 trailing bytes
  const Bytes shortb{0x5E, 0x01, 0x10};
  EXPECT_THROW(logp::decode_data(CrtpPacket::decode(shortb.data(), shortb.size())), CrtpError);
  EXPECT_THROW(logp::decode_data(CrtpPacket(port::kLog, 1, {1, 2, 3, 4})), CrtpError);  // wrong channel
}

TEST(Crtp, ParamReadWriteVectors) {
  // cflib _ParamUpdater.request_param_update (v2): pack('<H', id) on READ_CHANNEL 1
  EXPECT_EQ(param::read_request(0x0105).encode(), (Bytes{0x2D, 0x05, 0x01}));
  // Firmware read answer: [id u16, status 0, value]; float 0.25
  const Bytes rr{0x2D, 0x05, 0x01, 0x00, 0x00, 0x00, 0x80, 0x3E};
  const auto r = param::decode_read_reply(CrtpPacket::decode(rr.data(), rr.size()), param::kFloat);
  EXPECT_EQ(r.id, 0x0105);
  EXPECT_EQ(r.status, 0);
  EXPECT_DOUBLE_EQ(r.value, 0.25);
  EXPECT_EQ(param::read_reply(0x0105, param::kFloat, 0.25).encode(), rr);
  // cflib set_value (v2): pack('<H', id) + pack('<B', 1) on WRITE_CHANNEL 2
  EXPECT_EQ(param::write_request(2, param::kUint8, 1).encode(), (Bytes{0x2E, 0x02, 0x00, 0x01}));
  EXPECT_EQ(param::write_request(2, param::kInt16 | param::kFlagReadOnly, -2).encode(), (Bytes{0x2E, 0x02, 0x00, 0xFE, 0xFF}));
  const auto w = param::decode_write(param::write_request(9, param::kDouble, 1.0 / 3.0), param::kDouble);
  EXPECT_EQ(w.id, 9);
  EXPECT_DOUBLE_EQ(w.value, 1.0 / 3.0);
  // Integer values saturate instead of wrapping.
  EXPECT_EQ(param::write_request(2, param::kUint8, 300).encode(), (Bytes{0x2E, 0x02, 0x00, 0xFF}));
}

TEST(Crtp, TocVectors) {
  EXPECT_EQ(toc::info_request(port::kLog).encode(), (Bytes{0x5C, 0x03}));
  EXPECT_EQ(toc::item_request(port::kParam, 0x0203).encode(), (Bytes{0x2C, 0x02, 0x03, 0x02}));
  // cflib TocFetcher: unpack('<HI', payload[:6]) after the command byte
  const Bytes info{0x5C, 0x03, 0x0A, 0x00, 0xEF, 0xBE, 0xAD, 0xDE, 0x10, 0x80};
  const auto i = toc::decode_info(CrtpPacket::decode(info.data(), info.size()));
  EXPECT_EQ(i.count, 10);
  EXPECT_EQ(i.crc, 0xDEADBEEFu);
  EXPECT_EQ(i.max_packets, 16);
  EXPECT_EQ(i.max_ops, 128);
  // Item: [2, id u16, type, group\0, name\0] (cflib LogTocElement: data[0] type, then names)
  toc::Item it{7, 7, "stateEstimate", "x"};
  const auto b = toc::item_reply(port::kLog, it).encode();
  const Bytes expect{0x5C, 0x02, 0x07, 0x00, 0x07, 's', 't', 'a', 't', 'e', 'E', 's', 't', 'i', 'm', 'a', 't', 'e', 0, 'x', 0};
  EXPECT_EQ(b, expect);
  const auto back = toc::decode_item(CrtpPacket::decode(b.data(), b.size()));
  EXPECT_EQ(back.full_name(), "stateEstimate.x");
  // A name without its terminator is rejected with the byte offset.
  Bytes bad = expect;
  bad.pop_back();
  try {
    toc::decode_item(CrtpPacket::decode(bad.data(), bad.size()));
    FAIL();
  } catch (const CrtpError& e) {
    EXPECT_NE(std::string(e.what()).find("byte 18: string not NUL-terminated"), std::string::npos) << e.what();
  }
  // zlib's CRC-32 of "123456789" is 0xCBF43926.
  const char* s = "123456789";
  EXPECT_EQ(toc::crc32(reinterpret_cast<const uint8_t*>(s), 9), 0xCBF43926u);
}

TEST(Crtp, PlatformAndMemVectors) {
  EXPECT_EQ(platform::link_source_request().encode(), (Bytes{0xFD, 0x00}));
  EXPECT_EQ(platform::protocol_version_request().encode(), (Bytes{0xDD, 0x00}));
  EXPECT_EQ(platform::decode_protocol_version(platform::protocol_version_reply(10)), 10);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(platform::link_source_reply().data.data()), 18), "Bitcraze Crazyflie");
  EXPECT_EQ(mem::count_request().encode(), (Bytes{0x4C, 0x01}));
}

TEST(Crtp, HalfFloat) {
  EXPECT_EQ(float_to_half(1.0f), 0x3C00);
  EXPECT_EQ(float_to_half(-2.0f), 0xC000);
  EXPECT_EQ(float_to_half(65504.0f), 0x7BFF);
  EXPECT_EQ(float_to_half(1e6f), 0x7C00);
  EXPECT_FLOAT_EQ(half_to_float(0x3555), 0.333251953125f);
  EXPECT_FLOAT_EQ(half_to_float(0x0001), 5.9604645e-8f);
  for (float f : {0.1f, -3.75f, 1234.5f, 0.0001f}) EXPECT_NEAR(half_to_float(float_to_half(f)), f, std::fabs(f) * 1e-3);
}

TEST(Uri, RadioLikeCflib) {
  auto u = parse_uri("radio://0/80/2M/E7E7E7E7E7?safelink=1");
  EXPECT_EQ(u.kind, LinkUri::Kind::kRadio);
  EXPECT_EQ(u.devid, 0);
  EXPECT_EQ(u.channel, 80);
  EXPECT_EQ(u.datarate, DataRate::k2M);
  EXPECT_EQ(u.address, (std::array<uint8_t, 5>{{0xE7, 0xE7, 0xE7, 0xE7, 0xE7}}));
  EXPECT_TRUE(u.safelink);
  EXPECT_EQ(to_string(u), "radio://0/80/2M/E7E7E7E7E7?safelink=1");
  // Defaults: channel 2, 2M, E7E7E7E7E7.
  u = parse_uri("radio://1");
  EXPECT_EQ(u.devid, 1);
  EXPECT_EQ(u.channel, 2);
  // Address left-padded to 10 hex digits ('{:0>10}'), first pair first.
  u = parse_uri("radio://0/10/250K/E7E7E701");
  EXPECT_EQ(u.address, (std::array<uint8_t, 5>{{0x00, 0xE7, 0xE7, 0xE7, 0x01}}));
  EXPECT_EQ(u.datarate, DataRate::k250K);
  u = parse_uri("radio://0/10/1M?safelink=0&rate_limit=100");
  EXPECT_FALSE(u.safelink);
  EXPECT_EQ(*u.rate_limit, 100);
  // A serial (>= 10 chars) names the dongle.
  u = parse_uri("radio://a1b2c3d4e5f6/80");
  EXPECT_EQ(u.devid, -1);
  EXPECT_EQ(u.serial, "A1B2C3D4E5F6");
}

TEST(Uri, UsbUdpAndErrors) {
  EXPECT_EQ(parse_uri("usb://0").kind, LinkUri::Kind::kUsb);
  auto u = parse_uri("udp://127.0.0.1:19850");
  EXPECT_EQ(u.host, "127.0.0.1");
  EXPECT_EQ(u.port, 19850);
  EXPECT_FALSE(u.handshake);
  EXPECT_TRUE(parse_uri("udp://localhost:19851?handshake=1").handshake);
  for (const char* bad : {"radio://0/126", "radio://0/80/3M", "radio://0/80/2M/XYZ", "usb://a", "udp://host",
                          "udp://:19850", "udp://h:70000", "tcp://x:1", "radio://0/80?foo=1", "nonsense", "radio://"}) {
    try {
      parse_uri(bad);
      ADD_FAILURE() << bad;
    } catch (const UriError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(Radio, AckStatusParsing) {
  // cflib Crazyradio.send_packet: ack = bit0, powerDet = bit1, retry = data[0] >> 4, data = data[1:]
  const uint8_t a[] = {0x31, 0x5C, 0x01};
  auto s = radio::parse_ack(a, 3);
  EXPECT_TRUE(s.ack);
  EXPECT_FALSE(s.power_det);
  EXPECT_EQ(s.retry, 3);
  EXPECT_EQ(s.data, (Bytes{0x5C, 0x01}));
  const uint8_t b[] = {0x03};
  s = radio::parse_ack(b, 1);
  EXPECT_TRUE(s.ack && s.power_det);
  EXPECT_EQ(s.retry, 0);
  EXPECT_TRUE(s.data.empty());
  // Status byte 0: not acknowledged, retries = ARC.
  const uint8_t c[] = {0x00, 0xAA};
  s = radio::parse_ack(c, 2, 3);
  EXPECT_FALSE(s.ack);
  EXPECT_EQ(s.retry, 3);
  EXPECT_TRUE(s.data.empty());
  EXPECT_FALSE(radio::parse_ack(nullptr, 0).ack);
  // RSSI in an empty link-control ACK: header 0xF7 (0xF3 | safelink bit), 0x01, rssi.
  const uint8_t rssi[] = {0x11, 0xF7, 0x01, 0x2D};
  EXPECT_EQ(radio::uplink_rssi(radio::parse_ack(rssi, 4)), 45);
  EXPECT_FALSE(radio::uplink_rssi(radio::parse_ack(a, 3)));
  const uint8_t echo[] = {0x01, 0xFF, 0x05, 0x01};
  EXPECT_TRUE(radio::is_safelink_echo(radio::parse_ack(echo, 4)));
}

TEST(Radio, SafelinkToggling) {
  // cflib _send_packet_safe: header &= 0xF3; |= up << 3 | down << 2
  radio::SafeLink sl;
  EXPECT_EQ(sl.apply(0x7C), 0x7C);  // disabled: untouched
  sl.enable();                      // after the FF 05 01 handshake: up = down = 0
  EXPECT_EQ(sl.apply(0x7C), 0x70);
  EXPECT_EQ(sl.apply(0xFF), 0xF3);
  // ACK with data whose bit 2 equals down (0): both toggle.
  radio::AckStatus ack{true, false, 0, {0x50, 0x01}};
  EXPECT_TRUE(sl.on_ack(ack));
  EXPECT_EQ(sl.up(), 1);
  EXPECT_EQ(sl.down(), 1);
  EXPECT_EQ(sl.apply(0x7C), 0x7C);
  // ACK without data: only up toggles.
  EXPECT_TRUE(sl.on_ack({true, false, 0, {}}));
  EXPECT_EQ(sl.apply(0x70), 0x74);
  // ACK with data carrying the other bit (repeat): up toggles, down stays, reported.
  EXPECT_FALSE(sl.on_ack({true, false, 0, {0x50}}));
  EXPECT_EQ(sl.up(), 1);
  EXPECT_EQ(sl.down(), 1);
  // No ACK: nothing toggles (the packet is resent with the same bits).
  sl.on_ack({false, false, 3, {}});
  EXPECT_EQ(sl.apply(0x70), 0x7C);
}

TEST(Radio, InitSequenceLikeCflib) {
  // Crazyradio.__init__ (fw >= 0.4) then RadioDriver.connect for channel 80, 2M, default address.
  const auto seq = radio::init_sequence(0x0099, parse_uri("radio://0/80/2M/E7E7E7E7E7"));
  const std::vector<radio::VendorRequest> expect{
      {0x03, 2, 0, {}}, {0x01, 2, 0, {}}, {0x20, 0, 0, {}}, {0x02, 0, 0, {0xE7, 0xE7, 0xE7, 0xE7, 0xE7}},
      {0x04, 3, 0, {}}, {0x06, 3, 0, {}}, {0x05, 0xA0, 0, {}}, {0x10, 1, 0, {}},
      {0x01, 80, 0, {}}, {0x06, 3, 0, {}}};
  EXPECT_EQ(seq, expect);
  const auto seq2 = radio::init_sequence(0x0099, parse_uri("radio://0/2/250K/0102030405"));
  EXPECT_EQ(seq2[8], (radio::VendorRequest{0x03, 0, 0, {}}));
  EXPECT_EQ(seq2[9], (radio::VendorRequest{0x02, 0, 0, {1, 2, 3, 4, 5}}));
}

// Random and mutated input never crashes the decoders: they return or throw
// CrtpError (the libFuzzer harness in fuzz/ does the same, coverage-guided).
TEST(Crtp, RandomInputNeverCrashes) {
  std::mt19937 rng(42);
  std::vector<double> v;
  const std::vector<logp::Type> layout{logp::Type::kFloat, logp::Type::kFP16, logp::Type::kInt8, logp::Type::kUint32};
  size_t ok = 0, rejected = 0;
  for (int i = 0; i < 200000; ++i) {
    uint8_t buf[40];
    const size_t n = rng() % 36;
    for (size_t k = 0; k < n; ++k) buf[k] = static_cast<uint8_t>(rng());
    try {
      const auto pk = CrtpPacket::decode(buf, n);
      try {
        const auto d = logp::decode_data(pk);
        logp::decode_values(d, layout, v);
        ++ok;
      } catch (const CrtpError&) {
        ++rejected;
      }
      try { toc::decode_item(pk); } catch (const CrtpError&) {}
      try { toc::decode_info(pk); } catch (const CrtpError&) {}
      try { commander::decode(pk); } catch (const CrtpError&) {}
      try { param::decode_read_reply(pk, static_cast<uint8_t>(rng() % 12)); } catch (const CrtpError&) {}
    } catch (const CrtpError&) {
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 0u);
}

// ---- Firmware generations (cflib commander.py: protocol <= 8 -> legacy) ----

TEST(Crtp, HoverForProtocolFollowsCflibsThreshold) {
  // cflib: pack('<Bffff', TYPE_HOVER_LEGACY=5, vx, vy, -yawrate, z) for <= 8,
  // pack('<Bffff', TYPE_HOVER=10, vx, vy, yawrate, z) above.
  for (int v = 4; v <= 12; ++v) {
    const auto pk = commander::hover_for_protocol(static_cast<uint8_t>(v), 0.5f, -0.25f, 30.f, 0.4f);
    PayloadReader r(pk, "test");
    const uint8_t type = r.u8();
    r.f32();
    r.f32();
    const float yaw = r.f32();
    EXPECT_EQ(type, v <= 8 ? 5 : 10) << v;
    EXPECT_FLOAT_EQ(yaw, v <= 8 ? -30.f : 30.f) << v;
    EXPECT_EQ(commander::legacy_setpoints(static_cast<uint8_t>(v)), v <= 8);
  }
  // Byte vector: [0x70|0x0C, 5, 0.0f, 0.0f, -10.0f (0xC1200000), 0.5f]
  EXPECT_EQ(commander::hover_for_protocol(8, 0.f, 0.f, 10.f, 0.5f).encode(),
            (Bytes{0x7C, 0x05, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0x20, 0xC1, 0x00, 0x00, 0x00, 0x3F}));
}

TEST(Crtp, ForProtocolReencodesOnlyHoverAndVelocityWorld) {
  const auto h = commander::hover(0.1f, 0.2f, 15.f, 0.3f);
  EXPECT_EQ(commander::for_protocol(h, 10).encode(), h.encode());
  EXPECT_EQ(commander::for_protocol(h, 8).encode(), commander::hover_legacy(0.1f, 0.2f, 15.f, 0.3f).encode());
  const auto v = commander::velocity_world(0.1f, 0.2f, 0.3f, 15.f);
  const auto vl = commander::for_protocol(v, 8);
  EXPECT_EQ(vl.data[0], commander::kTypeVelocityWorldLegacy);
  EXPECT_FLOAT_EQ(commander::decode_for_firmware(vl, 8).setpoint.d, 15.f);  // negated twice: CCW again
  for (const auto& same : {commander::stop(), commander::position(1, 2, 3, 4), commander::notify_setpoint_stop(100)}) {
    EXPECT_EQ(commander::for_protocol(same, 8).encode(), same.encode());
  }
}

TEST(Crtp, FirmwareGenerationsDecodeWhatTheyKnowAndZeroTheRest) {
  using K = commander::Setpoint::Kind;
  // Legacy table ends at positionType 7: hover 10 and velocity-world 8 unknown.
  for (uint8_t t : {uint8_t{8}, uint8_t{9}, uint8_t{10}, uint8_t{11}, uint8_t{200}}) {
    CrtpPacket pk(port::kCommanderGeneric, 0);
    pk.u8(t).f32(0).f32(0).f32(30).f32(0.4f);
    const auto f = commander::decode_for_firmware(pk, 8);
    EXPECT_TRUE(f.unknown_type) << int(t);
    EXPECT_EQ(f.setpoint.kind, K::kStop) << int(t);
    EXPECT_EQ(commander::decode_for_firmware(pk, 10).unknown_type, t > 11) << int(t);
  }
  const auto legacy = commander::decode_for_firmware(commander::hover_legacy(0, 0, 30, 0.4f), 8);
  EXPECT_FALSE(legacy.unknown_type);
  EXPECT_EQ(legacy.setpoint.kind, K::kHover);
  EXPECT_FLOAT_EQ(legacy.setpoint.c, 30.f);
  const auto cur = commander::decode_for_firmware(commander::hover(0, 0, 30, 0.4f), 9);
  EXPECT_EQ(cur.setpoint.kind, K::kHover);
  EXPECT_FLOAT_EQ(cur.setpoint.c, 30.f);
  EXPECT_EQ(commander::decode_for_firmware(commander::stop(), 8).setpoint.kind, K::kStop);
  EXPECT_FALSE(commander::decode_for_firmware(commander::stop(), 8).unknown_type);
}

// ---- Compressed quaternion (firmware quatcompress.h) ----

TEST(Crtp, QuatDecompressHandValues) {
  // Identity: largest w (index 3), the three others 0 -> 3 << 30.
  auto q = quatz::decompress(0xC0000000u);
  EXPECT_DOUBLE_EQ(q.x, 0);
  EXPECT_DOUBLE_EQ(q.y, 0);
  EXPECT_DOUBLE_EQ(q.z, 0);
  EXPECT_DOUBLE_EQ(q.w, 1);
  EXPECT_EQ(quatz::compress({0, 0, 0, 1}), 0xC0000000u);
  // Yaw +90 deg (0, 0, s, s), s = 1/sqrt 2: |z| = |w|, the first largest is z
  // (index 2); w = s -> magnitude 511, sign 0, in the last 10 bits.
  const double s = std::sqrt(0.5);
  EXPECT_EQ(quatz::compress({0, 0, s, s}), 0x800001FFu);
  q = quatz::decompress(0x800001FFu);
  EXPECT_NEAR(q.z, s, 1e-12);
  EXPECT_NEAR(q.w, s, 1e-12);
  // Yaw -90 deg (0, 0, -s, s): largest z < 0, so every other component's sign
  // bit is "not negative XOR negate" = 1 (x and y with magnitude 0 too), and the
  // decoded quaternion is the same rotation with z >= 0: (-0, -0, s, -s).
  EXPECT_EQ(quatz::compress({0, 0, -s, s}), (2u << 30) | (0x200u << 20) | (0x200u << 10) | 0x3FFu);
  q = quatz::decompress((2u << 30) | (0x200u << 20) | (0x200u << 10) | 0x3FFu);
  EXPECT_NEAR(q.z, s, 1e-12);
  EXPECT_NEAR(q.w, -s, 1e-12);
  // Roll 60 deg (0.5, 0, 0, 0.866): largest w; x = 0.5 -> round(511 * 0.5 / s) = 361
  // in bits 29..20 (x is the first of the three others).
  EXPECT_EQ(quatz::compress({0.5, 0, 0, std::sqrt(0.75)}), (3u << 30) | (361u << 20));
  q = quatz::decompress((3u << 30) | (361u << 20));
  EXPECT_NEAR(q.x, s * 361 / 511, 1e-12);
  EXPECT_NEAR(q.w, std::sqrt(1 - q.x * q.x), 1e-12);
  EXPECT_THROW(quatz::compress({0, 0, 0, 0}), CrtpError);
}

TEST(Crtp, QuatCompressRoundTripWithinResolution) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  for (int i = 0; i < 10000; ++i) {
    quatz::Quat q{n(rng), n(rng), n(rng), n(rng)};
    const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    q = {q.x / norm, q.y / norm, q.z / norm, q.w / norm};
    const auto d = quatz::decompress(quatz::compress(q));
    const double dot = std::fabs(q.x * d.x + q.y * d.y + q.z * d.z + q.w * d.w);
    EXPECT_GT(dot, std::cos(0.25 * M_PI / 180 / 2));  // same rotation within 0.25 deg
  }
}
