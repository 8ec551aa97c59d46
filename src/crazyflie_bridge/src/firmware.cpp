#include "crazyflie_bridge/firmware.hpp"

#include <cerrno>

namespace crazyflie_bridge {
namespace {
uint32_t toc_crc(const std::vector<toc::Item>& items) {
  uint32_t crc = 0;
  for (const auto& it : items) {
    crc = toc::crc32(&it.type_byte, 1, crc);
    const std::string s = it.group + '\0' + it.name + '\0';
    crc = toc::crc32(reinterpret_cast<const uint8_t*>(s.data()), s.size(), crc);
  }
  return crc;
}
}  // namespace

FirmwareEmulator::FirmwareEmulator() : FirmwareEmulator(Options{}) {}
FirmwareEmulator::FirmwareEmulator(const Options& options) : opt_(options), armed_(options.auto_arm) {}

uint16_t FirmwareEmulator::add_log_variable(const std::string& group, const std::string& name, logp::Type type) {
  if (group.size() + name.size() + 2 > kCrtpMaxPayload - 4) throw std::invalid_argument("log variable name too long: " + group + "." + name);
  LogVar v;
  v.item.id = static_cast<uint16_t>(log_vars_.size());
  v.item.type_byte = static_cast<uint8_t>(type);
  v.item.group = group;
  v.item.name = name;
  log_vars_.push_back(v);
  log_values_.push_back(0.0);
  return v.item.id;
}

uint16_t FirmwareEmulator::add_param(const std::string& group, const std::string& name, uint8_t type, double value,
                                     bool read_only) {
  if (!param::valid_type(type)) throw std::invalid_argument("param " + group + "." + name + ": invalid type");
  if (group.size() + name.size() + 2 > kCrtpMaxPayload - 4) throw std::invalid_argument("param name too long: " + group + "." + name);
  Param p;
  p.item.id = static_cast<uint16_t>(params_.size());
  p.item.type_byte = static_cast<uint8_t>(type | (read_only ? param::kFlagReadOnly : 0));
  p.item.group = group;
  p.item.name = name;
  p.value = value;
  params_.push_back(p);
  return p.item.id;
}

std::optional<uint16_t> FirmwareEmulator::param_id(const std::string& full) const {
  for (const auto& p : params_) {
    if (p.item.full_name() == full) return p.item.id;
  }
  return std::nullopt;
}
std::optional<uint16_t> FirmwareEmulator::log_id(const std::string& full) const {
  for (const auto& v : log_vars_) {
    if (v.item.full_name() == full) return v.item.id;
  }
  return std::nullopt;
}

uint32_t FirmwareEmulator::log_toc_crc() const {
  std::vector<toc::Item> items;
  for (const auto& v : log_vars_) items.push_back(v.item);
  return toc_crc(items);
}
uint32_t FirmwareEmulator::param_toc_crc() const {
  std::vector<toc::Item> items;
  for (const auto& p : params_) items.push_back(p.item);
  return toc_crc(items);
}

void FirmwareEmulator::reply(std::vector<CrtpPacket>& out, const CrtpPacket& pk) {
  out.push_back(pk);
  ++stats_.replies;
}

void FirmwareEmulator::on_packet(const CrtpPacket& pk, uint32_t now_ms, std::vector<CrtpPacket>& out) {
  ++stats_.packets_in;
  try {
    if (pk.is_null()) {
      reply(out, CrtpPacket::null_packet());  // keep-alive / cflib UDP scan probe
      return;
    }
    if (on_arming(pk, out)) return;
    switch (pk.port) {
      case port::kLinkCtrl:
        if (pk.channel == platform::kLinkChanEcho) {
          reply(out, pk);  // cflib link_statistics ping
        } else if (pk.channel == platform::kLinkChanSource) {
          reply(out, platform::link_source_reply());
        } else {
          ++stats_.unknown;
        }
        return;
      case port::kPlatform:
        if (pk.channel == platform::kChanVersion && pk.size >= 1) {
          if (pk.data[0] == platform::kVersionGetProtocol) {
            reply(out, platform::protocol_version_reply(opt_.protocol_version));
          } else if (pk.data[0] == platform::kVersionGetFirmware) {
            reply(out, platform::firmware_version_reply(opt_.firmware_version));
          } else {
            ++stats_.unknown;
          }
        } else {
          ++stats_.unknown;
        }
        return;
      case port::kMem:
        if (pk.channel == mem::kChanInfo && pk.size >= 1 && pk.data[0] == mem::kCmdInfoNbr) {
          reply(out, mem::count_reply(0));
        } else {
          ++stats_.unknown;
        }
        return;
      case port::kLog:
        if (pk.channel == logp::kChanToc) {
          on_toc(pk, true, out);
        } else {
          on_log(pk, now_ms, out);
        }
        return;
      case port::kParam:
        if (pk.channel == param::kChanToc) {
          on_toc(pk, false, out);
        } else {
          on_param(pk, out);
        }
        return;
      case port::kCommanderGeneric: {
        const auto sp = commander::decode(pk);
        if (sp.kind == commander::Setpoint::Kind::kOther) {
          ++stats_.unknown;
          return;
        }
        ++stats_.setpoints;
        if (sp.kind == commander::Setpoint::Kind::kNotifyStop) {
          setpoint_valid_until_ms_ = now_ms + sp.remain_valid_ms;
          return;
        }
        setpoint_ = sp;
        setpoint_ms_ = now_ms;
        setpoint_valid_until_ms_ = 0;
        return;
      }
      default:
        ++stats_.unknown;
        return;
    }
  } catch (const CrtpError&) {
    ++stats_.malformed;
  }
}

bool FirmwareEmulator::on_arming(const CrtpPacket& pk, std::vector<CrtpPacket>& out) {
  bool arm = false;
  if (!arming::decode_request(pk, arm)) return false;
  if (pk.port == port::kSupervisor && opt_.protocol_version < arming::kSupervisorProtocolVersion) {
    ++stats_.unknown;  // no supervisor port before protocol 12
    return true;
  }
  ++stats_.arming_requests;
  armed_ = arm;
  if (pk.port == port::kSupervisor) {
    // Answer [cmd | 0x80, success, is_armed] (cflib Supervisor._supervisor_callback).
    reply(out, CrtpPacket(port::kSupervisor, arming::kSupervisorChanCommand,
                          {static_cast<uint8_t>(arming::kCmdArmSystem | 0x80), 1, static_cast<uint8_t>(armed_ ? 1 : 0)}));
  }
  return true;
}

bool FirmwareEmulator::motors_on(uint32_t now_ms) const {
  const auto c = commander(now_ms);
  return (c.mode == CommanderOutput::Mode::kSetpoint && c.setpoint.kind != commander::Setpoint::Kind::kStop) ||
         c.mode == CommanderOutput::Mode::kStabilize;
}

uint16_t FirmwareEmulator::supervisor_info(uint32_t now_ms) const {
  uint16_t v = 1u << 0;  // can be armed: the emulator has no pre-flight checks that fail
  if (armed_) v |= 1u << 1 | 1u << 3;  // is armed, can fly
  if (opt_.auto_arm) v |= 1u << 2;
  if (motors_on(now_ms)) v |= 1u << 4;  // is flying
  return v;
}

void FirmwareEmulator::on_toc(const CrtpPacket& pk, bool log, std::vector<CrtpPacket>& out) {
  const uint8_t port_no = log ? port::kLog : port::kParam;
  PayloadReader r(pk, log ? "log TOC request" : "param TOC request");
  const uint8_t cmd = r.u8();
  const size_t count = log ? log_vars_.size() : params_.size();
  if (cmd == toc::kCmdInfoV2) {
    toc::Info info;
    info.count = static_cast<uint16_t>(count);
    info.crc = log ? log_toc_crc() : param_toc_crc();
    info.max_packets = log ? static_cast<uint8_t>(opt_.max_blocks) : 0;
    info.max_ops = log ? static_cast<uint8_t>(opt_.max_ops) : 0;
    auto rep = toc::info_reply(port_no, info);
    if (!log) rep.size = 7;  // param TOC info v2: [3, count u16, crc u32]
    reply(out, rep);
  } else if (cmd == toc::kCmdItemV2) {
    const uint16_t id = r.u16();
    if (id >= count) {
      ++stats_.malformed;  // firmware sends nothing for an unknown id
      return;
    }
    reply(out, toc::item_reply(port_no, log ? log_vars_[id].item : params_[id].item));
  } else {
    ++stats_.unknown;  // v1 TOC (protocol < 4) not emulated
  }
}

size_t FirmwareEmulator::ops_in_use() const {
  size_t n = 0;
  for (const auto& [id, b] : blocks_) n += b.vars.size();
  return n;
}

void FirmwareEmulator::on_log(const CrtpPacket& pk, uint32_t now_ms, std::vector<CrtpPacket>& out) {
  if (pk.channel != logp::kChanSettings) {
    ++stats_.unknown;
    return;
  }
  PayloadReader r(pk, "log control");
  const uint8_t cmd = r.u8();
  auto answer = [&](uint8_t block, uint8_t status) {
    if (status != 0) ++stats_.log_errors;
    reply(out, logp::control_reply({cmd, block, status}));
  };
  if (cmd == logp::kCmdReset) {
    blocks_.clear();
    answer(0, 0);
    return;
  }
  const uint8_t id = r.u8();
  switch (cmd) {
    case logp::kCmdCreateBlockV2:
    case logp::kCmdAppendBlockV2: {
      const bool create = cmd == logp::kCmdCreateBlockV2;
      auto it = blocks_.find(id);
      if (create && it != blocks_.end()) return answer(id, EEXIST);
      if (!create && it == blocks_.end()) return answer(id, ENOENT);
      if (create && blocks_.size() >= opt_.max_blocks) return answer(id, ENOMEM);
      Block b = create ? Block{} : it->second;
      while (r.remaining() >= 3) {
        const uint8_t types = r.u8();
        const uint16_t var = r.u16();
        const uint8_t fetch = types & 0x0F;
        if (var >= log_vars_.size()) return answer(id, ENOENT);
        if (!logp::valid_type(fetch)) return answer(id, ENOEXEC);
        b.vars.push_back(var);
        b.fetch.push_back(static_cast<logp::Type>(fetch));
        b.bytes += logp::type_size(fetch);
      }
      if (r.remaining() != 0) return answer(id, EINVAL);
      if (b.bytes > logp::kMaxBlockBytes) return answer(id, E2BIG);
      if (ops_in_use() - (create ? 0 : it->second.vars.size()) + b.vars.size() > opt_.max_ops) return answer(id, ENOMEM);
      blocks_[id] = b;
      return answer(id, 0);
    }
    case logp::kCmdStartBlock:
    case logp::kCmdStartBlockV2: {
      const uint32_t period = cmd == logp::kCmdStartBlock ? 10u * r.u8() : r.u16();
      auto it = blocks_.find(id);
      if (it == blocks_.end()) return answer(id, ENOENT);
      it->second.started = true;
      it->second.period_ms = std::max<uint32_t>(period, 1);
      it->second.next_ms = now_ms;
      return answer(id, 0);
    }
    case logp::kCmdStopBlock: {
      auto it = blocks_.find(id);
      if (it == blocks_.end()) return answer(id, ENOENT);
      it->second.started = false;
      return answer(id, 0);
    }
    case logp::kCmdDeleteBlock: {
      if (blocks_.erase(id) == 0) return answer(id, ENOENT);
      return answer(id, 0);
    }
    default:
      ++stats_.unknown;  // v1 create/append (protocol < 4) not emulated
      return;
  }
}

void FirmwareEmulator::on_param(const CrtpPacket& pk, std::vector<CrtpPacket>& out) {
  if (pk.channel == param::kChanRead) {
    PayloadReader r(pk, "param read");
    const uint16_t id = r.u16();
    ++stats_.param_reads;
    if (id >= params_.size()) {
      reply(out, param::read_reply(id, 0, 0, ENOENT));
      return;
    }
    reply(out, param::read_reply(id, params_[id].item.type_byte, params_[id].value));
    return;
  }
  if (pk.channel == param::kChanWrite) {
    const uint16_t id = param::reply_id(pk);
    if (id >= params_.size()) {
      ++stats_.malformed;
      return;
    }
    auto& p = params_[id];
    const auto w = param::decode_write(pk, p.item.type_byte);
    ++stats_.param_writes;
    if (!(p.item.type_byte & param::kFlagReadOnly)) {
      // Store the value as the type holds it (round trip through the wire form).
      CrtpPacket tmp;
      param::append_value(tmp, p.item.type_byte, w.value);
      PayloadReader rr(tmp, "param value");
      p.value = param::read_value(rr, p.item.type_byte);
      if (on_param_written) on_param_written(id, p.value);
    }
    CrtpPacket echo(port::kParam, param::kChanWrite);
    echo.u16(id);
    param::append_value(echo, p.item.type_byte, p.value);
    reply(out, echo);
    return;
  }
  ++stats_.unknown;
}

void FirmwareEmulator::tick(uint32_t now_ms, std::vector<CrtpPacket>& out) {
  std::vector<double> values;
  for (auto& [id, b] : blocks_) {
    if (!b.started || now_ms < b.next_ms) continue;
    values.clear();
    for (uint16_t v : b.vars) values.push_back(log_values_[v]);
    out.push_back(logp::data_packet(id, now_ms & 0xFFFFFF, b.fetch, values));
    ++stats_.log_packets;
    b.next_ms += b.period_ms;
    if (b.next_ms <= now_ms) b.next_ms = now_ms + b.period_ms;  // skipped slots are not replayed
  }
}

FirmwareEmulator::CommanderOutput FirmwareEmulator::commander(uint32_t now_ms) const {
  CommanderOutput c;
  if (!setpoint_) return c;
  if (!armed_) {
    c.mode = CommanderOutput::Mode::kShutdown;  // the supervisor keeps the motors off
    return c;
  }
  const uint32_t ref = std::max(setpoint_ms_, setpoint_valid_until_ms_);
  const uint32_t age = now_ms >= ref ? now_ms - ref : 0;
  if (setpoint_->kind == commander::Setpoint::Kind::kStop) {
    c.mode = CommanderOutput::Mode::kShutdown;
  } else if (age < opt_.watchdog_stabilize_ms) {
    c.mode = CommanderOutput::Mode::kSetpoint;
    c.setpoint = *setpoint_;
  } else if (age < opt_.watchdog_shutdown_ms) {
    c.mode = CommanderOutput::Mode::kStabilize;
  } else {
    c.mode = CommanderOutput::Mode::kShutdown;
  }
  return c;
}

size_t FirmwareEmulator::started_blocks() const {
  size_t n = 0;
  for (const auto& [id, b] : blocks_) n += b.started;
  return n;
}
uint32_t FirmwareEmulator::block_period_ms(uint8_t id) const {
  auto it = blocks_.find(id);
  return it != blocks_.end() && it->second.started ? it->second.period_ms : 0;
}

}  // namespace crazyflie_bridge
