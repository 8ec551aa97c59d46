// Host glue of the bridge: a Link + CrazyflieClient + CrazyflieBridgeLogic.
// Connects, starts the whisker and state log blocks, then
//   pump()      receives log data and hands out the decoded messages,
//   on_hover_setpoint()  takes the behaviour's setpoint and, in forward mode, sends
//               it at once (event driven: the setpoint is the step's input),
//   on_timer()  the setpoint_rate_hz watchdog: steps the logic and sends its packet
//               when no setpoint stepped it since its previous call (every mode
//               but forward, or the behaviour's setpoints stopped), see
//               tactile_common/event_tick.hpp,
//   arm() .. emergency_stop()  the operator commands (sent at once where they
//               carry a packet: arming request, emergency stop),
//   land_and_stop()  the blocking shutdown landing (Ctrl-C, SIGTERM, destruction),
// with a mutex so that the rclcpp component (receive thread + timer) and the
// `tactile fly` loop use it the same way. Times are the caller's clock [ns].
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "crazyflie_bridge/client.hpp"
#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "tactile_common/event_tick.hpp"
#include "tactile_common/ports.hpp"

namespace crazyflie_bridge {

class BridgeRunner {
 public:
  struct Sinks {
    std::function<void(const tactile_msgs::msg::WhiskerPressure&)> left, right;
    std::function<void(const nav_msgs::msg::Odometry&)> odom;
  };

  /// The bridge's ports that its rclcpp component and `tactile fly` share
  /// (tactile_common/ports.hpp): the log data's three outputs (Pub::kData), returned as
  /// the Sinks pump() and land_and_stop() publish through, and the behaviour's setpoint
  /// input (Sub::kReliable: keep last 10, reliable), handed to `on_setpoint`, the host's
  /// own handler (the component takes the link's lock and checks it is streaming;
  /// `tactile fly` stops forwarding at the run's end). The rest is each host's: the
  /// component's link and status timers, operator services, TF and diagnostics; the
  /// real-time loop of `tactile fly` that pumps the link.
  template <class Ports, class OnSetpoint>
  static Sinks wire(Ports& p, OnSetpoint on_setpoint) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    Sinks sinks;
    sinks.left = p.template publisher<tactile_msgs::msg::WhiskerPressure>(CrazyflieBridgeLogic::kLeftPressureTopic,
                                                                          Pub::kData);
    sinks.right = p.template publisher<tactile_msgs::msg::WhiskerPressure>(CrazyflieBridgeLogic::kRightPressureTopic,
                                                                           Pub::kData);
    sinks.odom = p.template publisher<nav_msgs::msg::Odometry>(CrazyflieBridgeLogic::kOdomTopic, Pub::kData);
    p.template subscribe<tactile_msgs::msg::HoverSetpoint>(CrazyflieBridgeLogic::kSetpointTopic, Sub::kReliable,
                                                           std::move(on_setpoint));
    return sinks;
  }
  /// Wall-clock latency of one kind of log sample: received (the client's receive time)
  /// -> the next setpoint packet sent. Mean, max and quantiles from a fixed histogram
  /// (kBinS bins up to kBins * kBinS; longer ones in the last bin): memory does not
  /// grow with the flight.
  struct LatencyStats {
    static constexpr double kBinS = 25e-6;
    static constexpr std::size_t kBins = 4000;  ///< 100 ms
    uint64_t count = 0;
    double sum_s = 0, max_s = 0;
    std::array<uint32_t, kBins> bins{};
    void add(double s);
    double mean_s() const { return count ? sum_s / static_cast<double>(count) : 0.0; }
    /// Upper edge of the bin holding the q-quantile (0 < q <= 1) [s]; 0 without samples.
    double quantile_s(double q) const;
  };

  using Mode = CrazyflieBridgeLogic::Mode;
  using CommandResult = CrazyflieBridgeLogic::CommandResult;
  using Status = CrazyflieBridgeLogic::Status;

  /// Opens params.uri (or uses `link` if given), connects and creates the
  /// whisker, attitude, state and status log blocks (status variables the
  /// firmware's TOC lacks are skipped: see warnings()), and starts them unless
  /// `stream` is false (the lifecycle component: configure connects, activate
  /// streams). Throws UriError / LinkError / ClientError.
  explicit BridgeRunner(const CrazyflieBridgeLogic::Params& params, ClientOptions client_options = {},
                        std::unique_ptr<Link> link = nullptr, bool stream = true);

  /// Starts (again) the log blocks created at connect; a no-op when streaming.
  /// Throws ClientError.
  void start_streaming();
  /// Stops the log blocks (nothing is received after the firmware's answer).
  /// Refuses (returns false, nothing sent) while the logic is airborne
  /// (taking off .. landing): land_and_stop() first, never blind a flying vehicle.
  /// Throws ClientError on a failed stop request.
  bool stop_streaming();
  bool streaming() const { return streaming_; }

  /// Receives for at most `timeout` (then drains what already arrived),
  /// stamping messages with now_ns(); returns the number of log samples handled.
  static constexpr int kMaxSamplesPerPump = 1000;
  int pump(std::chrono::milliseconds timeout, const std::function<int64_t()>& now_ns, const Sinks& sinks);
  /// Hands the setpoint to the logic; in forward mode (the behaviour flies) the logic
  /// steps and its packet is sent now, unless another setpoint stepped it less than half
  /// a setpoint period ago (then the watchdog sends it). Returns true if a setpoint
  /// packet was sent.
  bool on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg, int64_t now_ns);
  /// The watchdog, called at setpoint_rate_hz: sends the logic's queued packets and steps
  /// the logic and sends its setpoint packet (if any), unless the logic is in forward mode
  /// and a setpoint stepped it since the previous call. Every other mode steps on every
  /// call. Returns true if a setpoint packet was sent.
  bool on_timer(int64_t now_ns);

  // Operator commands: CrazyflieBridgeLogic's, mutex-guarded; packets they
  // carry (arming request, the first emergency stop) are sent before return.
  CommandResult arm(bool on, int64_t now_ns);
  CommandResult takeoff(double height_m, double duration_s, int64_t now_ns);
  CommandResult land(double height_m, double duration_s, int64_t now_ns);
  CommandResult go_to(double x, double y, double z, double yaw_rad, double duration_s, bool relative, int64_t now_ns);
  CommandResult start_behaviour(int64_t now_ns);
  CommandResult notify_setpoints_stop(uint32_t remain_valid_ms, int64_t now_ns);
  CommandResult emergency_stop(int64_t now_ns);

  /// Blocking: land (if airborne), pump the link and send setpoints at
  /// setpoint_rate_hz until kStopped and its stop packets are out; on timeout,
  /// or as soon as `abort` returns true (e.g. a second Ctrl-C), emergency-stop.
  /// Returns true if it landed (or was on the ground already, not in
  /// kEmergency). Log messages received meanwhile go to `sinks` (none by default).
  bool land_and_stop(std::chrono::milliseconds timeout, const std::function<int64_t()>& now_ns,
                     const Sinks& sinks = {}, const std::function<bool()>& abort = {});

  /// The logic's status with the link fields (ACK rate, packets lost, log
  /// blocks missed) filled in.
  Status status(int64_t now_ns) const;
  std::vector<CrazyflieBridgeLogic::Transition> history() const;
  /// Connect-time warnings (e.g. a status variable the firmware lacks).
  const std::vector<std::string>& warnings() const { return warnings_; }

  CrazyflieBridgeLogic::Mode mode() const;
  CrazyflieBridgeLogic::Stats logic_stats() const;
  LinkStatistics link_stats() const;
  CrazyflieClient::Stats client_stats() const;
  /// State log sample received -> next setpoint sent.
  LatencyStats latency() const;
  /// Whisker log sample received -> next setpoint sent, for the setpoints the behaviour
  /// flies (forward mode): the pipeline's reaction time (pressure in -> TDORC -> depth ->
  /// behaviour -> setpoint out).
  LatencyStats whisker_latency() const;
  /// When setpoint packets were sent: on a setpoint's arrival (forward mode) or by the
  /// setpoint_rate_hz timer's watchdog (every other mode, or no setpoint arriving).
  tactile_common::EventTick::Stats tick_stats() const;
  const CrazyflieClient& client() const { return *client_; }

 private:
  std::unique_ptr<Link> link_;
  std::unique_ptr<CrazyflieClient> client_;
  CrazyflieBridgeLogic logic_;
  mutable std::mutex mutex_;  ///< guards logic_ and the link's send side
  std::chrono::steady_clock::time_point last_state_rx_{}, last_whisker_rx_{};
  bool state_pending_ = false, whisker_pending_ = false;
  LatencyStats latency_, whisker_latency_;
  std::vector<std::string> warnings_;
  std::vector<uint8_t> block_ids_;         ///< whisker, attitude, state: created at connect, in start order
  std::optional<uint8_t> status_block_id_;  ///< optional: its failures are warnings
  bool streaming_ = false;
  tactile_common::EventTick tick_;
  /// Sends what the logic queued (caller holds mutex_).
  void flush_outbox();
  /// One step of the logic and its packets sent (caller holds mutex_); true if a setpoint was sent.
  bool step(int64_t now_ns);
};

}  // namespace crazyflie_bridge
