#include "crazyflie_bridge/client.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace crazyflie_bridge {

CrazyflieClient::CrazyflieClient(Link& link, ClientOptions options) : link_(link), opt_(std::move(options)) {}

CrtpPacket CrazyflieClient::request(const CrtpPacket& pk, uint8_t port_no, uint8_t channel,
                                    const std::vector<uint8_t>& prefix, const char* what, int retries) {
  if (retries < 0) retries = opt_.retries;
  for (int attempt = 0; attempt <= retries; ++attempt) {
    if (attempt > 0) ++stats_.resends;
    link_.send(pk);
    const auto deadline = std::chrono::steady_clock::now() + opt_.reply_timeout;
    for (;;) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) break;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now + std::chrono::microseconds(999));
      auto in = link_.receive(left);
      if (!in) break;
      bool match = in->port == port_no && in->channel == channel && in->size >= prefix.size();
      for (size_t i = 0; match && i < prefix.size(); ++i) match = in->data[i] == prefix[i];
      if (match) return *in;
      dispatch(*in);
    }
  }
  throw ClientError(std::string("no answer to ") + what + " from " + link_.uri() + " after " +
                    std::to_string(retries + 1) + " tries of " + std::to_string(opt_.reply_timeout.count()) + " ms");
}

void CrazyflieClient::dispatch(const CrtpPacket& pk) {
  if (pk.port == port::kLog && pk.channel == logp::kChanData) {
    try {
      const auto d = logp::decode_data(pk);
      auto it = blocks_.find(d.block_id);
      if (it == blocks_.end()) {
        ++stats_.log_unknown_block;
        return;
      }
      LogSample s;
      s.block_id = d.block_id;
      s.timestamp_ms = d.timestamp_ms;
      s.names = it->second.names;
      logp::decode_values(d, it->second.types, s.values);
      s.received = std::chrono::steady_clock::now();
      Block& b = it->second;
      if (b.have_last && b.period_ms > 0) {
        const uint32_t dt = (d.timestamp_ms - b.last_ts) & 0xFFFFFF;  // 24-bit wrap
        const uint32_t slots = (dt + b.period_ms / 2) / b.period_ms;
        if (slots > 1 && slots < 100000) stats_.log_missed += slots - 1;  // larger: firmware restart
      }
      b.have_last = true;
      b.last_ts = d.timestamp_ms;
      pending_.push_back(std::move(s));
      ++stats_.log_samples;
    } catch (const CrtpError&) {
      ++stats_.log_decode_errors;
    }
    return;
  }
  ++stats_.other_packets;
}

std::optional<LogSample> CrazyflieClient::poll(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (pending_.empty()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    auto in = link_.receive(std::max(left, std::chrono::milliseconds(0)));
    if (!in) return std::nullopt;
    dispatch(*in);
    if (std::chrono::steady_clock::now() >= deadline && pending_.empty()) return std::nullopt;
  }
  LogSample s = std::move(pending_.front());
  pending_.pop_front();
  return s;
}

bool CrazyflieClient::load_cache(const std::string& kind, uint32_t crc, uint16_t count,
                                 std::vector<toc::Item>& items) const {
  if (opt_.toc_cache_dir.empty()) return false;
  char name[32];
  std::snprintf(name, sizeof name, "%08X.%s.toc", crc, kind.c_str());
  std::ifstream in(opt_.toc_cache_dir + "/" + name);
  if (!in) return false;
  std::vector<toc::Item> out;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    toc::Item it;
    unsigned id = 0, type = 0;
    if (!(ls >> id >> type >> it.group >> it.name)) return false;  // corrupt cache: download again
    it.id = static_cast<uint16_t>(id);
    it.type_byte = static_cast<uint8_t>(type);
    out.push_back(it);
  }
  if (out.size() != count) return false;
  items = std::move(out);
  return true;
}

void CrazyflieClient::store_cache(const std::string& kind, uint32_t crc, const std::vector<toc::Item>& items) const {
  if (opt_.toc_cache_dir.empty()) return;
  char name[32];
  std::snprintf(name, sizeof name, "%08X.%s.toc", crc, kind.c_str());
  std::ofstream out(opt_.toc_cache_dir + "/" + name);
  for (const auto& it : items) out << it.id << ' ' << unsigned(it.type_byte) << ' ' << it.group << ' ' << it.name << '\n';
}

std::vector<toc::Item> CrazyflieClient::fetch_toc(uint8_t port_no, uint32_t& crc, bool& cached) {
  const char* kind = port_no == port::kLog ? "log" : "param";
  const auto info_pk = request(toc::info_request(port_no), port_no, toc::kChannel, {toc::kCmdInfoV2},
                               port_no == port::kLog ? "log TOC info" : "param TOC info");
  const auto info = toc::decode_info(info_pk);
  crc = info.crc;
  std::vector<toc::Item> items;
  cached = load_cache(kind, info.crc, info.count, items);
  if (cached) return items;
  for (uint16_t id = 0; id < info.count; ++id) {
    const auto pk = request(toc::item_request(port_no, id), port_no, toc::kChannel,
                            {toc::kCmdItemV2, static_cast<uint8_t>(id & 0xFF), static_cast<uint8_t>(id >> 8)},
                            port_no == port::kLog ? "log TOC item" : "param TOC item");
    items.push_back(toc::decode_item(pk));
  }
  store_cache(kind, info.crc, items);
  return items;
}

void CrazyflieClient::connect() {
  // cflib platformservice: link source "Bitcraze Crazyflie", then protocol version.
  const auto src = request(platform::link_source_request(), port::kLinkCtrl, platform::kLinkChanSource, {}, "link source");
  if (src.size < 18 || std::memcmp(src.data.data(), platform::kSourceMagic, 18) != 0) {
    throw ClientError("link source answer from " + link_.uri() + " is not 'Bitcraze Crazyflie': " + src.to_string());
  }
  protocol_version_ = platform::decode_protocol_version(request(platform::protocol_version_request(), port::kPlatform,
                                                                platform::kChanVersion, {platform::kVersionGetProtocol},
                                                                "protocol version"));
  if (protocol_version_ < commander::kMinProtocolVersion) {
    // cflib (toc.py, log.py, param.py) speaks the v1 TOC/log/param packets to
    // such firmware; this client has only the v2 ones, so no generation fits.
    throw ClientError("Crazyflie at " + link_.uri() + " speaks CRTP protocol version " +
                      std::to_string(protocol_version_) + ": not supported (the oldest supported is " +
                      std::to_string(commander::kMinProtocolVersion) +
                      ", where cflib switches to the v2 TOC/log/param packets this client needs); update the firmware");
  }
  // Firmware version (platform VERSION_GET_FIRMWARE, cflib platformservice.py;
  // firmware platformservice.c versionCommandProcess(): [1, V_STAG text]):
  // informational, for the log and the metrics; a firmware that does not answer
  // it keeps an empty string (firmware_version_answered() false), it does not
  // fail the connection. Three tries, not opt_.retries: it is not needed to fly.
  try {
    const auto fw = request(platform::firmware_version_request(), port::kPlatform, platform::kChanVersion,
                            {platform::kVersionGetFirmware}, "firmware version", 2);
    firmware_version_.assign(reinterpret_cast<const char*>(fw.data.data()) + 1, fw.size - 1);
    const auto nul = firmware_version_.find('\0');
    if (nul != std::string::npos) firmware_version_.resize(nul);
    firmware_version_answered_ = true;
  } catch (const ClientError&) {
    firmware_version_.clear();
    firmware_version_answered_ = false;
  }
  const auto reset = logp::decode_control_reply(
      request(logp::reset(), port::kLog, logp::kChanSettings, {logp::kCmdReset}, "log reset"));
  (void)reset;
  blocks_.clear();
  log_toc_ = fetch_toc(port::kLog, log_crc_, log_toc_cached_);
  bool param_cached = false;
  param_toc_ = fetch_toc(port::kParam, param_crc_, param_cached);
  log_index_.clear();
  param_index_.clear();
  for (size_t i = 0; i < log_toc_.size(); ++i) log_index_[log_toc_[i].full_name()] = i;
  for (size_t i = 0; i < param_toc_.size(); ++i) param_index_[param_toc_[i].full_name()] = i;
}

const toc::Item* CrazyflieClient::log_item(const std::string& n) const {
  auto it = log_index_.find(n);
  return it == log_index_.end() ? nullptr : &log_toc_[it->second];
}
const toc::Item* CrazyflieClient::param_item(const std::string& n) const {
  auto it = param_index_.find(n);
  return it == param_index_.end() ? nullptr : &param_toc_[it->second];
}

uint8_t CrazyflieClient::start_log_block(const std::vector<std::string>& names, uint16_t period_ms) {
  const uint8_t id = create_log_block(names, period_ms);
  start_created_log_block(id);
  return id;
}

uint8_t CrazyflieClient::create_log_block(const std::vector<std::string>& names, uint16_t period_ms) {
  Block b;
  std::vector<logp::BlockVariable> vars;
  size_t bytes = 0;
  for (const auto& n : names) {
    const auto* item = log_item(n);
    if (!item) throw ClientError("log variable '" + n + "' is not in the log TOC of " + link_.uri());
    const uint8_t type = item->type_byte & 0x0F;
    if (!logp::valid_type(type)) throw ClientError("log variable '" + n + "' has unknown type " + std::to_string(type));
    bytes += logp::type_size(type);
    vars.push_back({item->id, static_cast<logp::Type>(type), static_cast<logp::Type>(type)});
    b.names.push_back(n);
    b.types.push_back(static_cast<logp::Type>(type));
  }
  if (bytes > logp::kMaxBlockBytes) {
    throw ClientError("log block of " + std::to_string(names.size()) + " variables needs " + std::to_string(bytes) +
                      " bytes > 26");
  }
  if (period_ms == 0) throw ClientError("log block period must be > 0 ms");
  const uint8_t id = next_block_++;
  for (const auto& pk : logp::create_block_v2(id, vars)) {
    const auto rep = logp::decode_control_reply(request(pk, port::kLog, logp::kChanSettings, {pk.data[0], id}, "log block create"));
    if (rep.status != 0 && !(rep.status == EEXIST && pk.data[0] == logp::kCmdCreateBlockV2)) {
      throw ClientError("creating log block " + std::to_string(id) + " failed: " + std::strerror(rep.status));
    }
  }
  b.period_ms = period_ms;
  blocks_[id] = b;
  return id;
}

void CrazyflieClient::start_created_log_block(uint8_t id) {
  auto it = blocks_.find(id);
  if (it == blocks_.end()) throw ClientError("starting log block " + std::to_string(id) + ": no such block was created");
  it->second.have_last = false;  // a restart's pause is no loss (reset before its first packet can arrive)
  const auto rep = logp::decode_control_reply(request(logp::start_block_v2(id, static_cast<uint16_t>(it->second.period_ms)),
                                                      port::kLog, logp::kChanSettings, {logp::kCmdStartBlockV2, id},
                                                      "log block start"));
  if (rep.status != 0) throw ClientError("starting log block " + std::to_string(id) + " failed: " + std::strerror(rep.status));
}

void CrazyflieClient::stop_log_block(uint8_t id) {
  const auto rep = logp::decode_control_reply(
      request(logp::stop_block(id), port::kLog, logp::kChanSettings, {logp::kCmdStopBlock, id}, "log block stop"));
  if (rep.status != 0) throw ClientError("stopping log block " + std::to_string(id) + " failed: " + std::strerror(rep.status));
}

double CrazyflieClient::read_param(const std::string& n) {
  const auto* item = param_item(n);
  if (!item) throw ClientError("parameter '" + n + "' is not in the param TOC of " + link_.uri());
  const auto pk = request(param::read_request(item->id), port::kParam, param::kChanRead,
                          {static_cast<uint8_t>(item->id & 0xFF), static_cast<uint8_t>(item->id >> 8)}, "param read");
  const auto r = param::decode_read_reply(pk, item->type_byte);
  if (r.status != 0) throw ClientError("reading parameter '" + n + "' failed: " + std::strerror(r.status));
  return r.value;
}

double CrazyflieClient::write_param(const std::string& n, double value) {
  const auto* item = param_item(n);
  if (!item) throw ClientError("parameter '" + n + "' is not in the param TOC of " + link_.uri());
  if (item->type_byte & param::kFlagReadOnly) throw ClientError("parameter '" + n + "' is read-only");
  const auto pk = request(param::write_request(item->id, item->type_byte, value), port::kParam, param::kChanWrite,
                          {static_cast<uint8_t>(item->id & 0xFF), static_cast<uint8_t>(item->id >> 8)}, "param write");
  return param::decode_write(pk, item->type_byte).value;
}

}  // namespace crazyflie_bridge
