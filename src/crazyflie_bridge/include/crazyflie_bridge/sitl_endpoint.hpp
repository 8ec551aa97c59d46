// Simulated Crazyflie on UDP: tactile_sim's whiskered Crazyflie behind the
// firmware side of CRTP (FirmwareEmulator), so that the bridge or any
// cflib-based tool flies the SITL over the same protocol as the real drone
// (udp://127.0.0.1:19850+N, cflib udpdriver). The physics runs in wall-clock
// time (speed 1) or faster; log blocks carry the simulated whisker
// barometers and the vehicle's state estimate; generic setpoints drive the
// vehicle through its hover-setpoint controller; the firmware's commander
// watchdog (500 ms hover in place, 2 s motors off) applies when setpoints stop.
//
// Log variables and parameters: crazyflie_bridge/sim_firmware.hpp
// (sitl.lossPct sets the injected uplink and downlink loss at run time).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "crazyflie_bridge/sim_firmware.hpp"
#include "crazyflie_bridge/link.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"

namespace crazyflie_bridge {

struct SitlEndpointOptions {
  uint16_t port = 19850;             ///< 0: any free port
  std::string bind_address = "127.0.0.1";
  double speed = 1.0;                ///< simulated seconds per wall-clock second
  double loss_rate = 0.0;            ///< probability of dropping each datagram (both directions)
  double spike_rate_hz = 0.0;        ///< latency spikes per second (Poisson)
  double spike_latency_s = 0.2;      ///< extra delay of every packet during a spike
  double spike_duration_s = 0.2;
  uint64_t fault_seed = 1;
  /// Keep the whiskers' ground truth for whisker_truth() (a run's evaluation;
  /// off for a server that runs indefinitely, where it would only grow).
  bool record_whisker_truth = false;
  /// Motors off until an arming request (default: auto-arm, as a brushed
  /// Crazyflie 2.x).
  bool require_arming = false;
};

class SitlEndpoint {
 public:
  struct Stats {
    uint64_t dropped_in = 0, dropped_out = 0;  ///< injected loss
    uint64_t delayed = 0;                      ///< packets held back by a latency spike
    uint64_t spikes = 0;
    uint64_t sim_steps = 0;
  };

  SitlEndpoint(const tactile_sim::Scenario& scenario, uint64_t seed, const SitlEndpointOptions& options);
  ~SitlEndpoint();

  uint16_t port() const { return server_.port(); }
  /// Runs until `stop` is set, the simulated `duration_s` elapsed (<= 0: the
  /// scenario's duration) or forever if both are absent.
  void run(double duration_s, const std::atomic<bool>* stop = nullptr);

  const tactile_sim::SimLogic& sim() const { return *sim_; }
  const FirmwareEmulator& firmware() const { return fw_.emulator(); }
  const UdpServer& server() const { return server_; }
  const Stats& stats() const { return stats_; }
  int64_t sim_time_ns() const { return now_ns_; }
  /// Ground-truth position of the vehicle (for tests and metrics); safe to
  /// call from another thread while run() is going.
  tactile_sim::Vec3 truth_position() const;
  /// Wall-clock (steady_clock) instant of simulated time 0: the start of
  /// run(); the epoch before run() starts. Thread-safe. At speed 1 a
  /// simulated time t happened at start_time() + t.
  std::chrono::steady_clock::time_point start_time() const {
    return std::chrono::steady_clock::time_point(std::chrono::steady_clock::duration(start_ticks_.load()));
  }
  /// The simulated whiskers' ground truth (000 Fig. 6 sweeps: depth in band),
  /// one entry per published sample and whisker, stamped in simulated time,
  /// when options.record_whisker_truth is set (else empty). Read it after
  /// run() has returned.
  struct WhiskerTruthSample {
    int64_t sim_ns = 0;
    int side = 0;  ///< 0 left, 1 right
    bool contact = false;
    double depth = 0.0;  ///< [m]
  };
  const std::vector<WhiskerTruthSample>& whisker_truth() const { return whisker_truth_; }
  /// Sets the injected loss rate (thread-safe; also settable over CRTP with
  /// the sitl.lossPct parameter).
  void set_loss_rate(double p) { loss_request_ = p; }
  /// Sets pm.vbat (thread-safe; NaN: back to the battery model).
  void set_battery_voltage(double v) { vbat_request_ = v; vbat_pending_ = true; }
  /// The firmware's motors spin now (thread-safe): armed and a setpoint is
  /// being followed or the commander watchdog is levelling out.
  bool motors_on() const { return motors_on_; }
  /// Simulated time [ns] the motors first came on, -1 if never (thread-safe).
  int64_t first_motors_on_ns() const { return first_motors_on_ns_; }

 private:
  void step_physics();
  void apply_commander();
  void flush(std::chrono::steady_clock::time_point now);
  bool drop();
  double extra_latency(std::chrono::steady_clock::time_point now);

  SitlEndpointOptions opt_;
  std::unique_ptr<tactile_sim::SimLogic> sim_;
  SimulatedCrazyflieFirmware fw_;
  UdpServer server_;
  tactile_sim::SimLogic::Outputs out_;
  int64_t now_ns_ = 0;
  struct Held {
    std::chrono::steady_clock::time_point release;
    CrtpPacket pk;
    bool inbound;
  };
  std::deque<Held> held_;
  std::vector<CrtpPacket> replies_;
  std::mt19937_64 rng_;
  std::chrono::steady_clock::time_point spike_until_{}, next_spike_{};
  uint16_t id_left_ = 0, id_right_ = 0, id_state_ = 0, id_vbat_ = 0, id_truth_ = 0;
  uint16_t p_stop_ = 0, p_loss_ = 0;
  double height_cmd_ = 0.0;
  mutable std::mutex truth_mutex_;
  tactile_sim::Vec3 truth_ = tactile_sim::Vec3::Zero();
  std::atomic<double> loss_request_{-1.0};
  std::atomic<double> vbat_request_{NAN};
  std::atomic<bool> vbat_pending_{false};
  std::atomic<bool> motors_on_{false};
  std::atomic<int64_t> first_motors_on_ns_{-1};
  std::atomic<std::chrono::steady_clock::duration::rep> start_ticks_{0};
  std::vector<WhiskerTruthSample> whisker_truth_;
  double param_loss_ = 0.0;  ///< last sitl.lossPct seen
  int last_mode_ = -1;
  Stats stats_;
};

}  // namespace crazyflie_bridge
