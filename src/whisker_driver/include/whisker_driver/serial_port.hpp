// POSIX serial port (termios) for the whisker deck: 8N1 raw, non-blocking,
// reads with a timeout (poll). Errors name the device and the reason.
// Core layer: no ROS.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace whisker_driver {

class SerialError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class SerialPort {
 public:
  SerialPort() = default;
  /// Opens `device` (see open()).
  explicit SerialPort(const std::string& device, int baud = 115200);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  SerialPort(SerialPort&& other) noexcept;
  SerialPort& operator=(SerialPort&& other) noexcept;

  /// Opens the device raw 8N1 at `baud` (9600, 19200, 38400, 57600, 115200,
  /// 230400, 460800, 921600), non-blocking, no flow control, with an exclusive
  /// advisory lock. Throws SerialError naming the device: "does not exist",
  /// "permission denied", "busy", "not a tty", unsupported baud rate.
  void open(const std::string& device, int baud = 115200);
  void close();
  bool is_open() const { return fd_ >= 0; }
  const std::string& device() const { return device_; }
  int fd() const { return fd_; }

  /// Waits up to timeout_ms (0: do not wait) for data and reads at most n
  /// bytes. Returns the number read, 0 on timeout. Throws SerialError when the
  /// device went away (hang-up, I/O error) or the port is not open.
  size_t read_some(char* buf, size_t n, int timeout_ms);

  /// Writes all n bytes (waits up to timeout_ms in total). Returns bytes written.
  size_t write(const char* data, size_t n, int timeout_ms = 100);

 private:
  [[noreturn]] void fail(const std::string& what, int err) const;

  int fd_ = -1;
  std::string device_;
};

}  // namespace whisker_driver
