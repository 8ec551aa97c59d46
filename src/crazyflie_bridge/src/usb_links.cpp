// Crazyradio and Crazyflie-USB links over libusb-1.0, following cflib
// drivers/crazyradio.py, crtp/radiodriver.py, drivers/cfusb.py.
#include <libusb.h>

#include <cstdio>
#include <thread>

#include "crazyflie_bridge/link.hpp"
#include "crazyflie_bridge/protocol.hpp"

namespace crazyflie_bridge {
namespace {

constexpr unsigned kCtrlTimeoutMs = 1000;  // cflib: timeout=1000
constexpr unsigned kRadioBulkTimeoutMs = 1000;
constexpr unsigned kCfUsbBulkTimeoutMs = 20;  // cflib cfusb: timeout=20

std::string usb_error(int rc) { return std::string(libusb_error_name(rc)) + " (" + libusb_strerror(static_cast<libusb_error>(rc)) + ")"; }

struct Context {
  libusb_context* ctx = nullptr;
  Context() {
    const int rc = libusb_init(&ctx);
    if (rc != 0) throw LinkError("libusb_init: " + usb_error(rc));
  }
  ~Context() {
    if (ctx) libusb_exit(ctx);
  }
};

/// Devices with vid:pid, in bus order.
std::vector<libusb_device*> find(libusb_context* ctx, uint16_t vid, uint16_t pid, libusb_device**& list) {
  std::vector<libusb_device*> out;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == vid && d.idProduct == pid) out.push_back(list[i]);
  }
  return out;
}

std::string serial_of(libusb_device_handle* h, const libusb_device_descriptor& d) {
  if (!d.iSerialNumber) return "";
  unsigned char buf[64] = {};
  const int n = libusb_get_string_descriptor_ascii(h, d.iSerialNumber, buf, sizeof buf);
  return n > 0 ? std::string(reinterpret_cast<char*>(buf), static_cast<size_t>(n)) : "";
}

}  // namespace

std::string usb_error_message(const std::string& what, int rc) {
  std::string s = what + ": " + usb_error(rc);
  if (rc == LIBUSB_ERROR_ACCESS) s += " — no permission: install the Bitcraze udev rules (see the crazyflie_bridge README)";
  if (rc == LIBUSB_ERROR_BUSY) s += " — the device is busy: another program (cfclient, another bridge) has claimed it";
  if (rc == LIBUSB_ERROR_NO_DEVICE) s += " — the device was unplugged";
  return s;
}

struct CrazyradioLink::Usb {
  Context ctx;
  libusb_device_handle* h = nullptr;
  ~Usb() {
    if (h) {
      libusb_release_interface(h, 0);
      libusb_close(h);
    }
  }
};

CrazyradioLink::CrazyradioLink(const LinkUri& uri) : usb_(std::make_unique<Usb>()), uri_(uri) {
  if (uri.kind != LinkUri::Kind::kRadio) throw LinkError("CrazyradioLink: '" + uri.text + "' is not a radio:// URI");
  const std::string name = "Crazyradio for " + to_string(uri);
  libusb_device** list = nullptr;
  auto devs = find(usb_->ctx.ctx, radio::kVendorId, radio::kProductId, list);
  libusb_device* dev = nullptr;
  if (uri.devid >= 0) {
    if (static_cast<size_t>(uri.devid) < devs.size()) dev = devs[static_cast<size_t>(uri.devid)];
  } else {
    for (auto* d : devs) {
      libusb_device_handle* h = nullptr;
      libusb_device_descriptor desc{};
      libusb_get_device_descriptor(d, &desc);
      if (libusb_open(d, &h) == 0) {
        const bool match = serial_of(h, desc) == uri.serial;
        libusb_close(h);
        if (match) {
          dev = d;
          break;
        }
      }
    }
  }
  if (!dev) {
    libusb_free_device_list(list, 1);
    throw LinkError(name + ": no Crazyradio found (USB 1915:7777, " + std::to_string(devs.size()) +
                    " connected) — is the dongle plugged in?");
  }
  libusb_device_descriptor desc{};
  libusb_get_device_descriptor(dev, &desc);
  version_ = desc.bcdDevice;
  int rc = libusb_open(dev, &usb_->h);
  libusb_free_device_list(list, 1);
  if (rc != 0) throw LinkError(usb_error_message(name + ": open", rc));
  rc = libusb_set_configuration(usb_->h, 1);  // cflib: set_configuration(1)
  if (rc != 0 && rc != LIBUSB_ERROR_BUSY) throw LinkError(usb_error_message(name + ": set configuration", rc));
  rc = libusb_claim_interface(usb_->h, 0);
  if (rc != 0) throw LinkError(usb_error_message(name + ": claim interface", rc));
  if (version_ < 0x0003) throw LinkError(name + ": Crazyradio firmware older than 0.3 is not supported");
  for (const auto& r : radio::init_sequence(version_, uri)) {
    rc = libusb_control_transfer(usb_->h, LIBUSB_REQUEST_TYPE_VENDOR | LIBUSB_ENDPOINT_OUT, r.request, r.value, r.index,
                                 const_cast<unsigned char*>(r.data.data()), static_cast<uint16_t>(r.data.size()),
                                 kCtrlTimeoutMs);
    if (rc < 0) throw LinkError(usb_error_message(name + ": vendor request " + std::to_string(r.request), rc));
  }
  // Safelink handshake (cflib: up to 10 tries of FF 05 01, echoed back).
  if (uri.safelink) {
    for (int i = 0; i < 10 && !safelink_.enabled(); ++i) {
      unsigned char out[3] = {0xFF, 0x05, 0x01};
      int sent = 0;
      rc = libusb_bulk_transfer(usb_->h, radio::kEndpointOut, out, 3, &sent, kRadioBulkTimeoutMs);
      if (rc != 0) throw LinkError(usb_error_message(name + ": safelink handshake", rc));
      unsigned char in[64];
      int got = 0;
      rc = libusb_bulk_transfer(usb_->h, radio::kEndpointIn, in, sizeof in, &got, kRadioBulkTimeoutMs);
      if (rc != 0) throw LinkError(usb_error_message(name + ": safelink handshake", rc));
      if (radio::is_safelink_echo(radio::parse_ack(in, static_cast<size_t>(got)))) safelink_.enable();
    }
  }
}

CrazyradioLink::~CrazyradioLink() = default;

void CrazyradioLink::transfer(const std::vector<uint8_t>& out_bytes) {
  std::vector<uint8_t> out = out_bytes;
  out[0] = safelink_.apply(out[0]);
  int sent = 0;
  int rc = libusb_bulk_transfer(usb_->h, radio::kEndpointOut, out.data(), static_cast<int>(out.size()), &sent,
                                kRadioBulkTimeoutMs);
  if (rc == LIBUSB_ERROR_NO_DEVICE || rc == LIBUSB_ERROR_IO || rc == LIBUSB_ERROR_PIPE) {
    throw LinkError(usb_error_message("Crazyradio for " + to_string(uri_) + ": send", rc) +
                    " (error communicating with the Crazyradio, it has probably been unplugged)");
  }
  if (rc != 0) {
    ++stats_.send_errors;
    return;
  }
  unsigned char in[64];
  int got = 0;
  rc = libusb_bulk_transfer(usb_->h, radio::kEndpointIn, in, sizeof in, &got, kRadioBulkTimeoutMs);
  if (rc == LIBUSB_ERROR_NO_DEVICE) {
    throw LinkError(usb_error_message("Crazyradio for " + to_string(uri_) + ": receive", rc));
  }
  if (rc != 0) {
    ++stats_.send_errors;
    return;
  }
  const auto ack = radio::parse_ack(in, static_cast<size_t>(got));
  if (!safelink_.on_ack(ack)) ++stats_.safelink_out_of_sequence;
  stats_.retries += static_cast<uint64_t>(ack.retry);
  if (!ack.ack) {
    ++stats_.ack_missing;
    if (++lost_in_a_row_ >= radio::kRetriesBeforeDisconnect) {
      throw LinkError("Crazyradio for " + to_string(uri_) + ": too many packets lost (" +
                      std::to_string(lost_in_a_row_) + " transfers without ACK): Crazyflie off or out of range");
    }
    return;
  }
  lost_in_a_row_ = 0;
  ++stats_.acks;
  if (const auto rssi = radio::uplink_rssi(ack)) {
    stats_.uplink_rssi = *rssi;
    ++stats_.rssi_reports;
  }
  if (!ack.data.empty()) {
    auto pk = CrtpPacket::try_decode(ack.data.data(), ack.data.size());
    if (!pk) {
      ++stats_.malformed;
    } else if (!pk->is_null()) {
      ++stats_.packets_received;
      in_.push_back(*pk);
    }
  }
}

void CrazyradioLink::send(const CrtpPacket& pk) {
  // cflib resends a packet that was not acknowledged; so do we (bounded).
  const auto bytes = pk.encode();
  for (int attempt = 0; attempt < 10; ++attempt) {
    const uint64_t before = stats_.acks;
    transfer(bytes);
    if (stats_.acks != before) break;
  }
  ++stats_.packets_sent;
}

std::optional<CrtpPacket> CrazyradioLink::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const std::vector<uint8_t> null{kNullHeader};
  int empty = 0;
  while (in_.empty()) {
    transfer(null);
    ++stats_.null_sent;
    if (!in_.empty()) break;
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    // cflib: after 10 empty answers poll every 10 ms; rate_limit caps the poll rate.
    if (uri_.rate_limit) {
      std::this_thread::sleep_for(std::chrono::microseconds(1000000 / *uri_.rate_limit));
    } else if (++empty > 10) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  CrtpPacket pk = in_.front();
  in_.pop_front();
  return pk;
}

// ---------------------------------------------------------------------------

struct CfUsbLink::Usb {
  Context ctx;
  libusb_device_handle* h = nullptr;
  ~Usb() {
    if (h) {
      // Back to the default (non-CRTP) USB mode, as cflib's close does implicitly on reset.
      libusb_control_transfer(h, LIBUSB_REQUEST_TYPE_VENDOR | LIBUSB_ENDPOINT_OUT, 0x01, 0x01, 0, nullptr, 0, 100);
      libusb_release_interface(h, 0);
      libusb_close(h);
    }
  }
};

CfUsbLink::CfUsbLink(const LinkUri& uri) : usb_(std::make_unique<Usb>()), uri_(uri) {
  if (uri.kind != LinkUri::Kind::kUsb) throw LinkError("CfUsbLink: '" + uri.text + "' is not a usb:// URI");
  const std::string name = "Crazyflie on " + to_string(uri);
  libusb_device** list = nullptr;
  auto devs = find(usb_->ctx.ctx, radio::kCfUsbVendorId, radio::kCfUsbProductId, list);
  if (static_cast<size_t>(uri.devid) >= devs.size()) {
    libusb_free_device_list(list, 1);
    throw LinkError(name + ": no Crazyflie found on USB (0483:5740, " + std::to_string(devs.size()) + " connected)");
  }
  int rc = libusb_open(devs[static_cast<size_t>(uri.devid)], &usb_->h);
  libusb_free_device_list(list, 1);
  if (rc != 0) throw LinkError(usb_error_message(name + ": open", rc));
  libusb_set_auto_detach_kernel_driver(usb_->h, 1);
  rc = libusb_claim_interface(usb_->h, 0);
  if (rc != 0) throw LinkError(usb_error_message(name + ": claim interface", rc));
  // cflib cfusb.set_crtp_to_usb(True): vendor request 0x01, value 0x01, index 1.
  rc = libusb_control_transfer(usb_->h, LIBUSB_REQUEST_TYPE_VENDOR | LIBUSB_ENDPOINT_OUT, 0x01, 0x01, 1, nullptr, 0,
                               kCtrlTimeoutMs);
  if (rc < 0) throw LinkError(usb_error_message(name + ": enable CRTP over USB", rc));
}

CfUsbLink::~CfUsbLink() = default;

void CfUsbLink::send(const CrtpPacket& pk) {
  auto bytes = pk.encode();
  int sent = 0;
  const int rc = libusb_bulk_transfer(usb_->h, radio::kEndpointOut, bytes.data(), static_cast<int>(bytes.size()), &sent,
                                      kCfUsbBulkTimeoutMs);
  if (rc == LIBUSB_ERROR_NO_DEVICE) throw LinkError(usb_error_message("Crazyflie on " + to_string(uri_) + ": send", rc));
  if (rc != 0) {
    ++stats_.send_errors;
    return;
  }
  ++stats_.packets_sent;
}

std::optional<CrtpPacket> CfUsbLink::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  do {
    unsigned char in[64];
    int got = 0;
    const int rc = libusb_bulk_transfer(usb_->h, radio::kEndpointIn, in, sizeof in, &got, kCfUsbBulkTimeoutMs);
    if (rc == LIBUSB_ERROR_NO_DEVICE || rc == LIBUSB_ERROR_PIPE || rc == LIBUSB_ERROR_IO) {
      throw LinkError(usb_error_message("Crazyflie on " + to_string(uri_) + ": receive", rc) + " (Crazyflie disconnected)");
    }
    if (rc == 0 && got > 0) {
      auto pk = CrtpPacket::try_decode(in, static_cast<size_t>(got));
      if (!pk) {
        ++stats_.malformed;
      } else if (!pk->is_null()) {
        ++stats_.packets_received;
        return pk;
      }
    }
  } while (std::chrono::steady_clock::now() < deadline);
  return std::nullopt;
}

// ---------------------------------------------------------------------------

std::unique_ptr<Link> open_link(const std::string& text) {
  const LinkUri uri = parse_uri(text);
  switch (uri.kind) {
    case LinkUri::Kind::kUdp: return std::make_unique<UdpLink>(uri);
    case LinkUri::Kind::kRadio: return std::make_unique<CrazyradioLink>(uri);
    case LinkUri::Kind::kUsb: return std::make_unique<CfUsbLink>(uri);
  }
  throw LinkError("unsupported URI " + text);
}

std::vector<FoundDevice> scan(const std::string& udp_host) {
  std::vector<FoundDevice> found;
  try {
    Context ctx;
    libusb_device** list = nullptr;
    auto radios = find(ctx.ctx, radio::kVendorId, radio::kProductId, list);
    for (size_t i = 0; i < radios.size(); ++i) {
      libusb_device_descriptor d{};
      libusb_get_device_descriptor(radios[i], &d);
      char ver[16];
      std::snprintf(ver, sizeof ver, "%x.%x", d.bcdDevice >> 8, d.bcdDevice & 0xFF);
      found.push_back({"radio://" + std::to_string(i), std::string("Crazyradio, firmware ") + ver});
    }
    libusb_free_device_list(list, 1);
    auto cfs = find(ctx.ctx, radio::kCfUsbVendorId, radio::kCfUsbProductId, list);
    for (size_t i = 0; i < cfs.size(); ++i) found.push_back({"usb://" + std::to_string(i), "Crazyflie on USB"});
    libusb_free_device_list(list, 1);
  } catch (const LinkError& e) {
    found.push_back({"", std::string("USB scan unavailable: ") + e.what()});
  }
  for (int i = 0; i < 10; ++i) {
    const std::string uri = "udp://" + udp_host + ":" + std::to_string(19850 + i);
    try {
      UdpLink link(parse_uri(uri));
      const uint8_t probe = 0xFF;
      link.send_raw(&probe, 1);
      // Any answer (the simulated firmware echoes the null packet) marks a device.
      bool any = false;
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      while (!any && std::chrono::steady_clock::now() < deadline) {
        try {
          link.receive(std::chrono::milliseconds(20));
        } catch (const LinkError&) {
          break;
        }
        const auto& st = link.statistics();
        any = st.packets_received > 0 || st.null_received > 0 || st.malformed > 0;
      }
      if (any) found.push_back({uri, "simulated Crazyflie"});
    } catch (const LinkError&) {
    }
  }
  return found;
}

}  // namespace crazyflie_bridge
