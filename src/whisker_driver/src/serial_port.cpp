#include "whisker_driver/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <utility>

namespace whisker_driver {
namespace {

bool baud_constant(int baud, speed_t& out) {
  switch (baud) {
    case 9600: out = B9600; return true;
    case 19200: out = B19200; return true;
    case 38400: out = B38400; return true;
    case 57600: out = B57600; return true;
    case 115200: out = B115200; return true;
    case 230400: out = B230400; return true;
    case 460800: out = B460800; return true;
    case 921600: out = B921600; return true;
    default: return false;
  }
}

}  // namespace

SerialPort::SerialPort(const std::string& device, int baud) { open(device, baud); }

SerialPort::~SerialPort() { close(); }

SerialPort::SerialPort(SerialPort&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), device_(std::move(other.device_)) {}

SerialPort& SerialPort::operator=(SerialPort&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    device_ = std::move(other.device_);
  }
  return *this;
}

void SerialPort::fail(const std::string& what, int err) const {
  std::string msg = "serial device " + device_ + ": " + what;
  if (err != 0) msg += " (" + std::string(std::strerror(err)) + ")";
  throw SerialError(msg);
}

void SerialPort::open(const std::string& device, int baud) {
  close();
  device_ = device;
  speed_t speed{};
  if (!baud_constant(baud, speed)) fail("unsupported baud rate " + std::to_string(baud), 0);
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    switch (err) {
      case ENOENT: fail("does not exist", err);
      case EACCES:
      case EPERM: fail("permission denied (is the user in the dialout group?)", err);
      case EBUSY: fail("busy (in use by another process)", err);
      default: fail("cannot open", err);
    }
  }
  if (!::isatty(fd)) {
    ::close(fd);
    fail("not a tty", 0);
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    fail("busy (locked by another process)", err);
  }
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    fail("tcgetattr failed", err);
  }
  ::cfmakeraw(&tio);  // raw: no echo, no line editing, no CR/LF translation
  tio.c_cflag &= ~static_cast<tcflag_t>(PARENB | CSTOPB | CSIZE | CRTSCTS);
  tio.c_cflag |= CS8 | CLOCAL | CREAD;  // 8N1, ignore modem lines
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 ||
      ::tcsetattr(fd, TCSANOW, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    fail("cannot configure 8N1 at " + std::to_string(baud) + " baud", err);
  }
  ::tcflush(fd, TCIFLUSH);  // drop bytes buffered before we opened
  fd_ = fd;
}

void SerialPort::close() {
  if (fd_ >= 0) {
    ::flock(fd_, LOCK_UN);
    ::close(fd_);
    fd_ = -1;
  }
}

size_t SerialPort::read_some(char* buf, size_t n, int timeout_ms) {
  if (fd_ < 0) fail("not open", 0);
  if (n == 0) return 0;
  pollfd p{fd_, POLLIN, 0};
  int r;
  do {
    r = ::poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  } while (r < 0 && errno == EINTR);
  if (r < 0) fail("poll failed", errno);
  if (r == 0) return 0;
  if (p.revents & POLLNVAL) fail("invalid descriptor", 0);
  if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
    const ssize_t got = ::read(fd_, buf, n);
    if (got > 0) return static_cast<size_t>(got);
    if (got == 0) fail("disconnected (end of file)", 0);
    const int err = errno;
    if (err == EAGAIN || err == EWOULDBLOCK || err == EINTR) return 0;
    fail("disconnected (read failed)", err);
  }
  return 0;
}

size_t SerialPort::write(const char* data, size_t n, int timeout_ms) {
  if (fd_ < 0) fail("not open", 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  size_t done = 0;
  while (done < n) {
    const ssize_t w = ::write(fd_, data + done, n - done);
    if (w > 0) {
      done += static_cast<size_t>(w);
      continue;
    }
    if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) fail("write failed", errno);
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) break;
    pollfd p{fd_, POLLOUT, 0};
    ::poll(&p, 1, static_cast<int>(left));
  }
  return done;
}

}  // namespace whisker_driver
