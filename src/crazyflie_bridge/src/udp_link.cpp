#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "crazyflie_bridge/link.hpp"

namespace crazyflie_bridge {
namespace {

std::string errno_text() { return std::strerror(errno); }

bool wait_readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  return r > 0 && (p.revents & POLLIN);
}

}  // namespace

UdpLink::UdpLink(const LinkUri& uri) : uri_(uri) {
  if (uri.kind != LinkUri::Kind::kUdp) throw LinkError("UdpLink: '" + uri.text + "' is not a udp:// URI");
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const int rc = ::getaddrinfo(uri.host.c_str(), std::to_string(uri.port).c_str(), &hints, &res);
  if (rc != 0 || !res) throw LinkError("udp link " + to_string(uri) + ": cannot resolve host: " + gai_strerror(rc));
  fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) {
    ::freeaddrinfo(res);
    throw LinkError("udp link " + to_string(uri) + ": socket: " + errno_text());
  }
  if (::connect(fd_, res->ai_addr, res->ai_addrlen) != 0) {
    const std::string e = errno_text();
    ::freeaddrinfo(res);
    ::close(fd_);
    throw LinkError("udp link " + to_string(uri) + ": connect: " + e);
  }
  ::freeaddrinfo(res);
  if (uri.handshake) {
    const uint8_t hello = 0xF3;
    send_raw(&hello, 1);
  }
}

UdpLink::~UdpLink() {
  if (fd_ >= 0) {
    if (uri_.handshake) {
      const uint8_t bye = 0xF4;
      (void)::send(fd_, &bye, 1, 0);
    }
    ::close(fd_);
  }
}

void UdpLink::send_raw(const uint8_t* data, size_t n) {
  if (::send(fd_, data, n, 0) < 0) {
    ++stats_.send_errors;  // e.g. ECONNREFUSED after an ICMP port unreachable
  }
}

void UdpLink::send(const CrtpPacket& pk) {
  uint8_t buf[32];
  const size_t n = pk.encode(buf);
  send_raw(buf, n);
  ++stats_.packets_sent;
}

std::optional<CrtpPacket> UdpLink::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (!wait_readable(fd_, static_cast<int>(std::max<int64_t>(0, left.count())))) return std::nullopt;
    uint8_t buf[256];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n < 0) {
      if (errno == ECONNREFUSED) {  // nobody listening yet: not fatal for UDP
        ++stats_.send_errors;
        continue;
      }
      throw LinkError("udp link " + to_string(uri_) + ": recv: " + errno_text());
    }
    auto pk = CrtpPacket::try_decode(buf, static_cast<size_t>(n));
    if (!pk) {
      ++stats_.malformed;
      continue;
    }
    if (pk->is_null()) {
      ++stats_.null_received;
      continue;
    }
    ++stats_.packets_received;
    return pk;
  }
}

UdpServer::UdpServer(uint16_t port, const std::string& bind_address) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) throw LinkError("udp server: socket: " + errno_text());
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (::inet_pton(AF_INET, bind_address.c_str(), &a.sin_addr) != 1) {
    ::close(fd_);
    throw LinkError("udp server: bind address '" + bind_address + "' is not an IPv4 address");
  }
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string e = errno_text();
    ::close(fd_);
    throw LinkError("udp server: cannot bind " + bind_address + ":" + std::to_string(port) + ": " + e +
                    (errno == EADDRINUSE ? " (another simulated Crazyflie uses this port?)" : ""));
  }
  socklen_t len = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

UdpServer::~UdpServer() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<CrtpPacket> UdpServer::receive(std::chrono::microseconds timeout) {
  const int ms = static_cast<int>((timeout.count() + 999) / 1000);
  if (!wait_readable(fd_, ms)) return std::nullopt;
  uint8_t buf[256];
  sockaddr_storage from{};
  socklen_t len = sizeof from;
  const ssize_t n = ::recvfrom(fd_, buf, sizeof buf, 0, reinterpret_cast<sockaddr*>(&from), &len);
  if (n < 0) return std::nullopt;
  const auto now = std::chrono::steady_clock::now();
  const bool owned = has_peer_ && now - peer_heard_ <= std::chrono::milliseconds(kPeerIdleMs);
  const bool same = has_peer_ && len == peer_len_ && std::memcmp(peer_, &from, len) == 0;
  const bool null_packet = n == 1 && buf[0] == 0xFF;
  if (!(owned && same)) {
    if (null_packet) {
      // A probe (cflib's scan, `tactile scan`): answered to its sender only, and it does
      // not take the link (a scan before a flight must not hold it for kPeerIdleMs).
      if (owned) ++foreign_;
      const uint8_t answer = 0xFF;
      ::sendto(fd_, &answer, 1, 0, reinterpret_cast<const sockaddr*>(&from), len);
      return std::nullopt;
    }
    if (owned) {
      // Another client while the link is owned: dropped and counted, never answered to
      // the owner (a second client stole the owner's log packets before).
      ++foreign_;
      return std::nullopt;
    }
    std::memcpy(peer_, &from, std::min<size_t>(len, sizeof peer_));
    peer_len_ = len;
    has_peer_ = true;
  }
  peer_heard_ = now;
  if (n == 1 && buf[0] == 0xF3) {
    ++connects_;
    return std::nullopt;
  }
  if (n == 1 && buf[0] == 0xF4) {
    ++disconnects_;
    has_peer_ = false;  // the link is free for the next client
    return std::nullopt;
  }
  auto pk = CrtpPacket::try_decode(buf, static_cast<size_t>(n));
  if (!pk) {
    ++stats_.malformed;
    return std::nullopt;
  }
  ++stats_.packets_received;
  return pk;
}

void UdpServer::send(const CrtpPacket& pk) {
  if (!has_peer_) {
    ++stats_.send_errors;
    return;
  }
  uint8_t buf[32];
  const size_t n = pk.encode(buf);
  if (::sendto(fd_, buf, n, 0, reinterpret_cast<const sockaddr*>(peer_), peer_len_) < 0) {
    ++stats_.send_errors;
    return;
  }
  ++stats_.packets_sent;
}

}  // namespace crazyflie_bridge
