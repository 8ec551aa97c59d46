// The ground client against the firmware emulator: in memory (every byte
// goes through encode/decode) and over real UDP sockets.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <thread>

#include "crazyflie_bridge/client.hpp"
#include "crazyflie_bridge/firmware.hpp"

using namespace crazyflie_bridge;

namespace {

/// Link whose far end is a FirmwareEmulator; drop_every > 0 drops every n-th uplink packet.
class EmulatorLink : public Link {
 public:
  explicit EmulatorLink(FirmwareEmulator& fw) : fw_(fw) {}
  void send(const CrtpPacket& pk) override {
    ++stats_.packets_sent;
    if (drop_every > 0 && stats_.packets_sent % static_cast<uint64_t>(drop_every) == 0) return;
    const auto wire = pk.encode();
    std::vector<CrtpPacket> out;
    fw_.on_packet(CrtpPacket::decode(wire.data(), wire.size()), now_ms, out);
    for (auto& p : out) in_.push_back(p);
  }
  std::optional<CrtpPacket> receive(std::chrono::milliseconds) override {
    if (in_.empty()) {
      std::vector<CrtpPacket> out;
      fw_.tick(now_ms, out);
      now_ms += 10;
      for (auto& p : out) in_.push_back(p);
      if (in_.empty()) return std::nullopt;
    }
    auto wire = in_.front().encode();
    in_.pop_front();
    ++stats_.packets_received;
    return CrtpPacket::decode(wire.data(), wire.size());
  }
  const LinkStatistics& statistics() const override { return stats_; }
  std::string uri() const override { return "emulator://"; }
  uint32_t now_ms = 0;
  int drop_every = 0;
  void inject(const CrtpPacket& pk) { in_.push_back(pk); }

 private:
  FirmwareEmulator& fw_;
  std::deque<CrtpPacket> in_;
  LinkStatistics stats_;
};

FirmwareEmulator make_firmware() {
  FirmwareEmulator fw;
  fw.add_log_variable("Whisker", "Barometer1_1", logp::Type::kFloat);
  fw.add_log_variable("stateEstimate", "z", logp::Type::kFloat);
  fw.add_log_variable("pm", "state", logp::Type::kInt8);
  fw.add_log_variable("motor", "m1", logp::Type::kUint16);
  fw.add_param("deck", "bcWhisker", param::kUint8, 1, true);
  fw.add_param("pid", "kp", param::kFloat, 2.5, false);
  fw.add_param("ring", "effect", param::kInt16, -3, false);
  return fw;
}

}  // namespace

TEST(FirmwareClient, ConnectDownloadsTocsAndLogs) {
  auto fw = make_firmware();
  fw.set_log_value(0, 101325.5);
  fw.set_log_value(1, 0.4);
  fw.set_log_value(2, -1);
  fw.set_log_value(3, 40000);
  EmulatorLink link(fw);
  CrazyflieClient c(link);
  c.connect();
  EXPECT_EQ(c.protocol_version(), 10);
  ASSERT_EQ(c.log_toc().size(), 4u);
  EXPECT_EQ(c.log_toc()[3].full_name(), "motor.m1");
  ASSERT_EQ(c.param_toc().size(), 3u);
  EXPECT_EQ(c.log_toc_crc(), fw.log_toc_crc());
  const uint8_t id = c.start_log_block({"Whisker.Barometer1_1", "stateEstimate.z", "pm.state", "motor.m1"}, 20);
  EXPECT_EQ(fw.block_period_ms(id), 20u);
  std::vector<LogSample> got;
  for (int i = 0; i < 10; ++i) {
    if (auto s = c.poll(std::chrono::milliseconds(10))) got.push_back(*s);
  }
  ASSERT_GE(got.size(), 3u);
  EXPECT_FLOAT_EQ(static_cast<float>(got[0].values[0]), 101325.5f);
  EXPECT_FLOAT_EQ(static_cast<float>(got[0].values[1]), 0.4f);
  EXPECT_EQ(got[0].values[2], -1.0);
  EXPECT_EQ(got[0].values[3], 40000.0);
  // 20 ms period: consecutive firmware timestamps 20 ms apart.
  EXPECT_EQ(got[1].timestamp_ms - got[0].timestamp_ms, 20u);
}

TEST(FirmwareClient, ParamsReadWriteAndErrors) {
  auto fw = make_firmware();
  EmulatorLink link(fw);
  CrazyflieClient c(link);
  c.connect();
  EXPECT_EQ(c.read_param("deck.bcWhisker"), 1.0);
  EXPECT_FLOAT_EQ(static_cast<float>(c.read_param("pid.kp")), 2.5f);
  EXPECT_EQ(c.read_param("ring.effect"), -3.0);
  EXPECT_FLOAT_EQ(static_cast<float>(c.write_param("pid.kp", 0.75)), 0.75f);
  EXPECT_FLOAT_EQ(static_cast<float>(fw.param_value(1)), 0.75f);
  EXPECT_FLOAT_EQ(static_cast<float>(c.read_param("pid.kp")), 0.75f);
  EXPECT_EQ(c.write_param("ring.effect", 40000), 32767.0);  // saturated to int16
  EXPECT_THROW(c.write_param("deck.bcWhisker", 0), ClientError);  // read-only
  EXPECT_THROW(c.read_param("no.such"), ClientError);
  EXPECT_THROW(c.start_log_block({"no.such"}, 20), ClientError);
  // 7 floats = 28 bytes > 26.
  EXPECT_THROW(c.start_log_block(std::vector<std::string>(7, "stateEstimate.z"), 20), ClientError);
}

TEST(FirmwareClient, RequestsSurvivePacketLoss) {
  auto fw = make_firmware();
  EmulatorLink link(fw);
  link.drop_every = 3;  // every third uplink packet lost
  ClientOptions opt;
  opt.reply_timeout = std::chrono::milliseconds(1);
  CrazyflieClient c(link, opt);
  c.connect();
  EXPECT_EQ(c.log_toc().size(), 4u);
  EXPECT_GT(c.stats().resends, 0u);
  EXPECT_FLOAT_EQ(static_cast<float>(c.write_param("pid.kp", 1.25)), 1.25f);
  EXPECT_EQ(c.stats().log_missed, 0u);
}

TEST(FirmwareClient, MissedLogPacketsCountedFromTimestamps) {
  auto fw = make_firmware();
  EmulatorLink link(fw);
  CrazyflieClient c(link);
  c.connect();
  const uint8_t id = c.start_log_block({"stateEstimate.z"}, 10);
  std::vector<CrtpPacket> ignored;
  fw.on_packet(logp::stop_block(id), 0, ignored);  // only the hand-made packets below
  // t = 100, 110, 140 (2 missing), 150; then a jump of ~4.6 h (more than 100000
  // periods: a firmware restart, not counted) and the 24-bit wrap
  // 0xFFFFFA -> 0x000004, which is one 10 ms period (nothing missing).
  for (uint32_t t : {100u, 110u, 140u, 150u}) link.inject(logp::data_packet(id, t, {logp::Type::kFloat}, {0.5}));
  int n = 0;
  while (c.poll(std::chrono::milliseconds(1))) ++n;
  EXPECT_EQ(n, 4);
  EXPECT_EQ(c.stats().log_missed, 2u);
  link.inject(logp::data_packet(id, 0xFFFFFAu, {logp::Type::kFloat}, {0.5}));
  link.inject(logp::data_packet(id, 0x000004u, {logp::Type::kFloat}, {0.5}));
  while (c.poll(std::chrono::milliseconds(1))) ++n;
  EXPECT_EQ(n, 6);
  EXPECT_EQ(c.stats().log_missed, 2u);
  link.inject(logp::data_packet(id, 0x000022u, {logp::Type::kFloat}, {0.5}));  // 4 -> 34: 2 missing
  c.poll(std::chrono::milliseconds(1));
  EXPECT_EQ(c.stats().log_missed, 4u);
}

TEST(FirmwareClient, TocCacheByCrc) {
  const auto dir = std::filesystem::temp_directory_path() / ("cf_toc_cache_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto fw = make_firmware();
  ClientOptions opt;
  opt.toc_cache_dir = dir.string();
  {
    EmulatorLink link(fw);
    CrazyflieClient c(link, opt);
    c.connect();
    EXPECT_FALSE(c.log_toc_from_cache());
  }
  EmulatorLink link(fw);
  CrazyflieClient c(link, opt);
  const auto before = fw.stats().replies;
  c.connect();
  EXPECT_TRUE(c.log_toc_from_cache());
  EXPECT_EQ(c.log_toc()[1].full_name(), "stateEstimate.z");
  // Cached: no TOC item requests, only protocol and firmware version, reset,
  // 2 infos (+ link source).
  EXPECT_EQ(fw.stats().replies - before, 6u);
  // A different TOC (new CRC) is downloaded again.
  fw.add_log_variable("extra", "v", logp::Type::kFloat);
  EmulatorLink link2(fw);
  CrazyflieClient c2(link2, opt);
  c2.connect();
  EXPECT_FALSE(c2.log_toc_from_cache());
  EXPECT_EQ(c2.log_toc().size(), 5u);
  std::filesystem::remove_all(dir);
}

TEST(FirmwareClient, ReadsProtocolAndFirmwareVersion) {
  FirmwareEmulator::Options o;
  o.protocol_version = 8;
  o.firmware_version = "2024.2";
  FirmwareEmulator fw(o);
  fw.add_log_variable("stateEstimate", "z", logp::Type::kFloat);
  EmulatorLink link(fw);
  CrazyflieClient c(link);
  c.connect();
  EXPECT_EQ(c.protocol_version(), 8);
  EXPECT_TRUE(c.firmware_version_answered());
  EXPECT_EQ(c.firmware_version(), "2024.2");
}

TEST(FirmwareClient, RefusesProtocolBelowCflibsV2Minimum) {
  // cflib toc.py/log.py/param.py use the v2 packets from protocol 4 on; below
  // it no generation this client speaks fits: refused, naming the version.
  for (uint8_t v : {uint8_t{0}, uint8_t{3}}) {
    FirmwareEmulator::Options o;
    o.protocol_version = v;
    FirmwareEmulator fw(o);
    fw.add_log_variable("stateEstimate", "z", logp::Type::kFloat);
    EmulatorLink link(fw);
    CrazyflieClient c(link);
    try {
      c.connect();
      FAIL() << "protocol " << int(v) << " accepted";
    } catch (const ClientError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("CRTP protocol version " + std::to_string(v) + ": not supported"), std::string::npos) << m;
      EXPECT_NE(m.find("oldest supported is 4"), std::string::npos) << m;
    }
  }
  FirmwareEmulator::Options o;
  o.protocol_version = 4;  // the oldest accepted
  FirmwareEmulator fw(o);
  fw.add_log_variable("stateEstimate", "z", logp::Type::kFloat);
  EmulatorLink link(fw);
  CrazyflieClient c(link);
  EXPECT_NO_THROW(c.connect());
}

TEST(FirmwareClient, EachGenerationDecodesItsOwnHoverAndStopsOnTheOther) {
  using Mode = FirmwareEmulator::CommanderOutput::Mode;
  std::vector<CrtpPacket> out;
  // Legacy firmware (protocol 8): type 5 with the negated yaw rate is CCW 30 deg/s.
  FirmwareEmulator::Options old_o;
  old_o.protocol_version = 8;
  FirmwareEmulator old_fw(old_o);
  old_fw.on_packet(commander::hover_for_protocol(8, 0.f, 0.f, 30.f, 0.4f), 0, out);
  auto c = old_fw.commander(10);
  ASSERT_EQ(c.mode, Mode::kSetpoint);
  EXPECT_FLOAT_EQ(c.setpoint.c, 30.f);
  EXPECT_FLOAT_EQ(c.setpoint.d, 0.4f);
  // The same firmware given type 10: no decoder -> all-zero setpoint = motors off.
  old_fw.on_packet(commander::hover(0.f, 0.f, 30.f, 0.4f), 20, out);
  EXPECT_EQ(old_fw.commander(30).mode, Mode::kShutdown);
  EXPECT_EQ(old_fw.stats().unknown_setpoint_types, 1u);
  // Current firmware (protocol 10): type 10 CCW as sent; legacy 5 still decoded.
  FirmwareEmulator new_fw;
  new_fw.on_packet(commander::hover_for_protocol(10, 0.f, 0.f, 30.f, 0.4f), 0, out);
  c = new_fw.commander(10);
  ASSERT_EQ(c.mode, Mode::kSetpoint);
  EXPECT_EQ(c.setpoint.type, commander::kTypeHover);
  EXPECT_FLOAT_EQ(c.setpoint.c, 30.f);
  new_fw.on_packet(commander::hover_legacy(0.f, 0.f, 30.f, 0.4f), 20, out);
  EXPECT_FLOAT_EQ(new_fw.commander(30).setpoint.c, 30.f);
  CrtpPacket unknown(port::kCommanderGeneric, commander::kChanSetpoint, {12});
  new_fw.on_packet(unknown, 40, out);
  EXPECT_EQ(new_fw.commander(50).mode, Mode::kShutdown);
  EXPECT_EQ(new_fw.stats().unknown_setpoint_types, 1u);
}

TEST(FirmwareClient, LogControlErrnos) {
  auto fw = make_firmware();
  std::vector<CrtpPacket> out;
  fw.on_packet(logp::start_block_v2(9, 10), 0, out);  // unknown block
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(logp::decode_control_reply(out[0]).status, ENOENT);
  out.clear();
  fw.on_packet(logp::create_block_v2(1, {{99, logp::Type::kFloat, logp::Type::kFloat}})[0], 0, out);  // unknown var
  EXPECT_EQ(logp::decode_control_reply(out[0]).status, ENOENT);
  out.clear();
  fw.on_packet(logp::create_block_v2(1, {{0, logp::Type::kFloat, logp::Type::kFloat}})[0], 0, out);
  fw.on_packet(logp::create_block_v2(1, {{0, logp::Type::kFloat, logp::Type::kFloat}})[0], 0, out);
  EXPECT_EQ(logp::decode_control_reply(out[0]).status, 0);
  EXPECT_EQ(logp::decode_control_reply(out[1]).status, EEXIST);
  out.clear();
  // Truncated packets are counted, not answered.
  fw.on_packet(CrtpPacket(port::kLog, 1, {logp::kCmdStartBlockV2, 1, 5}), 0, out);
  fw.on_packet(CrtpPacket(port::kParam, 1, {1}), 0, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(fw.stats().malformed, 2u);
}

TEST(FirmwareClient, CommanderWatchdog) {
  auto fw = make_firmware();
  std::vector<CrtpPacket> out;
  EXPECT_EQ(fw.commander(0).mode, FirmwareEmulator::CommanderOutput::Mode::kIdle);
  fw.on_packet(commander::hover(0.1f, 0, 0, 0.4f), 1000, out);
  EXPECT_EQ(fw.commander(1499).mode, FirmwareEmulator::CommanderOutput::Mode::kSetpoint);
  EXPECT_EQ(fw.commander(1500).mode, FirmwareEmulator::CommanderOutput::Mode::kStabilize);
  EXPECT_EQ(fw.commander(3000).mode, FirmwareEmulator::CommanderOutput::Mode::kShutdown);
  // notify-setpoint-stop keeps the last setpoint valid for the given time.
  fw.on_packet(commander::notify_setpoint_stop(1000), 1100, out);
  EXPECT_EQ(fw.commander(2500).mode, FirmwareEmulator::CommanderOutput::Mode::kSetpoint);
  fw.on_packet(commander::stop(), 2600, out);
  EXPECT_EQ(fw.commander(2600).mode, FirmwareEmulator::CommanderOutput::Mode::kShutdown);
  EXPECT_TRUE(out.empty());  // setpoints are not answered
}

namespace {
/// The firmware emulator behind a UDP server on wall-clock milliseconds, until `stop`.
void serve_over_udp(FirmwareEmulator& fw, UdpServer& server, const std::atomic<bool>& stop) {
  const auto t0 = std::chrono::steady_clock::now();
  uint32_t last_tick = 0;
  while (!stop) {
    const auto now_ms = static_cast<uint32_t>(
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0).count());
    std::vector<CrtpPacket> out;
    if (auto pk = server.receive(std::chrono::microseconds(1000))) fw.on_packet(*pk, now_ms, out);
    if (now_ms != last_tick) fw.tick(now_ms, out), last_tick = now_ms;
    for (auto& p : out) server.send(p);
  }
}
}  // namespace

TEST(FirmwareClient, OverUdpSockets) {
  auto fw = make_firmware();
  fw.set_log_value(1, 0.5);
  UdpServer server(0);
  std::atomic<bool> stop{false};
  std::thread t([&] { serve_over_udp(fw, server, stop); });
  {
    UdpLink link(parse_uri("udp://127.0.0.1:" + std::to_string(server.port()) + "?handshake=1"));
    CrazyflieClient c(link);
    c.connect();
    c.start_log_block({"stateEstimate.z"}, 10);
    int n = 0;
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(300)) {
      if (auto s = c.poll(std::chrono::milliseconds(50))) {
        EXPECT_FLOAT_EQ(static_cast<float>(s->values[0]), 0.5f);
        ++n;
      }
    }
    EXPECT_GE(n, 15);  // 100 Hz for 0.3 s, generous for a loaded machine
    EXPECT_LE(n, 35);
    // Garbage datagrams are counted by the server, not fatal.
    const uint8_t junk[40] = {};
    link.send_raw(junk, sizeof junk);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  stop = true;
  t.join();
  EXPECT_EQ(server.connects(), 1u);
  EXPECT_EQ(server.disconnects(), 1u);
  EXPECT_EQ(server.statistics().malformed, 1u);
  // Port busy: a second server on the same port fails with a clear error.
  try {
    UdpServer again(server.port());
    FAIL();
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind"), std::string::npos);
  }
}

// A busy, unplugged or forbidden device (no hardware here: the messages the
// links throw for those libusb codes; LIBUSB_ERROR_* values of libusb-1.0).
TEST(Links, BusyUnpluggedAndForbiddenDevicesAreNamed) {
  const std::string what = "Crazyradio for radio://0/80/2M/E7E7E7E7E7: claim interface";
  const std::string busy = usb_error_message(what, -6);  // LIBUSB_ERROR_BUSY
  EXPECT_EQ(busy.rfind(what + ": LIBUSB_ERROR_BUSY", 0), 0u) << busy;
  EXPECT_NE(busy.find("another program (cfclient, another bridge) has claimed it"), std::string::npos) << busy;
  const std::string gone = usb_error_message("Crazyflie on usb://0: send", -4);  // LIBUSB_ERROR_NO_DEVICE
  EXPECT_NE(gone.find("LIBUSB_ERROR_NO_DEVICE"), std::string::npos) << gone;
  EXPECT_NE(gone.find("unplugged"), std::string::npos) << gone;
  const std::string access = usb_error_message("Crazyradio: open", -3);  // LIBUSB_ERROR_ACCESS
  EXPECT_NE(access.find("udev rules"), std::string::npos) << access;
  const std::string timeout = usb_error_message("Crazyradio: vendor request 1", -7);  // LIBUSB_ERROR_TIMEOUT
  EXPECT_NE(timeout.find("LIBUSB_ERROR_TIMEOUT"), std::string::npos) << timeout;
  EXPECT_EQ(timeout.find("unplugged"), std::string::npos) << timeout;
}

TEST(Links, MissingDevicesGiveClearErrors) {
  // No Crazyradio / Crazyflie is attached to the test machine (or libusb cannot
  // see one): opening must fail with a message naming the device, not crash.
  for (const char* uri : {"radio://7/80/2M", "usb://7"}) {
    try {
      open_link(uri);
      ADD_FAILURE() << uri;
    } catch (const LinkError& e) {
      const std::string w = e.what();
      EXPECT_TRUE(w.find("no Crazy") != std::string::npos || w.find("libusb") != std::string::npos) << w;
    }
  }
}

// Issue 32 item 8: the simulated Crazyflie answered whoever sent the last datagram, so a
// `tactile scan` during a flight took the flight's log packets. The link now serves the
// client that owns it; a scan's null packet is answered to the scanner only.
TEST(FirmwareClient, UdpServerServesOneClientAndAnswersScans) {
  auto fw = make_firmware();
  fw.set_log_value(1, 0.5);
  UdpServer server(0);
  std::atomic<bool> stop{false};
  std::thread t([&] { serve_over_udp(fw, server, stop); });
  const std::string uri = "udp://127.0.0.1:" + std::to_string(server.port());
  {
    UdpLink owner_link(parse_uri(uri + "?handshake=1"));
    CrazyflieClient owner(owner_link);
    owner.connect();
    owner.start_log_block({"stateEstimate.z"}, 10);
    ASSERT_TRUE(owner.poll(std::chrono::milliseconds(500)).has_value());

    // A scan's probe during the flight is answered (to the scanner) ...
    UdpLink other(parse_uri(uri));
    const uint8_t probe = 0xFF;
    other.send_raw(&probe, 1);
    bool answered = false;
    for (int i = 0; i < 20 && !answered; ++i) {
      other.receive(std::chrono::milliseconds(10));
      answered = other.statistics().null_received > 0 || other.statistics().packets_received > 0;
    }
    EXPECT_TRUE(answered);
    // ... and its other packets are dropped: the owner's stream is unaffected, the other
    // client receives none of the owner's log data.
    other.send(CrtpPacket(5, 1, {0x05}));  // a log reset request from the second client
    int owner_samples = 0;
    const auto t1 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t1 < std::chrono::milliseconds(200)) {
      if (owner.poll(std::chrono::milliseconds(20))) ++owner_samples;
    }
    EXPECT_GE(owner_samples, 8);  // 100 Hz for 0.2 s, generous for a loaded machine
    uint64_t before = other.statistics().packets_received;
    for (int i = 0; i < 10; ++i) other.receive(std::chrono::milliseconds(10));
    EXPECT_EQ(other.statistics().packets_received, before);
    EXPECT_EQ(server.foreign_datagrams(), 2u);  // the probe and the reset
  }  // the owner says goodbye (0xF4): the link is free
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  {
    UdpLink next(parse_uri(uri + "?handshake=1"));
    CrazyflieClient c(next);
    c.connect();  // the next client takes the link
  }
  stop = true;
  t.join();
  EXPECT_EQ(server.foreign_datagrams(), 2u);
}
