// The simulated whiskered Crazyflie's firmware side, independent of the
// transport: a FirmwareEmulator whose log variables are fed from the
// simulator's messages and whose commander output becomes the simulator's
// setpoints. Used by SitlEndpoint (UDP, wall clock) and by `tactile sim`'s
// whisker_fsm_crtp graph (in lockstep on the simulated clock).
//
// Log TOC: Whisker.Barometer1_1..3, Whisker1.Barometer2_1..3 [Pa, float],
// stateEstimate.x/y/z [m], yaw [deg], vx/vy/vz [m/s world], pm.vbat [V],
// sitl.truthX/Y/Z [m] (ground truth, simulator only); with status_log:
// pm.state (int8), supervisor.info (uint16), radio.rssi (uint8, -dBm).
// Battery model: pm.vbat = vbat_full - vbat_drain_v_per_s * (time with the
// motors on), or the voltage set with set_battery_voltage() (a test hook).
// Params: deck.bcWhisker (u8, RO, 1), commander.enHighLevel (u8),
// stabilizer.stop (u8: 1 stops the motors), sitl.lossPct (u8: injected loss in
// %, read by the transport through loss_percent()).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>

#include "crazyflie_bridge/firmware.hpp"
#include "geometry_msgs/msg/pose_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"

namespace crazyflie_bridge {

class SimulatedCrazyflieFirmware {
 public:
  struct Options {
    double loss_rate = 0.0;  ///< initial sitl.lossPct / 100
    /// Motors off until an arming request (a brushless Crazyflie); false: the
    /// brushed Crazyflie 2.x's auto-arm.
    bool require_arming = false;
    /// pm.state, supervisor.info and radio.rssi in the log TOC. The lockstep
    /// graph whisker_fsm_crtp leaves them out: a longer TOC is more packets
    /// through its seeded lossy wire, which would change every run's numbers.
    bool status_log = true;
    /// Crazyflie 2.1 with its 250 mAh LiPo: ~4.1 V charged, ~7 min of hover
    /// to ~3.5 V (Bitcraze: flight time 7 min) -> 0.6 V / 420 s.
    double vbat_full = 4.1;             ///< [V]
    double vbat_drain_v_per_s = 0.0014; ///< [V/s] with the motors on
    double rssi_dbm = 35.0;             ///< radio.rssi (-dBm): a close, clean link
  };
  explicit SimulatedCrazyflieFirmware(double loss_rate = 0.0);
  explicit SimulatedCrazyflieFirmware(const Options& options);

  FirmwareEmulator& emulator() { return fw_; }
  const FirmwareEmulator& emulator() const { return fw_; }

  void on_pressure(const tactile_msgs::msg::WhiskerPressure& msg);
  /// The vehicle's state estimate (/odom: body twist, REP-105).
  void on_estimate(const nav_msgs::msg::Odometry& msg);
  /// Ground truth (/ground_truth/odom), logged as sitl.truthX/Y/Z.
  void on_truth(const nav_msgs::msg::Odometry& msg);

  /// What the simulated vehicle is told at now_ns (firmware commander with
  /// its watchdog; stabilizer.stop): a hover setpoint, a position setpoint,
  /// or nothing (motors off until the first setpoint). `dt` integrates the
  /// height of velocity-world setpoints.
  struct Command {
    std::optional<tactile_msgs::msg::HoverSetpoint> hover;
    std::optional<geometry_msgs::msg::PoseStamped> position;
  };
  Command command(int64_t now_ns, double dt);

  /// sitl.lossPct / 100.
  double loss_rate() const;
  /// Test hook: pm.vbat is `v` from now on (NaN: back to the battery model).
  void set_battery_voltage(double v) { vbat_override_ = v; }
  double battery_voltage() const;

 private:
  FirmwareEmulator fw_;
  uint16_t id_left_ = 0, id_right_ = 0, id_state_ = 0, id_truth_ = 0;
  uint16_t p_stop_ = 0, p_loss_ = 0;
  uint16_t id_vbat_ = 0;
  int id_pm_state_ = -1, id_supervisor_ = -1, id_rssi_ = -1;
  Options opt_;
  double motors_on_s_ = 0.0;  ///< time with the motors on (battery model)
  double vbat_override_ = NAN;
  double height_cmd_ = 0.0;
  double yaw_ = 0.0;  ///< estimated yaw [rad]
};

}  // namespace crazyflie_bridge
