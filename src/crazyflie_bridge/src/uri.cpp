#include "crazyflie_bridge/uri.hpp"

#include <cctype>
#include <cstdio>
#include <vector>

namespace crazyflie_bridge {
namespace {

[[noreturn]] void fail(const std::string& uri, const std::string& what) {
  throw UriError("link URI '" + uri + "': " + what);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

bool all_digits(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

int to_int(const std::string& uri, const std::string& s, const char* what, long lo, long hi) {
  if (!all_digits(s) || s.size() > 9) fail(uri, std::string(what) + ": '" + s + "' is not a number");
  const long v = std::stol(s);
  if (v < lo || v > hi) {
    fail(uri, std::string(what) + ": " + s + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return static_cast<int>(v);
}

bool parse_flag(const std::string& uri, const std::string& key, const std::string& v) {
  if (v == "1" || v == "true") return true;
  if (v == "0" || v == "false") return false;
  fail(uri, "query " + key + "=" + v + ": expected 0 or 1");
}

}  // namespace

const char* to_string(DataRate r) {
  switch (r) {
    case DataRate::k250K: return "250K";
    case DataRate::k1M: return "1M";
    case DataRate::k2M: return "2M";
  }
  return "?";
}

LinkUri parse_uri(const std::string& uri) {
  LinkUri u;
  u.text = uri;
  const auto sep = uri.find("://");
  if (sep == std::string::npos) fail(uri, "missing scheme (radio://, usb:// or udp://)");
  const std::string scheme = uri.substr(0, sep);
  std::string rest = uri.substr(sep + 3);
  std::string query;
  if (auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  auto for_query = [&](auto&& fn) {
    if (query.empty()) return;
    for (const auto& kv : split(query, '&')) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) fail(uri, "query '" + kv + "': expected key=value");
      fn(kv.substr(0, eq), kv.substr(eq + 1));
    }
  };
  if (scheme == "radio") {
    u.kind = LinkUri::Kind::kRadio;
    while (!rest.empty() && rest.back() == '/') rest.pop_back();
    const auto parts = split(rest, '/');
    const std::string& dev = parts[0];
    if (dev.empty()) fail(uri, "missing dongle number or serial after radio://");
    if (dev.size() < 10 && all_digits(dev)) {
      u.devid = to_int(uri, dev, "dongle number", 0, 255);
    } else {
      u.devid = -1;
      for (char c : dev) {
        if (!std::isxdigit(static_cast<unsigned char>(c))) fail(uri, "dongle serial '" + dev + "': not hexadecimal");
        u.serial += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      }
    }
    if (parts.size() > 1) u.channel = to_int(uri, parts[1], "channel", 0, 125);
    if (parts.size() > 2) {
      if (parts[2] == "250K") {
        u.datarate = DataRate::k250K;
      } else if (parts[2] == "1M") {
        u.datarate = DataRate::k1M;
      } else if (parts[2] == "2M") {
        u.datarate = DataRate::k2M;
      } else {
        fail(uri, "data rate '" + parts[2] + "': expected 250K, 1M or 2M");
      }
    }
    if (parts.size() > 3) {
      const std::string& a = parts[3];
      if (a.empty() || a.size() > 10) fail(uri, "address '" + a + "': expected 1 to 10 hex digits");
      std::string padded = std::string(10 - a.size(), '0') + a;  // cflib '{:0>10}'
      for (size_t i = 0; i < 5; ++i) {
        const std::string byte = padded.substr(2 * i, 2);
        for (char c : byte) {
          if (!std::isxdigit(static_cast<unsigned char>(c))) fail(uri, "address '" + a + "': not hexadecimal");
        }
        u.address[i] = static_cast<uint8_t>(std::stoul(byte, nullptr, 16));
      }
    }
    if (parts.size() > 4) fail(uri, "unexpected path part '" + parts[4] + "'");
    for_query([&](const std::string& k, const std::string& v) {
      if (k == "safelink") {
        u.safelink = parse_flag(uri, k, v);
      } else if (k == "rate_limit") {
        u.rate_limit = to_int(uri, v, "rate_limit", 1, 100000);
      } else {
        fail(uri, "unknown query key '" + k + "' (radio: safelink, rate_limit)");
      }
    });
    return u;
  }
  if (scheme == "usb") {
    u.kind = LinkUri::Kind::kUsb;
    u.devid = to_int(uri, rest, "device number", 0, 255);  // cflib: ^usb://([0-9]+)$
    if (!query.empty()) fail(uri, "usb URIs take no query");
    return u;
  }
  if (scheme == "udp") {
    u.kind = LinkUri::Kind::kUdp;
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos) fail(uri, "expected udp://host:port");
    u.host = rest.substr(0, colon);
    if (u.host.empty()) fail(uri, "empty host");
    u.port = static_cast<uint16_t>(to_int(uri, rest.substr(colon + 1), "port", 1, 65535));
    for_query([&](const std::string& k, const std::string& v) {
      if (k == "handshake") {
        u.handshake = parse_flag(uri, k, v);
      } else {
        fail(uri, "unknown query key '" + k + "' (udp: handshake)");
      }
    });
    return u;
  }
  fail(uri, "unknown scheme '" + scheme + "' (radio, usb or udp)");
}

std::string to_string(const LinkUri& u) {
  switch (u.kind) {
    case LinkUri::Kind::kRadio: {
      char addr[11];
      std::snprintf(addr, sizeof addr, "%02X%02X%02X%02X%02X", u.address[0], u.address[1], u.address[2],
                    u.address[3], u.address[4]);
      std::string s = "radio://" + (u.devid >= 0 ? std::to_string(u.devid) : u.serial) + "/" +
                      std::to_string(u.channel) + "/" + to_string(u.datarate) + "/" + addr;
      s += u.safelink ? "?safelink=1" : "?safelink=0";
      if (u.rate_limit) s += "&rate_limit=" + std::to_string(*u.rate_limit);
      return s;
    }
    case LinkUri::Kind::kUsb: return "usb://" + std::to_string(u.devid);
    case LinkUri::Kind::kUdp: return "udp://" + u.host + ":" + std::to_string(u.port) + (u.handshake ? "?handshake=1" : "");
  }
  return "";
}

}  // namespace crazyflie_bridge
