// XPLORER external force estimation (001 eq. 2-7) and yaw-torque observer.
#include "xplorer_force_est/force_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace xplorer_force_est {
namespace {

[[noreturn]] void bad(const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << "Params." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const std::string& f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(f, "must be finite and > 0", v);
}
void non_negative(const std::string& f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(f, "must be finite and >= 0", v);
}
void odd_window(const std::string& f, int v) {
  if (v < 1 || v > MedianFilter::kMaxWindow || v % 2 == 0) bad(f, "must be odd and in [1, 15]", v);
}
Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

}  // namespace

const char* to_string(KappaMode m) { return m == KappaMode::kRate ? "rate" : "magnitude"; }

KappaMode kappa_mode_from_string(const std::string& s) {
  if (s == "rate") return KappaMode::kRate;
  if (s == "magnitude") return KappaMode::kMagnitude;
  throw std::invalid_argument("Params.kappa_mode: must be \"rate\" or \"magnitude\", got \"" + s + "\"");
}

void Params::validate() const {
  positive("arm_rate_hz", arm_rate_hz);
  positive("imu_rate_hz", imu_rate_hz);
  odd_window("arm_median_window", arm_median_window);
  positive("arm_lowpass_hz", arm_lowpass_hz);
  if (arm_lowpass_hz >= 0.5 * arm_rate_hz) bad("arm_lowpass_hz", "must be below arm_rate_hz / 2", arm_lowpass_hz);
  positive("arm_bandstop_hz", arm_bandstop_hz);
  if (arm_bandstop_hz >= 0.5 * arm_rate_hz) bad("arm_bandstop_hz", "must be below arm_rate_hz / 2", arm_bandstop_hz);
  positive("arm_bandstop_q", arm_bandstop_q);
  if (arm_hold_samples < 0) bad("arm_hold_samples", "must be >= 0", arm_hold_samples);
  positive("arm_inertia", arm_inertia);
  non_negative("arm_damping", arm_damping);
  positive("arm_stiffness", arm_stiffness);
  positive("lever_arm", lever_arm);
  positive("observer_gain", observer_gain);
  if (observer_gain / arm_rate_hz >= 1.0)
    bad("observer_gain", "K_I / arm_rate_hz must be < 1 (stable, non-oscillating discrete observer)", observer_gain);
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(arm_directions[i])) bad("arm_directions[" + std::to_string(i) + "]", "must be finite", arm_directions[i]);
  }
  positive("mass", mass);
  positive("thrust_scale", thrust_scale);
  positive("gravity", gravity);
  odd_window("com_median_window", com_median_window);
  positive("com_lowpass_hz", com_lowpass_hz);
  if (com_lowpass_hz >= 0.5 * imu_rate_hz) bad("com_lowpass_hz", "must be below imu_rate_hz / 2", com_lowpass_hz);
  positive("contact_threshold", contact_threshold);
  non_negative("xi_f", xi_f);
  positive("yaw_inertia", yaw_inertia);
  positive("yaw_observer_gain", yaw_observer_gain);
  if (yaw_observer_gain / imu_rate_hz >= 1.0)
    bad("yaw_observer_gain", "K_o / imu_rate_hz must be < 1", yaw_observer_gain);
  non_negative("torque_coefficient", torque_coefficient);
  for (int i = 0; i < 4; ++i) {
    if (spin_sign[i] != 1.0 && spin_sign[i] != -1.0) bad("spin_sign[" + std::to_string(i) + "]", "must be +1 or -1", spin_sign[i]);
  }
}

// --- 001 eq. 2-3 -------------------------------------------------------------
ArmForceObserver::ArmForceObserver(double inertia, double damping, double stiffness, double lever_arm, double gain)
    : J_(inertia), b_(damping), k_(stiffness), l_(lever_arm), K_(gain) {}

void ArmForceObserver::reset() {
  r_ = S_ = p0_ = 0.0;
  started_ = false;
}

double ArmForceObserver::update(double theta, double theta_dot, double dt) {
  const double p = J_ * theta_dot;  // generalised momentum of the arm (eq. 2)
  if (!started_) {
    p0_ = p;
    started_ = true;
  }
  S_ += dt * (r_ - b_ * theta_dot - k_ * theta);
  r_ = K_ * (p - p0_ - S_);  // r_dot = K_I (tau - r): 001 eq. 3 on tau = delta_f l
  return r_ / l_;            // 001 eq. 2: delta_tau = delta_f l
}

// --- 001 eq. 4 ----------------------------------------------------------------
Vec3 arm_force_world(double force, double direction, double theta, const Mat3& R_wb) {
  return R_wb * (rot_z(direction + theta) * Vec3(0.0, force, 0.0));  // w_R_b b_R_ai a_delta
}

// --- 001 eq. 5 ----------------------------------------------------------------
Vec3 com_force_raw(const Vec3& specific_force_body, const Mat3& R_wb, double thrust, double mass) {
  // m v_dot + m g e3 - f R e3 = R (m a_imu - f e3)   (ENU form of 001 eq. 5)
  return R_wb * (mass * specific_force_body - thrust * Vec3::UnitZ());
}

// --- 001 eq. 6 ----------------------------------------------------------------
bool contact_indicator(const std::array<double, 4>& theta, const std::array<bool, 4>& valid, double threshold) {
  double sum = 0.0;
  for (size_t i = 0; i < 4; ++i) {
    if (valid[i]) sum += std::abs(theta[i]);
  }
  return sum > threshold;
}

// --- 001 eq. 7 ----------------------------------------------------------------
Vec3 adaptive_gain(double xi_f, const Vec3& signal) {
  return (xi_f * signal.cwiseAbs()).cwiseMin(1.0);
}

Vec3 fuse(const Vec3& com, const Vec3& arm_sum, const Vec3& kappa, bool contact) {
  const double U = contact ? 1.0 : 0.0;
  const Vec3 one = Vec3::Ones();
  return (one - U * one + U * kappa).cwiseProduct(com) + U * (one - kappa).cwiseProduct(arm_sum);
}

// --- yaw-torque observer ---------------------------------------------------------
YawTorqueObserver::YawTorqueObserver(double inertia, double gain) : I_(inertia), K_(gain) {}

void YawTorqueObserver::reset() {
  r_ = S_ = p0_ = 0.0;
  started_ = false;
}

double YawTorqueObserver::update(double yaw_rate, double commanded_torque, double dt) {
  const double p = I_ * yaw_rate;
  if (!started_) {
    p0_ = p;
    started_ = true;
  }
  S_ += dt * (commanded_torque + r_);
  r_ = K_ * (p - p0_ - S_);
  return r_;
}

double rotor_yaw_torque(const std::array<double, 4>& thrust, const std::array<double, 4>& spin_sign,
                        double torque_coefficient) {
  double t = 0.0;
  for (size_t i = 0; i < 4; ++i) t += spin_sign[i] * torque_coefficient * thrust[i];
  return t;
}

// --- one arm ------------------------------------------------------------------------
ArmChannel::ArmChannel(const Params& p)
    : hold_samples_(p.arm_hold_samples),
      bandstop_on_(p.arm_bandstop),
      median_(p.arm_median_window),
      lowpass_(p.arm_lowpass_hz, p.arm_rate_hz),
      bandstop_(p.arm_bandstop_hz, p.arm_bandstop_q, p.arm_rate_hz),
      observer_(p.arm_inertia, p.arm_damping, p.arm_stiffness, p.lever_arm, p.observer_gain) {}

void ArmChannel::reset() {
  median_.reset();
  lowpass_.reset();
  bandstop_.reset();
  observer_.reset();
  theta_ = last_raw_ = 0.0;
  missing_ = 0;
  valid_ = have_raw_ = false;
}

bool ArmChannel::update(double theta_raw, double dt) {
  if (!std::isfinite(theta_raw)) {
    if (!have_raw_ || ++missing_ > hold_samples_) {
      if (have_raw_) reset();  // dropped: restart from the next valid sample
      return false;
    }
    theta_raw = last_raw_;  // hold the last sample for a short gap
  } else {
    missing_ = 0;
    last_raw_ = theta_raw;
    have_raw_ = true;
  }
  // 001 Sec. V-A2: median, low-pass, band-stop.
  double th = lowpass_.update(median_.update(theta_raw));
  if (bandstop_on_) th = bandstop_.update(th);
  const double rate = valid_ ? (th - theta_) / dt : 0.0;
  theta_ = th;
  observer_.update(theta_, rate, dt);
  valid_ = true;
  return true;
}

// --- the estimator ----------------------------------------------------------------------
namespace {
template <class T, class... A>
std::array<T, 3> three(const A&... a) {
  return {T(a...), T(a...), T(a...)};
}
template <class T, class... A>
std::array<T, 4> four(const A&... a) {
  return {T(a...), T(a...), T(a...), T(a...)};
}
}  // namespace

XplorerForceEstimator::XplorerForceEstimator(const Params& params)
    : p_((params.validate(), params)),
      arms_(four<ArmChannel>(p_)),
      com_median_(three<MedianFilter>(p_.com_median_window)),
      com_lowpass_(three<LowPassFilter>(p_.com_lowpass_hz, p_.imu_rate_hz)),
      yaw_(p_.yaw_inertia, p_.yaw_observer_gain) {}

void XplorerForceEstimator::reset() {
  for (auto& a : arms_) a.reset();
  for (auto& m : com_median_) m.reset();
  for (auto& l : com_lowpass_) l.reset();
  yaw_.reset();
  com_.setZero();
  com_prev_.setZero();
  have_thrust_ = have_imu_ = have_rotors_ = have_com_prev_ = false;
  est_ = Estimate{};
}

void XplorerForceEstimator::set_thrust(double collective_thrust) {
  thrust_ = collective_thrust;
  have_thrust_ = true;
}

void XplorerForceEstimator::set_rotor_thrusts(const std::array<double, 4>& thrust) {
  rotor_thrust_ = thrust;
  have_rotors_ = true;
}

void XplorerForceEstimator::update_imu(const Vec3& specific_force_body, const Vec3& gyro_body, const Quat& q_wb,
                                       double dt) {
  q_wb_ = q_wb.normalized();
  const Mat3 R = q_wb_.toRotationMatrix();
  if (have_thrust_) {
    const Vec3 raw = com_force_raw(specific_force_body, R, thrust_, p_.mass);  // 001 eq. 5
    for (int i = 0; i < 3; ++i) com_[i] = com_lowpass_[i].update(com_median_[i].update(raw[i]));  // median low-pass
    have_imu_ = true;
  }
  const double tau_cmd = have_rotors_ ? rotor_yaw_torque(rotor_thrust_, p_.spin_sign, p_.torque_coefficient) : 0.0;
  // Body yaw momentum about the body z axis (near hover the body and world z coincide).
  est_.yaw_torque = yaw_.update(gyro_body.z(), tau_cmd, dt);
}

const Estimate& XplorerForceEstimator::update_arms(const std::array<double, 4>& theta_raw, double dt) {
  const Mat3 R = q_wb_.toRotationMatrix();
  Estimate& e = est_;
  e.arm_sum_world.setZero();
  e.arms_valid = 0;
  for (size_t i = 0; i < 4; ++i) {
    e.arm_valid[i] = arms_[i].update(theta_raw[i], dt);
    e.theta[i] = e.arm_valid[i] ? arms_[i].theta() : 0.0;
    e.arm_force[i] = arms_[i].force();
    if (e.arm_valid[i]) {
      ++e.arms_valid;
      e.arm_sum_world += arm_force_world(e.arm_force[i], p_.arm_directions[i], e.theta[i], R);  // 001 eq. 4
    }
  }
  e.contact = contact_indicator(e.theta, e.arm_valid, p_.contact_threshold);  // 001 eq. 6
  e.com_ready = have_imu_;
  e.com_world = com_;
  if (have_imu_) {
    const Vec3 signal = p_.kappa_mode == KappaMode::kRate ? Vec3(have_com_prev_ ? Vec3((com_ - com_prev_) / dt) : Vec3::Zero())
                                                          : com_;
    e.kappa = adaptive_gain(p_.xi_f, signal);
    com_prev_ = com_;
    have_com_prev_ = true;
    e.force_world = fuse(com_, e.arm_sum_world, e.kappa, e.contact);  // 001 eq. 7
  } else {
    // No CoM estimate yet: the arms alone (eq. 7 with kappa = 0 in contact, 0 otherwise).
    e.kappa.setZero();
    e.force_world = e.contact ? e.arm_sum_world : Vec3::Zero();
  }
  e.force_body = R.transpose() * e.force_world;
  e.degraded = e.arms_valid < 4 || !have_imu_;
  return e;
}

}  // namespace xplorer_force_est
