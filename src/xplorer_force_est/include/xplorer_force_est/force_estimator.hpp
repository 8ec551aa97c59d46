// XPLORER external force estimation (paper 001 Sec. III-A, eq. 2-7) and the
// momentum-based yaw-torque observer (001 Sec. III-A3, after its ref. [21]).
//
// Frames: world ENU (z up), body FLU (REP-103); arm frame i = body frame
// turned about z by the arm's undeflected direction plus its deflection
// theta_i, x along the arm (hinge -> motor). Eq. 1a is written for z down in
// 001; in ENU it reads m v_dot = f R e3 - m g e3 + delta_f, so eq. 5 becomes
// delta_f_CoM = m v_dot + m g e3 - f R e3 = R (m a_imu - f e3), with a_imu the
// accelerometer's specific force in the body frame.
//
// Core layer: no ROS, no messages, SI units, no allocation per sample.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include <Eigen/Geometry>

#include "xplorer_force_est/filters.hpp"

namespace xplorer_force_est {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// How the adaptive gain kappa_f of 001 eq. 7 is formed.
enum class KappaMode {
  kRate,       ///< kappa_f = xi_f |d/dt delta_f_CoM| (001 Sec. III-A3 text: "the rate of delta_f_CoM is higher at the collision instant")
  kMagnitude,  ///< kappa_f = xi_f |delta_f_CoM| (001 eq. 7 as printed)
};
const char* to_string(KappaMode m);
KappaMode kappa_mode_from_string(const std::string& s);  ///< "rate" | "magnitude"; throws std::invalid_argument

struct Params {
  // --- sampling ---
  double arm_rate_hz = 50.0;  ///< arm IMU rate (001 Sec. V-A2: BNO055 at 50 Hz)
  double imu_rate_hz = 500.0; ///< flight-controller IMU rate (choice: the SITL IMU rate)

  // --- arm-angle filter (001 Sec. V-A2: median low-pass + band-stop) ---
  int arm_median_window = 5;        ///< samples (choice: removes single-sample spikes)
  double arm_lowpass_hz = 10.0;     ///< first-order cut-off (choice)
  bool arm_bandstop = true;
  double arm_bandstop_hz = 4.68;    ///< the arm's damped natural frequency sqrt(k/J - (b/2J)^2) / 2pi (choice)
  double arm_bandstop_q = 0.7;      ///< (choice)
  int arm_hold_samples = 5;         ///< a missing/NaN arm sample holds the last angle this many samples, then the arm is dropped (choice)

  // --- arm spring-damper model, 001 eq. 2-3 ---
  double arm_inertia = 0.0015;   ///< J_zz [kg m^2] (001 Sec. V-A2)
  double arm_damping = 0.009;    ///< b [N m s/rad] (001 Sec. V-A2)
  double arm_stiffness = 1.307;  ///< k [N m/rad] (001 Sec. V-A2)
  /// l of 001 eq. 2 [m]: not given by 001. The arm only feels the force
  /// component across it; for a face contact shared by two arms at 45 deg the
  /// four projected arm forces sum to cos^2(45 deg) of the face force with the
  /// geometric hinge -> motor distance (0.15 m), so the effective l is
  /// 0.15 cos^2(45 deg) = 0.075 m (calibration choice, README).
  double lever_arm = 0.075;
  double observer_gain = 25.0;   ///< K_I of 001 eq. 3 [1/s] (choice; must satisfy K_I / arm_rate_hz < 1)
  /// Undeflected arm directions in the body frame [rad], arms counter-clockwise
  /// from the front-right one (tactile_msgs/ArmImu.arm_id).
  std::array<double, 4> arm_directions = {-M_PI / 4, M_PI / 4, 3 * M_PI / 4, -3 * M_PI / 4};

  // --- CoM estimate, 001 eq. 5 ---
  double mass = 1.12;           ///< [kg] (001 Sec. V-A1)
  double thrust_scale = 32.5;   ///< thrust = normalised command x 32.5 N (001 Sec. V-A3)
  double gravity = 9.81;        ///< [m/s^2]
  int com_median_window = 5;    ///< samples at imu_rate_hz (choice)
  double com_lowpass_hz = 1.0;  ///< (choice: 001 Fig. 4 shows the CoM estimate converging slower than the arms)

  // --- contact indicator and fusion, 001 eq. 6-7 ---
  double contact_threshold = 0.03;  ///< theta_th on sum |theta_i| [rad] (choice; a 1 N face push gives ~0.08)
  double xi_f = 0.1;                ///< xi_f of eq. 7 (choice) [s/N] in rate mode, [1/N] in magnitude mode
  KappaMode kappa_mode = KappaMode::kRate;

  // --- momentum-based yaw-torque observer (001 Sec. III-A3, ref. [21]) ---
  double yaw_inertia = 0.015;        ///< I_zz [kg m^2] (estimate, the SITL vehicle's)
  double yaw_observer_gain = 10.0;   ///< K_o [1/s] (choice)
  double torque_coefficient = 0.016; ///< rotor drag torque per thrust [m] (choice, 5" propeller)
  std::array<double, 4> spin_sign = {1.0, -1.0, 1.0, -1.0};  ///< yaw torque sign per rotor

  /// Throws std::invalid_argument "Params.<field>: <reason>, got <value>".
  void validate() const;
};

// ---------------------------------------------------------------------------
// Building blocks (each one equation; unit-tested against hand computations)

/// 001 eq. 2-3 in momentum form (no second derivative of the measured angle):
///   p = J theta_dot,  r_k = K_I (p_k - p_0 - S_k),
///   S_k = S_{k-1} + dt (r_{k-1} - b theta_dot_k - k theta_k)
/// so that r_dot = K_I (tau - r) with tau = J theta_dd + b theta_dot + k theta
/// = delta_f l (eq. 2): r is the first-order (eq. 3) estimate of the arm
/// torque, and r / l the arm force estimate.
class ArmForceObserver {
 public:
  ArmForceObserver(double inertia, double damping, double stiffness, double lever_arm, double gain);
  /// One sample; returns the force estimate delta_f_a [N] (across the arm, +
  /// in the direction that increases theta).
  double update(double theta, double theta_dot, double dt);
  void reset();
  double torque() const { return r_; }
  double force() const { return r_ / l_; }

 private:
  double J_, b_, k_, l_, K_;
  double r_ = 0.0, S_ = 0.0, p0_ = 0.0;
  bool started_ = false;
};

/// 001 eq. 4: arm force in the world frame, w_delta = R_wb R_ba_i [0, delta, 0]
/// (arm frame x along the arm, the force across it along y; 001 writes the
/// same vector in its own arm axes a_1/a_2). R_ba_i = Rz(direction_i + theta_i).
Vec3 arm_force_world(double force, double direction, double theta, const Mat3& R_wb);

/// 001 eq. 5 (ENU): delta_f_CoM = R (m a_imu - f e3); a_imu: specific force
/// measured by the IMU (body frame), f: collective thrust [N].
Vec3 com_force_raw(const Vec3& specific_force_body, const Mat3& R_wb, double thrust, double mass);

/// 001 eq. 6: 1 if sum_i |theta_i| over the valid arms > theta_th.
bool contact_indicator(const std::array<double, 4>& theta, const std::array<bool, 4>& valid, double threshold);

/// Adaptive gain of 001 eq. 7, element-wise and clamped to [0, 1] (the
/// weights 1 - kappa_f and kappa_f stay in [0, 1]).
Vec3 adaptive_gain(double xi_f, const Vec3& signal);

/// 001 eq. 7: delta_f = (1 - U + U kappa) . delta_CoM + (1 - kappa) . U sum_i delta_a^i
/// ('.' element-wise, U the contact indicator).
Vec3 fuse(const Vec3& com, const Vec3& arm_sum, const Vec3& kappa, bool contact);

/// Momentum-based external yaw-torque observer (001 ref. [21], z axis):
///   r_k = K_o (I w_k - I w_0 - S_k),  S_k = S_{k-1} + dt (tau_cmd_k + r_{k-1})
/// so r_dot = K_o (tau_ext - r). The gyroscopic term (I_yy - I_xx) w_x w_y is
/// zero for the symmetric vehicle.
class YawTorqueObserver {
 public:
  YawTorqueObserver(double inertia, double gain);
  double update(double yaw_rate, double commanded_torque, double dt);
  void reset();
  double value() const { return r_; }

 private:
  double I_, K_;
  double r_ = 0.0, S_ = 0.0, p0_ = 0.0;
  bool started_ = false;
};

/// Commanded yaw torque from per-rotor thrusts: sum_i s_i c_tau T_i.
double rotor_yaw_torque(const std::array<double, 4>& thrust, const std::array<double, 4>& spin_sign,
                        double torque_coefficient);

// ---------------------------------------------------------------------------
// The estimator of 001 Sec. III-A

/// One arm: median + low-pass + band-stop angle filter, finite-difference
/// rate, eq. 2-3 observer, and hold/drop of missing samples.
class ArmChannel {
 public:
  explicit ArmChannel(const Params& p);
  /// A sample (finite theta) or a missing one (NaN). Returns true while the
  /// arm is usable (a recent valid sample).
  bool update(double theta_raw, double dt);
  bool valid() const { return valid_; }
  double theta() const { return theta_; }  ///< filtered angle [rad]
  double force() const { return valid_ ? observer_.force() : 0.0; }
  void reset();

 private:
  int hold_samples_;
  bool bandstop_on_;
  MedianFilter median_;
  LowPassFilter lowpass_;
  BandStopFilter bandstop_;
  ArmForceObserver observer_;
  double theta_ = 0.0, last_raw_ = 0.0;
  int missing_ = 0;
  bool valid_ = false, have_raw_ = false;
};

/// Result of one arm-rate update.
struct Estimate {
  Vec3 force_world = Vec3::Zero();     ///< fused delta_f (001 eq. 7), world [N]
  Vec3 force_body = Vec3::Zero();      ///< the same in the body frame [N]
  Vec3 com_world = Vec3::Zero();       ///< delta_f_CoM (eq. 5, filtered), world [N]
  Vec3 arm_sum_world = Vec3::Zero();   ///< sum_i w_delta_a^i (eq. 4), world [N]
  Vec3 kappa = Vec3::Zero();           ///< kappa_f (eq. 7)
  std::array<double, 4> arm_force{};   ///< delta_f_a,i (eq. 2-3) [N]
  std::array<double, 4> theta{};       ///< filtered arm angles [rad]
  std::array<bool, 4> arm_valid{};
  int arms_valid = 0;
  bool contact = false;                ///< Upsilon (eq. 6)
  bool com_ready = false;              ///< an IMU sample and a thrust value have arrived
  double yaw_torque = 0.0;             ///< external yaw torque [N m]
  /// An arm is missing or the CoM estimate is not available: the estimate
  /// falls back to what remains (fewer arms; CoM only; arms only).
  bool degraded = false;
};

class XplorerForceEstimator {
 public:
  explicit XplorerForceEstimator(const Params& params);

  /// Flight-controller IMU sample (imu_rate_hz): specific force and angular
  /// rate in the body frame, attitude body -> world. Feeds eq. 5 and the yaw
  /// observer. Non-finite input must be filtered by the caller (node logic).
  void update_imu(const Vec3& specific_force_body, const Vec3& gyro_body, const Quat& q_wb, double dt);
  /// Latest collective thrust [N] (eq. 5; the node converts the normalised
  /// command with thrust_scale) and, if known, per-rotor thrusts for the yaw
  /// torque (otherwise the yaw observer sees zero commanded torque).
  void set_thrust(double collective_thrust);
  void set_rotor_thrusts(const std::array<double, 4>& thrust);

  /// Arm sample set at arm_rate_hz: raw angles (NaN = missing). Runs the
  /// arm filters and observers (eq. 2-3), eq. 4, eq. 6 and eq. 7.
  const Estimate& update_arms(const std::array<double, 4>& theta_raw, double dt);

  const Estimate& estimate() const { return est_; }
  const Params& params() const { return p_; }
  void reset();

 private:
  Params p_;
  std::array<ArmChannel, 4> arms_;
  std::array<MedianFilter, 3> com_median_;
  std::array<LowPassFilter, 3> com_lowpass_;
  YawTorqueObserver yaw_;
  Quat q_wb_ = Quat::Identity();
  Vec3 com_ = Vec3::Zero(), com_prev_ = Vec3::Zero();
  double thrust_ = 0.0;
  std::array<double, 4> rotor_thrust_{};
  bool have_thrust_ = false, have_imu_ = false, have_rotors_ = false, have_com_prev_ = false;
  Estimate est_;
};

}  // namespace xplorer_force_est
