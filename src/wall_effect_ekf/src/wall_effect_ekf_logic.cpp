#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "tactile_common/time.hpp"

namespace wall_effect_ekf {

using tactile_common::ParamMap;

namespace {

using tactile_common::at_least;
using tactile_common::choice;
using tactile_common::closed;
using tactile_common::paper;
using tactile_common::ParamInfo;
using tactile_common::ParamRange;
using tactile_common::positive;
using tactile_common::tuned;

/// A double parameter of the node: its key, where it lives in Params and its description
/// (from the Params comments; config/wall_effect_ekf.yaml gives the same sources), unit and
/// the range validate() takes for the key alone (a bound set by another key is named in the
/// description). None is live: the component reads them at start, so `ros2 param set`
/// refuses every key (read-only).
struct DoubleKey {
  std::string key;
  double* field;
  ParamInfo info;
};

/// Every double parameter of the node.
std::vector<DoubleKey> doubles(WallEffectEkfLogic::Params& p) {
  EkfParams& e = p.ekf;
  VehicleParams& v = e.vehicle;
  const ParamRange below_one{0.0, 1.0, true, true};  // b1, b2: (0, 1) (004 eq. 4)
  return {
      {"rate_hz", &p.rate_hz, {"filter rate; ekf.dt = 1 / rate_hz (004: 100 Hz)", "Hz", positive(), false,
       paper("004 Methods: estimator sample rate 100 Hz")}},
      {"detection_range", &p.detection_range,
       {"wall_detected: y_hat below this and sqrt(P_yy) below detection_sigma (choice, a little beyond 004's "
        "d_dagger = 20 cm, within which its estimates are reliable)",
        "m", positive(), false, choice("a little beyond 004's d_dagger = 20 cm")}},
      {"detection_sigma", &p.detection_sigma,
       {"wall_detected: sqrt(P_yy) below this and y_hat below detection_range (choice)", "m", positive(), false,
        choice()}},
      {"max_input_age_s", &p.max_input_age_s,
       {"thrust command / IMU older than this: no filter step, nothing published (choice)", "s", positive(),
        false, choice()}},
      {"vehicle.mass", &v.mass,
       {"m (004: 280 g); the four rotors must carry it: vehicle.mass g < 4 vehicle.max_rotor_thrust", "kg",
        positive(), false, paper("004: 280 g")}},
      {"vehicle.rotor_offset", &v.rotor_offset,
       {"L of the rotor positions (+-L, +-L, 0) (004: d* = 17 cm with a 5 cm duct gap, and d_bar = 2.1 at "
        "0.2 m, give 0.082 m)",
        "m", positive(), false, paper("004: d* = 17 cm with a 5 cm duct gap, d_bar = 2.1 at 0.2 m")}},
      {"vehicle.torque_coefficient", &v.torque_coefficient, {"c_tau of 004 eq. 7 (choice)", "m", at_least(0.0), false,
       choice("004 eq. 7 gives no value")}},
      {"vehicle.linear_drag", &v.linear_drag,
       {"linear drag k subtracted from the wall-frame thrust in 004 eq. 6 (choice; 004 has none: 0 is the "
        "paper's model)",
        "N s/m", at_least(0.0), false, paper("004 eq. 6 has no drag: 0")}},
      {"vehicle.max_rotor_thrust", &v.max_rotor_thrust,
       {"per rotor (004: over 440 g of thrust in total); > vehicle.mass g / 4", "N", positive(), false,
        paper("004: over 440 g of thrust in total")}},
      {"proximity.rotor_radius", &v.proximity.rotor_radius,
       {"R of d_bar = y_i / R (004: AVAN 3024, R = 38 mm)", "m", positive(), false,
        paper("004: AVAN 3024, R = 38 mm")}},
      {"proximity.a1", &v.proximity.a1,
       {"a1 of gamma_h = a1 b1^d_bar (004 eq. 4 least-squares fit: 0.21)", "", positive(), false,
        paper("004 eq. 4: 0.21")}},
      {"proximity.b1", &v.proximity.b1, {"b1 of gamma_h = a1 b1^d_bar (004 eq. 4: 0.34)", "", below_one, false,
       paper("004 eq. 4: 0.34")}},
      {"proximity.a2", &v.proximity.a2,
       {"a2 of gamma_v = 1 + a2 b2^d_bar (004 eq. 4 least-squares fit: 0.06)", "", positive(), false,
        paper("004 eq. 4: 0.06")}},
      {"proximity.b2", &v.proximity.b2, {"b2 of gamma_v = 1 + a2 b2^d_bar (004 eq. 4: 0.54)", "", below_one, false,
       paper("004 eq. 4: 0.54")}},
      {"ekf.q_distance", &e.q_distance,
       {"process noise: random walk of y, the wall geometry changing (choice, 004 gives none: tuned for a "
        "consistent NEES on ducted_estimation)",
        "m/sqrt(s)", at_least(0.0), false, tuned("README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.q_height", &e.q_height,
       {"process noise: random walk of z, the floor changing (choice, NEES-tuned)", "m/sqrt(s)", at_least(0.0),
        false, tuned("README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.q_velocity", &e.q_velocity,
       {"process noise of the velocity: unmodelled force (choice)", "m/s^2/sqrt(Hz)", at_least(0.0), false, choice()}},
      {"ekf.q_attitude", &e.q_attitude,
       {"process noise of the attitude (choice, NEES-tuned)", "rad/sqrt(s)", at_least(0.0), false,
        tuned("README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.q_rate", &e.q_rate,
       {"process noise of the body rates: unmodelled torque, motor lag (choice)", "rad/s^2/sqrt(Hz)", at_least(0.0),
        false, choice()}},
      {"ekf.r_accel", &e.r_accel,
       {"accelerometer noise std, body x and y (004 eq. 23; choice for a BMI088, NEES-tuned)", "m/s^2", positive(),
        false, tuned("BMI088; README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.r_accel_z", &e.r_accel_z,
       {"accelerometer noise std, body z: larger, it also absorbs the thrust-magnitude error (motor lag, thrust "
        "constant) that would leak into y through gamma_v (choice)",
        "m/s^2", positive(), false, choice()}},
      {"motor_time_constant", &p.motor_time_constant,
       {"first-order lag of the commanded thrusts before the prediction, the motors' response; 0: none (choice: "
        "the simulated motors' 20 ms)",
        "s", at_least(0.0), false, choice("the simulated motors' 20 ms")}},
      {"ekf.r_gyro", &e.r_gyro, {"gyro noise std (choice, NEES-tuned)", "rad/s", positive(), false,
       tuned("README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.r_flow", &e.r_flow,
       {"optical-flow noise std (004 eq. 9-10; choice for a PMW3901, NEES-tuned)", "rad/s", positive(), false,
        tuned("PMW3901; README Results: NEES 6.5 of 11 on ducted_estimation, seeds 1-4")}},
      {"ekf.r_tof", &e.r_tof, {"ToF noise std (choice: a VL53L1x at 1 m, 2 mm + 0.5 %)", "m", positive(), false,
       choice("VL53L1x at 1 m: 2 mm + 0.5 %")}},
      {"ekf.gate_chi2", &e.gate_chi2,
       {"chi-square gate of the flow (2 dof) and ToF (1 dof) innovations: beyond it the sample is dropped and "
        "counted (choice)",
        "", positive(), false, choice()}},
      {"ekf.y_min", &e.y_min,
       {"lower bound of y_hat, the centre-to-wall distance (choice); < ekf.y_max", "m", positive(), false, choice()}},
      {"ekf.y_max", &e.y_max,
       {"upper bound of y_hat and its start, \"no wall nearby\": beyond it the wall effect is below the sensor "
        "noise (choice); > ekf.y_min",
        "m", positive(), false, choice()}},
      {"ekf.sigma_y_init", &e.sigma_y_init, {"initial std of y (choice)", "m", positive(), false, choice()}},
      {"ekf.sigma_yaw_init", &e.sigma_yaw_init,
       {"initial std of the yaw, i.e. of the wall direction (choice)", "rad", positive(), false, choice()}},
      {"ekf.sigma_y_max", &e.sigma_y_max, {"cap of sqrt(P_yy) (choice)", "m", positive(), false, choice()}},
      {"ekf.sigma_attitude_max", &e.sigma_attitude_max, {"cap of the attitude std (choice)", "rad", positive(), false,
       choice()}},
      {"ekf.min_height", &e.min_height,
       {"flow and ToF are used above this height (choice)", "m", at_least(0.0), false, choice()}},
      {"ekf.reacquire_accel", &e.reacquire_accel,
       {"re-acquisition: a low-passed horizontal specific force beyond this that the estimate does not explain "
        "re-initialises the wall direction and distance (choice)",
        "m/s^2", positive(), false, choice()}},
      {"ekf.reacquire_angle", &e.reacquire_angle,
       {"re-acquisition: the mismatch between that force's direction and the estimated wall direction that "
        "triggers it (choice)",
        "rad", positive(), false, choice()}},
      {"ekf.reacquire_time_constant", &e.reacquire_time_constant,
       {"re-acquisition: low-pass time constant of the horizontal specific force (choice)", "s", positive(),
        false, choice()}},
  };
}

bool finite3(const Vec3& v) { return v.allFinite(); }

}  // namespace

void WallEffectEkfLogic::Params::validate() const {
  auto fail = [](const char* f, const char* why, double v) {
    throw std::invalid_argument(std::string("WallEffectEkfLogic.") + f + ": " + why + ", got " + std::to_string(v));
  };
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) fail("rate_hz", "must be finite and > 0", rate_hz);
  if (!(detection_range > 0.0) || !std::isfinite(detection_range)) fail("detection_range", "must be finite and > 0", detection_range);
  if (!(detection_sigma > 0.0) || !std::isfinite(detection_sigma)) fail("detection_sigma", "must be finite and > 0", detection_sigma);
  if (!(max_input_age_s > 0.0) || !std::isfinite(max_input_age_s)) fail("max_input_age_s", "must be finite and > 0", max_input_age_s);
  if (!(motor_time_constant >= 0.0) || !std::isfinite(motor_time_constant)) fail("motor_time_constant", "must be finite and >= 0", motor_time_constant);
  ekf.validate();
  if (std::abs(ekf.dt * rate_hz - 1.0) > 1e-9) fail("rate_hz", "ekf.dt must be 1 / rate_hz", rate_hz);
}

ParamMap WallEffectEkfLogic::default_parameters() {
  Params d;
  ParamMap m(kNodeName, "defaults");
  for (const auto& k : doubles(d)) m.set(k.key, *k.field, k.info);
  const Vec3& J = d.ekf.vehicle.inertia_diag;
  m.set("vehicle.inertia_diag", std::vector<double>{J.x(), J.y(), J.z()},
        {"J diagonal, each finite and > 0 (choice: the simulated vehicle's estimate)", "kg m^2", {}, false,
         choice("the simulated vehicle's estimate")});
  m.set("min_flow_quality", static_cast<int64_t>(d.min_flow_quality),
        {"flow samples below this quality (the OpticalFlow quality byte) are dropped (choice)", "",
         closed(0, 255), false, choice()});
  return m;
}

WallEffectEkfLogic::Params WallEffectEkfLogic::params_from(const ParamMap& map) {
  Params p;
  const auto fields = doubles(p);
  for (const auto& k : fields) *k.field = map.get_double(k.key);
  const std::vector<double> J = map.get_double_array("vehicle.inertia_diag");
  if (J.size() != 3) throw map.error("vehicle.inertia_diag", "must have 3 entries, got " + std::to_string(J.size()));
  p.ekf.vehicle.inertia_diag = Vec3(J[0], J[1], J[2]);
  p.min_flow_quality = map.get_integer<uint64_t>("min_flow_quality", 0, 255);
  p.ekf.dt = 1.0 / p.rate_hz;
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    // Name the parameter: the message starts with "<Struct>.<field>:".
    const std::string what = e.what();
    const std::string field = what.substr(0, what.find(':'));
    const std::string leaf = field.substr(field.rfind('.') + 1);
    std::string key;
    if (leaf == "dt") {
      key = "rate_hz";  // ekf.dt = 1 / rate_hz (a rate so small that dt overflows)
    } else if (leaf.rfind("inertia_diag", 0) == 0) {
      key = "vehicle.inertia_diag";  // "inertia_diag[i]"
    }
    for (const auto& f : fields) {
      const std::string& k = f.key;
      if (!key.empty()) break;
      if (k.size() >= leaf.size() && k.compare(k.size() - leaf.size(), leaf.size(), leaf) == 0 &&
          (k.size() == leaf.size() || k[k.size() - leaf.size() - 1] == '.')) {
        key = k;
      }
    }
    if (key.empty()) key = field;  // no key of its own: the message's field, not another key
    throw map.error(key, what);
  }
  return p;
}

WallEffectEkfLogic::WallEffectEkfLogic(const Params& params)
    : params_((params.validate(), params)), ekf_(params.ekf) {}

int64_t WallEffectEkfLogic::period_ns() const { return tactile_common::from_seconds(1.0 / params_.rate_hz); }

void WallEffectEkfLogic::on_imu(const sensor_msgs::msg::Imu& msg) {
  ++stats_.imu;
  const Vec3 a(msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z);
  const Vec3 w(msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z);
  if (!finite3(a) || !finite3(w)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  acc_sum_ += a;
  gyro_sum_ += w;
  ++imu_count_;
  have_imu_ = true;
  imu_ns_ = tactile_common::from_stamp(msg.header.stamp);
}

void WallEffectEkfLogic::on_flow(const tactile_msgs::msg::OpticalFlow& msg) {
  ++stats_.flow;
  if (!std::isfinite(msg.flow_x) || !std::isfinite(msg.flow_y)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (msg.quality < params_.min_flow_quality) {
    ++stats_.dropped_low_quality;
    return;
  }
  flow_ = Vec2(msg.flow_x, msg.flow_y);
  flow_new_ = true;
}

void WallEffectEkfLogic::on_range(const sensor_msgs::msg::Range& msg) {
  ++stats_.range;
  if (std::isnan(msg.range)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (std::isinf(msg.range)) {  // REP-117: no return / too close
    ++stats_.dropped_out_of_range;
    return;
  }
  range_ = msg.range;
  range_new_ = true;
}

void WallEffectEkfLogic::on_thrust(const tactile_msgs::msg::ThrustCommand& msg) {
  ++stats_.thrust;
  if (msg.rotor_thrust.size() != 4) {
    ++stats_.dropped_bad_thrust;
    return;
  }
  if (!msg.header.frame_id.empty()) body_frame_ = msg.header.frame_id;
  Vec4 t;
  for (int i = 0; i < 4; ++i) t[i] = msg.rotor_thrust[static_cast<size_t>(i)];
  if (!t.allFinite()) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (t.minCoeff() < 0.0) {
    ++stats_.dropped_bad_thrust;
    return;
  }
  thrust_ = t;
  have_thrust_ = true;
  thrust_ns_ = tactile_common::from_stamp(msg.header.stamp);
}

std::optional<tactile_msgs::msg::WallEstimate> WallEffectEkfLogic::on_timer(int64_t now_ns) {
  const int64_t max_age = tactile_common::from_seconds(params_.max_input_age_s);
  if (!have_thrust_ || !have_imu_ || now_ns - thrust_ns_ > max_age || now_ns - imu_ns_ > max_age) {
    ++stats_.ticks_without_input;
    acc_sum_.setZero();
    gyro_sum_.setZero();
    imu_count_ = 0;
    return std::nullopt;
  }
  if (!started_) {
    // Start at the measured height (level), the wall at the far bound.
    ekf_.reset(range_new_ ? range_ : 0.0);
    started_ = true;
  }
  if (!lag_started_ || params_.motor_time_constant <= 0.0) {
    thrust_lag_ = thrust_;
    lag_started_ = true;
  } else {
    thrust_lag_ += (thrust_ - thrust_lag_) * (1.0 - std::exp(-params_.ekf.dt / params_.motor_time_constant));
  }
  ekf_.predict(thrust_lag_);                               // 004 eq. 21-22
  if (imu_count_ > 0) {
    ekf_.update_accel(acc_sum_ / imu_count_);              // 004 eq. 23-25
    ekf_.update_gyro(gyro_sum_ / imu_count_);
  } else {
    ++stats_.ticks_without_imu;
  }
  acc_sum_.setZero();
  gyro_sum_.setZero();
  imu_count_ = 0;
  if (flow_new_) ekf_.update_flow(flow_);
  if (range_new_) ekf_.update_tof(range_);
  flow_new_ = range_new_ = false;

  const WallState& x = ekf_.state();
  const Mat3 C = ekf_.output_covariance();
  tactile_msgs::msg::WallEstimate out;
  tactile_common::to_stamp(now_ns, out.header.stamp);
  out.header.frame_id = body_frame_;  // the thrust command's body frame (cf1/base_link with a prefix)
  out.distance = x.y;
  out.direction = x.wall_direction();
  out.height = x.z;
  out.velocity.x = x.v.x();
  out.velocity.y = x.v.y();
  out.velocity.z = x.v.z();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.covariance[static_cast<size_t>(3 * r + c)] = C(r, c);
  out.wall_detected = x.y < params_.detection_range && std::sqrt(C(0, 0)) < params_.detection_sigma;
  ++stats_.published;
  return out;
}

}  // namespace wall_effect_ekf
