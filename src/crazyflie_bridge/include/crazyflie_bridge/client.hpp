// Ground side of the CRTP services over any Link: the connection sequence
// cflib uses (link source + protocol version, log reset, log TOC v2, param
// TOC v2; TOCs cached on disk by CRC like cflib's toccache), log blocks v2
// (create, start with a u16 ms period), decoded log data, param read/write,
// and setpoints. Synchronous: requests wait for their answer (resent on
// timeout, like cflib's expected_reply); log data arriving meanwhile is kept
// for poll(), never dropped.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "crazyflie_bridge/link.hpp"
#include "crazyflie_bridge/protocol.hpp"

namespace crazyflie_bridge {

class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ClientOptions {
  std::chrono::milliseconds reply_timeout{200};  ///< cflib send_packet timeout 0.2 s
  int retries = 15;                              ///< resends before giving up
  std::string toc_cache_dir;                     ///< empty: no cache
};

struct LogSample {
  uint8_t block_id = 0;
  uint32_t timestamp_ms = 0;
  std::vector<std::string> names;  ///< shared layout of the block (copied for convenience)
  std::vector<double> values;
  std::chrono::steady_clock::time_point received;
};

class CrazyflieClient {
 public:
  struct Stats {
    uint64_t log_samples = 0;
    uint64_t log_decode_errors = 0;  ///< data packets whose layout did not match (dropped)
    uint64_t log_unknown_block = 0;  ///< data for a block we did not create (dropped)
    /// Log packets that never arrived: gaps in the firmware timestamps of
    /// each block larger than its period (exact downlink loss of the log stream).
    uint64_t log_missed = 0;
    uint64_t resends = 0;
    uint64_t other_packets = 0;      ///< packets no request waited for (console, late replies)
  };

  CrazyflieClient(Link& link, ClientOptions options = {});

  /// Connection setup; throws ClientError (no answer, bad TOC) or LinkError.
  void connect();
  /// CRTP protocol version (platform service); selects the setpoint
  /// generation (commander::legacy_setpoints). connect() refuses versions
  /// below commander::kMinProtocolVersion with a ClientError naming it.
  uint8_t protocol_version() const { return protocol_version_; }
  /// Firmware version text (platform VERSION_GET_FIRMWARE), empty when the
  /// firmware did not answer (firmware_version_answered() false).
  const std::string& firmware_version() const { return firmware_version_; }
  bool firmware_version_answered() const { return firmware_version_answered_; }
  const std::vector<toc::Item>& log_toc() const { return log_toc_; }
  const std::vector<toc::Item>& param_toc() const { return param_toc_; }
  bool log_toc_from_cache() const { return log_toc_cached_; }
  uint32_t log_toc_crc() const { return log_crc_; }
  const toc::Item* log_item(const std::string& full_name) const;
  const toc::Item* param_item(const std::string& full_name) const;

  /// Creates and starts a block of `names` fetched as their TOC types; returns
  /// its id. Throws ClientError naming the unknown variable, a block over 26
  /// bytes or the firmware's errno.
  uint8_t start_log_block(const std::vector<std::string>& names, uint16_t period_ms);
  /// start_log_block() in two steps: create the block (same errors), start it
  /// later (and again after stop_log_block(): a restarted block's timestamp gap
  /// is not counted as lost packets in Stats::log_missed).
  uint8_t create_log_block(const std::vector<std::string>& names, uint16_t period_ms);
  void start_created_log_block(uint8_t block_id);
  /// Stops a started block (log v2 STOP_BLOCK); throws ClientError with the
  /// firmware's errno.
  void stop_log_block(uint8_t block_id);

  /// Next log sample, waiting at most `timeout`.
  std::optional<LogSample> poll(std::chrono::milliseconds timeout);

  double read_param(const std::string& full_name);
  /// Writes and returns the value the firmware echoes.
  double write_param(const std::string& full_name, double value);

  /// Fire-and-forget (setpoints).
  void send(const CrtpPacket& pk) { link_.send(pk); }
  Link& link() { return link_; }
  const Stats& stats() const { return stats_; }

 private:
  /// Sends `pk` and waits for a packet on (port, channel) whose payload starts
  /// with `prefix`.
  /// retries < 0: opt_.retries.
  CrtpPacket request(const CrtpPacket& pk, uint8_t port_no, uint8_t channel, const std::vector<uint8_t>& prefix,
                     const char* what, int retries = -1);
  /// Routes a packet that no request is waiting for.
  void dispatch(const CrtpPacket& pk);
  std::vector<toc::Item> fetch_toc(uint8_t port_no, uint32_t& crc, bool& cached);
  bool load_cache(const std::string& kind, uint32_t crc, uint16_t count, std::vector<toc::Item>& items) const;
  void store_cache(const std::string& kind, uint32_t crc, const std::vector<toc::Item>& items) const;

  struct Block {
    std::vector<std::string> names;
    std::vector<logp::Type> types;
    uint32_t period_ms = 0;
    bool have_last = false;
    uint32_t last_ts = 0;
  };
  Link& link_;
  ClientOptions opt_;
  uint8_t protocol_version_ = 0;
  std::string firmware_version_;
  bool firmware_version_answered_ = false;
  std::vector<toc::Item> log_toc_, param_toc_;
  std::map<std::string, size_t> log_index_, param_index_;
  uint32_t log_crc_ = 0, param_crc_ = 0;
  bool log_toc_cached_ = false;
  std::map<uint8_t, Block> blocks_;
  uint8_t next_block_ = 1;
  std::deque<LogSample> pending_;
  std::vector<double> scratch_;
  Stats stats_;
};

}  // namespace crazyflie_bridge
