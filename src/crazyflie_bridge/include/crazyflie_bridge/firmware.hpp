// Firmware side of CRTP for a simulated Crazyflie: log TOC and log blocks,
// param TOC and read/write, generic commander setpoints with the firmware's
// commander watchdog, a supervisor (arming, supervisor.info), platform/link/mem answers the official client (cflib)
// needs to connect. Protocol only: the owner binds variables to a simulated
// vehicle (crazyflie_bridge/sitl_endpoint.hpp) and feeds packets from a link.
// Behaviour follows the Crazyflie firmware (log.c, param_logic.c,
// crtp_commander_generic.c, commander.c) as seen by cflib.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "crazyflie_bridge/protocol.hpp"

namespace crazyflie_bridge {

class FirmwareEmulator {
 public:
  struct Options {
    uint8_t protocol_version = 10;  ///< > 8: cflib sends hover type 10 (CCW yaw rate)
    std::string firmware_version = "tactile-sitl";
    /// Firmware commander watchdog (commander.c): no setpoint for this long ->
    /// level out (hover in place here), then stop the motors.
    uint32_t watchdog_stabilize_ms = 500;   ///< COMMANDER_WDT_TIMEOUT_STABILIZE
    uint32_t watchdog_shutdown_ms = 2000;   ///< COMMANDER_WDT_TIMEOUT_SHUTDOWN
    size_t max_blocks = 16;                 ///< LOG_MAX_BLOCKS
    size_t max_ops = 128;                   ///< LOG_MAX_OPS
    /// Supervisor: armed at start-up without a request, as a brushed
    /// Crazyflie 2.x (the firmware's auto-arm; a brushless one requires an
    /// arming request). false: motors stay off until an arming request.
    bool auto_arm = true;
  };
  struct Stats {
    uint64_t packets_in = 0, replies = 0, log_packets = 0;
    uint64_t setpoints = 0, param_reads = 0, param_writes = 0;
    uint64_t malformed = 0;       ///< truncated / invalid packets (dropped)
    uint64_t unknown = 0;         ///< ports/commands not emulated (dropped)
    uint64_t log_errors = 0;      ///< log control commands answered with an errno
    uint64_t arming_requests = 0; ///< arm / disarm requests (either port)
  };
  /// What the commander does at a given time.
  struct CommanderOutput {
    enum class Mode { kIdle, kSetpoint, kStabilize, kShutdown };
    Mode mode = Mode::kIdle;
    commander::Setpoint setpoint;  ///< valid in kSetpoint
  };

  FirmwareEmulator();
  explicit FirmwareEmulator(const Options& options);

  /// Registers a log variable; returns its TOC id. Register everything before
  /// the first packet (the TOC CRC is computed then).
  uint16_t add_log_variable(const std::string& group, const std::string& name, logp::Type type);
  void set_log_value(uint16_t id, double value) { log_values_.at(id) = value; }
  /// Registers a parameter; returns its TOC id.
  uint16_t add_param(const std::string& group, const std::string& name, uint8_t type, double value, bool read_only);
  double param_value(uint16_t id) const { return params_.at(id).value; }
  std::optional<uint16_t> param_id(const std::string& full_name) const;
  std::optional<uint16_t> log_id(const std::string& full_name) const;
  /// Called after a successful parameter write (id, new value).
  std::function<void(uint16_t, double)> on_param_written;

  /// One packet from the ground station at firmware time now_ms; answers are
  /// appended to `out`.
  void on_packet(const CrtpPacket& pk, uint32_t now_ms, std::vector<CrtpPacket>& out);
  /// Log data of the started blocks that are due at now_ms.
  void tick(uint32_t now_ms, std::vector<CrtpPacket>& out);
  /// Commander state at now_ms (last setpoint + watchdog); motors off
  /// (kShutdown, or kIdle before any setpoint) while not armed.
  CommanderOutput commander(uint32_t now_ms) const;

  // Supervisor (firmware supervisor.c as cflib sees it): arming state from
  // auto-arm or arming requests (supervisor port from protocol 12, the legacy
  // platform request on any version), the supervisor.info bit field.
  bool armed() const { return armed_; }
  /// Motors spinning at now_ms: armed and the commander has a setpoint or is
  /// levelling out (kSetpoint with anything but stop, kStabilize).
  bool motors_on(uint32_t now_ms) const;
  /// supervisor.info: bit 0 can be armed, 1 is armed, 2 auto-arm, 3 can fly,
  /// 4 is flying (cflib crazyflie/supervisor.py BIT_*); tumbled / locked are
  /// not emulated (0).
  uint16_t supervisor_info(uint32_t now_ms) const;

  uint32_t log_toc_crc() const;
  uint32_t param_toc_crc() const;
  const Stats& stats() const { return stats_; }
  size_t started_blocks() const;
  /// Period [ms] of a started block, 0 if none.
  uint32_t block_period_ms(uint8_t block_id) const;

 private:
  struct LogVar {
    toc::Item item;
  };
  struct Param {
    toc::Item item;
    double value = 0;
  };
  struct Block {
    std::vector<uint16_t> vars;
    std::vector<logp::Type> fetch;
    size_t bytes = 0;
    bool started = false;
    uint32_t period_ms = 0;
    uint32_t next_ms = 0;
  };
  void on_log(const CrtpPacket& pk, uint32_t now_ms, std::vector<CrtpPacket>& out);
  void on_param(const CrtpPacket& pk, std::vector<CrtpPacket>& out);
  void on_toc(const CrtpPacket& pk, bool log, std::vector<CrtpPacket>& out);
  /// Arming request on the supervisor port or the legacy platform port; false if `pk` is none.
  bool on_arming(const CrtpPacket& pk, std::vector<CrtpPacket>& out);
  size_t ops_in_use() const;
  void reply(std::vector<CrtpPacket>& out, const CrtpPacket& pk);

  Options opt_;
  std::vector<LogVar> log_vars_;
  std::vector<double> log_values_;
  std::vector<Param> params_;
  std::map<uint8_t, Block> blocks_;
  std::optional<commander::Setpoint> setpoint_;
  uint32_t setpoint_ms_ = 0;
  uint32_t setpoint_valid_until_ms_ = 0;  ///< notify-setpoint-stop keeps the last one valid this long
  bool armed_ = true;
  Stats stats_;
};

}  // namespace crazyflie_bridge
