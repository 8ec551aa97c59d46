// Serial port and serial source end to end over a pseudo terminal: the test
// writes protocol lines to the master side, the driver reads the slave side.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "whisker_driver/serial_port.hpp"
#include "whisker_driver/sources.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"

using namespace whisker_driver;

namespace {

class Pty {
 public:
  Pty() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) return;
    const char* name = ::ptsname(master_);
    if (name) slave_ = name;
  }
  ~Pty() { close_master(); }
  bool ok() const { return master_ >= 0 && !slave_.empty(); }
  const std::string& slave() const { return slave_; }
  void write(const std::string& s) const {
    ASSERT_EQ(::write(master_, s.data(), s.size()), static_cast<ssize_t>(s.size()));
  }
  void close_master() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }

 private:
  int master_ = -1;
  std::string slave_;
};

// Reads from the port until `want` bytes arrived or 2 s passed.
std::string read_n(SerialPort& port, size_t want) {
  std::string got;
  char buf[256];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (got.size() < want && std::chrono::steady_clock::now() < deadline) {
    const size_t n = port.read_some(buf, sizeof(buf), 50);
    got.append(buf, n);
  }
  return got;
}

std::string error_of(const std::string& device) {
  try {
    SerialPort p(device);
  } catch (const SerialError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SerialPort, OpensPtyRaw115200AndReadsWhatTheMasterWrites) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port(pty.slave());
  EXPECT_TRUE(port.is_open());
  termios tio{};
  ASSERT_EQ(::tcgetattr(port.fd(), &tio), 0);
  EXPECT_EQ(::cfgetispeed(&tio), static_cast<speed_t>(B115200));
  EXPECT_EQ(::cfgetospeed(&tio), static_cast<speed_t>(B115200));
  EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(tio.c_cflag & (PARENB | CSTOPB), 0u);
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG), 0u);
  EXPECT_EQ(tio.c_iflag & (ICRNL | IXON), 0u);  // CR bytes reach the parser unchanged
  EXPECT_NE(::fcntl(port.fd(), F_GETFL) & O_NONBLOCK, 0);

  // Timeout without data.
  char buf[16];
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(port.read_some(buf, sizeof(buf), 100), 0u);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(ms, 90);

  const std::string line = "P1:101325.5\r\n";
  pty.write(line);
  EXPECT_EQ(read_n(port, line.size()), line);
}

TEST(SerialPort, ErrorsNameTheDeviceAndTheReason) {
  const std::string missing = "/nonexistent/ttyWHISKER0";
  const std::string e1 = error_of(missing);
  EXPECT_NE(e1.find(missing), std::string::npos) << e1;
  EXPECT_NE(e1.find("does not exist"), std::string::npos) << e1;

  const std::string e2 = error_of("/dev/null");
  EXPECT_NE(e2.find("/dev/null"), std::string::npos) << e2;
  EXPECT_NE(e2.find("not a tty"), std::string::npos) << e2;

  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort first(pty.slave());
  const std::string e3 = error_of(pty.slave());
  EXPECT_NE(e3.find(pty.slave()), std::string::npos) << e3;
  EXPECT_NE(e3.find("busy"), std::string::npos) << e3;
  first.close();
  EXPECT_NO_THROW(SerialPort again(pty.slave()));

  // Permission denied (not testable as root, who bypasses file modes).
  if (::geteuid() != 0) {
    std::string tmpl = (std::filesystem::temp_directory_path() / "whisker_driver_ttyXXXXXX").string();
    std::vector<char> path(tmpl.begin(), tmpl.end());
    path.push_back('\0');
    const int fd = ::mkstemp(path.data());
    ASSERT_GE(fd, 0);
    ::close(fd);
    ::chmod(path.data(), 0);
    const std::string e4 = error_of(path.data());
    EXPECT_NE(e4.find("permission denied"), std::string::npos) << e4;
    ::unlink(path.data());
  }
  EXPECT_THROW(SerialPort(pty.slave(), 12345), SerialError);
}

TEST(SerialPort, HangUpIsReportedAsDisconnect) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port(pty.slave());
  pty.close_master();
  char buf[16];
  try {
    port.read_some(buf, sizeof(buf), 200);
    FAIL() << "expected SerialError";
  } catch (const SerialError& e) {
    EXPECT_NE(std::string(e.what()).find("disconnected"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(pty.slave()), std::string::npos) << e.what();
  }
}

TEST(SerialSource, TextProtocolEndToEndOverPty) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialSource src(SerialPort(pty.slave()), Protocol::kText, {1, "whisker_right"});
  std::vector<WhiskerPressure> out;
  src.poll(1000, out);
  EXPECT_TRUE(out.empty());
  // Two frames, the second split across writes, with a garbage line between.
  pty.write("P1:101325.5\r\nP2:101400\r\nP3:99000.25\r\nT1:25.5\r\nT2:26\r\nT3:-3.5\r\n");
  pty.write("garbage!\r\nP1:101330\r\nP2:1014");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (out.empty() && std::chrono::steady_clock::now() < deadline) {
    ::usleep(5000);
    src.poll(2000000000, out);
  }
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].pressure[2], 99000.25);
  EXPECT_DOUBLE_EQ(out[0].temperature[2], -3.5);
  EXPECT_EQ(out[0].whisker_id, 1);
  EXPECT_EQ(out[0].header.frame_id, "whisker_right");
  EXPECT_EQ(out[0].header.stamp.sec, 2);
  EXPECT_EQ(out[0].header.stamp.nanosec, 0u);
  pty.write("01.5\r\nP3:99001\r\nT1:25.6\r\nT2:26.1\r\nT3:-3.4\r\n");
  out.clear();
  const auto deadline2 = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (out.empty() && std::chrono::steady_clock::now() < deadline2) {
    ::usleep(5000);
    src.poll(2020000000, out);
  }
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].pressure[1], 101401.5);
  EXPECT_EQ(out[0].sequence, 1u);
  EXPECT_EQ(src.parse_stats().malformed_lines, 1u);
  EXPECT_EQ(src.parse_stats().frames, 2u);
}

TEST(SerialSource, SeveralFramesInOnePollAreSpacedByThePeriod) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialSource src(SerialPort(pty.slave()), Protocol::kCsv, {0, "whisker_left"}, 20000000);
  pty.write("100000,100001,100002\n100010,100011,100012\n100020,100021,100022\n");
  ::usleep(50000);
  std::vector<WhiskerPressure> out;
  src.poll(10000000000, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].header.stamp.sec, 9);
  EXPECT_EQ(out[0].header.stamp.nanosec, 960000000u);
  EXPECT_EQ(out[2].header.stamp.sec, 10);
  EXPECT_EQ(out[2].header.stamp.nanosec, 0u);
  EXPECT_DOUBLE_EQ(out[1].pressure[2], 100012.0);
  for (double t : out[1].temperature) EXPECT_TRUE(std::isnan(t));
}

TEST(SerialSource, DisconnectIsCountedAndDoesNotThrow) {
  auto pty = std::make_unique<Pty>();
  ASSERT_TRUE(pty->ok());
  SerialSource src(SerialPort(pty->slave()), Protocol::kCsv, {0, "whisker_left"});
  pty->close_master();
  std::vector<WhiskerPressure> out;
  EXPECT_NO_THROW(src.poll(0, out));
  EXPECT_EQ(src.errors(), 1u);
  EXPECT_NE(src.last_error().find("disconnected"), std::string::npos) << src.last_error();
  EXPECT_FALSE(src.port().is_open());
  // Retries not before a second; the pty is gone, so the reopen fails and is counted.
  src.poll(SerialSource::kReopenIntervalNs / 2, out);
  EXPECT_EQ(src.errors(), 1u);
  src.poll(SerialSource::kReopenIntervalNs, out);
  EXPECT_EQ(src.errors(), 2u);
  EXPECT_TRUE(out.empty());
}

TEST(WhiskerDriverLogic, SerialSourceFromParameters) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  WhiskerDriverParams p;
  p.source = "serial";
  p.device = pty.slave();
  p.protocol = "csv";
  p.whisker_id = 1;
  p.frame_id = "whisker_right";
  WhiskerDriverLogic logic(p);
  pty.write("100000,100001,100002\n100000,nan,100002\n");
  ::usleep(50000);
  const auto out = logic.on_timer(5000000000);
  ASSERT_EQ(out.pressure.size(), 1u);
  EXPECT_EQ(out.pressure[0].whisker_id, 1);
  EXPECT_EQ(logic.stats().parse.non_finite_values, 1u);
  EXPECT_EQ(logic.stats().published, 1u);

  p.device = "/nonexistent/ttyWHISKER1";
  try {
    WhiskerDriverLogic bad(p);
    FAIL() << "expected SerialError";
  } catch (const SerialError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ttyWHISKER1"), std::string::npos);
  }
}
