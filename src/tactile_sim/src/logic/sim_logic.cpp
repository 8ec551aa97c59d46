#include "tactile_sim/logic/sim_logic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include "tactile_common/frames.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/crazyflie.hpp"
#include "tactile_sim/robot_model.hpp"
#include "tactile_sim/ducted_quad.hpp"
#include "tactile_sim/sensors.hpp"
#include "tactile_sim/whisker_barometer_model.hpp"
#include "tactile_sim/whisker_stage.hpp"
#include "tactile_sim/xplorer.hpp"

namespace tactile_sim {

namespace {

// Stream ids of the random sources SimLogic owns (vehicles own theirs).
constexpr uint64_t kStreamVehicle = 1;
constexpr uint64_t kStreamBarometerLeft = 10;
constexpr uint64_t kStreamBarometerRight = 11;
constexpr uint64_t kStreamFaults = 20;  // + index of the faulted topic
constexpr uint64_t kStreamTrialYaw = 30;

template <class Stamp>
void stamp(Stamp& s, int64_t ns) {
  tactile_common::to_stamp(ns, s);
}

void fill_pose(const RigidBodyState& x, geometry_msgs::msg::Pose& pose) {
  pose.position.x = x.position.x();
  pose.position.y = x.position.y();
  pose.position.z = x.position.z();
  pose.orientation.x = x.orientation.x();
  pose.orientation.y = x.orientation.y();
  pose.orientation.z = x.orientation.z();
  pose.orientation.w = x.orientation.w();
}

nav_msgs::msg::Odometry odometry(const RigidBodyState& x, int64_t now_ns, const std::string& frame,
                                  const std::string& child_frame) {
  nav_msgs::msg::Odometry m;
  stamp(m.header.stamp, now_ns);
  m.header.frame_id = frame;
  m.child_frame_id = child_frame;
  fill_pose(x, m.pose.pose);
  // REP-105: twist in the child (body) frame.
  const Vec3 v_body = x.orientation.conjugate() * x.velocity;
  m.twist.twist.linear.x = v_body.x();
  m.twist.twist.linear.y = v_body.y();
  m.twist.twist.linear.z = v_body.z();
  m.twist.twist.angular.x = x.angular_velocity.x();
  m.twist.twist.angular.y = x.angular_velocity.y();
  m.twist.twist.angular.z = x.angular_velocity.z();
  return m;
}

sensor_msgs::msg::Imu imu_msg(const ImuSample& s, const Quat& q, int64_t now_ns, const SimFrames& f) {
  constexpr double gyro_var = 0.0, accel_var = 0.0;  // not reported (0: unknown, REP 145)
  sensor_msgs::msg::Imu m;
  stamp(m.header.stamp, now_ns);
  m.header.frame_id = f.imu;
  m.orientation.x = q.x();
  m.orientation.y = q.y();
  m.orientation.z = q.z();
  m.orientation.w = q.w();
  m.angular_velocity.x = s.gyro.x();
  m.angular_velocity.y = s.gyro.y();
  m.angular_velocity.z = s.gyro.z();
  m.linear_acceleration.x = s.accel.x();
  m.linear_acceleration.y = s.accel.y();
  m.linear_acceleration.z = s.accel.z();
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity_covariance[static_cast<size_t>(4 * i)] = gyro_var;
    m.linear_acceleration_covariance[static_cast<size_t>(4 * i)] = accel_var;
  }
  return m;
}

sensor_msgs::msg::Range range_msg(double range, const RangeParams& p, int64_t now_ns, const SimFrames& f) {
  sensor_msgs::msg::Range m;
  stamp(m.header.stamp, now_ns);
  m.header.frame_id = f.tof_down;
  m.radiation_type = sensor_msgs::msg::Range::INFRARED;
  m.field_of_view = static_cast<float>(p.field_of_view);
  m.min_range = static_cast<float>(p.min_range);
  m.max_range = static_cast<float>(p.max_range);
  m.range = static_cast<float>(range);
  // Jazzy/Kilted layout: the variance of the model's noise at this range (0 = unknown
  // where the reading is not a range: -inf/+inf/NaN).
  const double sigma = p.noise_std + p.noise_proportional * range;
  m.variance = std::isfinite(range) ? static_cast<float>(sigma * sigma) : 0.0F;
  return m;
}

tactile_msgs::msg::OpticalFlow flow_msg(const FlowSample& s, int64_t now_ns, const SimFrames& f) {
  tactile_msgs::msg::OpticalFlow m;
  stamp(m.header.stamp, now_ns);
  m.header.frame_id = f.flow;
  m.flow_x = s.n_x;
  m.flow_y = s.n_y;
  m.integration_time = s.integration_time;
  m.quality = s.quality;
  return m;
}

bool every(int64_t k, double physics_hz, double rate_hz) {
  const auto n = static_cast<int64_t>(std::llround(physics_hz / rate_hz));
  return n <= 1 || k % n == 0;
}

double heading(const Quat& q) {
  const Vec3 x = q * Vec3::UnitX();
  return std::atan2(x.y(), x.x());
}

template <class Map>
double& at_least(Map& m, const char* key, double v) {
  auto [it, inserted] = m.emplace(key, v);
  if (!inserted) it->second = std::max(it->second, v);
  return it->second;
}

}  // namespace

// ---------------------------------------------------------------------------
// Vehicles

class SimLogic::Vehicle {
 public:
  virtual ~Vehicle() = default;
  /// Geometry of the vehicle's links (static transforms, robot_description).
  virtual tactile_common::RobotModel model() const = 0;
  /// The frame names its messages carry (set by SimLogic after construction).
  SimFrames frames;
  virtual void step(double dt, const Arena& arena) = 0;
  virtual const RigidBodyState& truth() const = 0;
  virtual RigidBodyState estimate() const = 0;
  virtual Vec3 external_force_world() const = 0;
  virtual std::vector<CollisionEvent> take_collisions() = 0;
  /// Setpoints; false if this vehicle does not take that kind.
  virtual bool hover_setpoint(const HoverSetpoint&) { return false; }
  virtual bool position_setpoint(const Vec3&, double) { return false; }
  virtual bool rotor_thrust(const std::array<double, 4>&) { return false; }
  /// Vehicle-specific sensors due at physics step k.
  virtual void sense(int64_t k, double physics_hz, int64_t now_ns, const Arena& arena, SimLogic::Outputs& out,
                     std::vector<Vec2>& whisker_contacts) = 0;
  /// Topics this vehicle publishes, with their type names (fault validation).
  virtual std::vector<std::pair<std::string, std::string>> topics() const = 0;
  virtual void summarize(Summary& s) const = 0;
};

namespace {

const char* kPressure = "tactile_msgs/msg/WhiskerPressure";
const char* kImuType = "sensor_msgs/msg/Imu";
const char* kRangeType = "sensor_msgs/msg/Range";
const char* kFlowType = "tactile_msgs/msg/OpticalFlow";
const char* kArmType = "tactile_msgs/msg/ArmImuArray";
const char* kThrustType = "tactile_msgs/msg/ThrustCommand";
const char* kWallType = "tactile_msgs/msg/WallEstimate";
const char* kTruthType = "tactile_msgs/msg/WhiskerGroundTruth";

/// Sets `field` of `params` from the scenario's vehicle.params (by name).
class ParamOverrides {
 public:
  ParamOverrides(const Scenario& s) : s_(s) {}
  void number(const char* name, double& field) {
    auto it = s_.vehicle_params.find(name);
    if (it == s_.vehicle_params.end()) return;
    used_.insert(name);
    if (auto d = std::get_if<double>(&it->second)) {
      field = *d;
    } else if (auto i = std::get_if<int64_t>(&it->second)) {
      field = static_cast<double>(*i);
    } else {
      throw ScenarioError(s_.source + ": vehicle.params." + name + ": expected a number");
    }
  }
  void flag(const char* name, bool& field) {
    auto it = s_.vehicle_params.find(name);
    if (it == s_.vehicle_params.end()) return;
    used_.insert(name);
    if (auto b = std::get_if<bool>(&it->second)) {
      field = *b;
    } else {
      throw ScenarioError(s_.source + ": vehicle.params." + name + ": expected true or false");
    }
  }
  /// Each model's validate(); its std::invalid_argument is rethrown naming the scenario file.
  template <class... Models>
  void validate(const Models&... models) const {
    try {
      (models.validate(), ...);
    } catch (const std::invalid_argument& e) {
      throw ScenarioError(s_.source + ": vehicle.params: " + e.what());
    }
  }
  /// Every override must have been used: unknown names are typos.
  void check_all_used(const std::string& known) const {
    for (const auto& [k, v] : s_.vehicle_params) {
      if (!used_.count(k)) {
        throw ScenarioError(s_.source + ": vehicle.params." + k + ": unknown parameter of " +
                            to_string(s_.vehicle) + " (settable: " + known + ")");
      }
    }
  }

 private:
  const Scenario& s_;
  std::set<std::string> used_;
};

ImuParams imu_at(double rate_hz) {
  ImuParams p;
  p.rate_hz = rate_hz;
  return p;
}

PositionSetpoint position_setpoint(const Vec3& position, double yaw) {
  PositionSetpoint sp;
  sp.position = position;
  sp.yaw = yaw;
  return sp;
}

/// Hold the initial pose: the position vehicles' setpoint before the pilot's first.
PositionSetpoint hold_initial(const Scenario& s) { return position_setpoint(s.initial_position, s.initial_yaw); }

/// The ducted quadrotor (004) and its IMU from the scenario's vehicle.params: the mass, and
/// accel_bias_sigma, the accelerometer's residual turn-on bias after calibration (1 sigma per
/// axis, drawn per seed; default 0 as ImuParams'), which INDI's dead-reckoned fail-safe
/// descent must tolerate (wall_effect_ekf README, "INDI fail-safe").
struct DuctedSetup {
  DuctedQuadParams vehicle;
  ImuParams imu;
};
DuctedSetup ducted_setup(const Scenario& s, double imu_hz) {
  DuctedSetup d;
  ParamOverrides o(s);
  o.number("mass", d.vehicle.mass);
  d.imu = imu_at(imu_hz);
  o.number("accel_bias_sigma", d.imu.accel_bias_initial_sigma);
  o.check_all_used("mass, accel_bias_sigma");
  o.validate(d.vehicle, d.imu);
  return d;
}

/// XPLORER and its flight-controller IMU from the scenario's vehicle.params
/// (001): the arm's spring-damper (eq. 2), the rigid-chassis comparison
/// vehicle (Sec. V-C4), the thrust curve behind the 32.5 N scale (Sec. V-A3)
/// and the accelerometer's errors. Values are checked by the models'
/// validate(), reported with the file.
struct XplorerSetup {
  XplorerParams vehicle;
  ImuParams imu;
};
XplorerSetup xplorer_setup(const Scenario& s, double imu_hz) {
  XplorerSetup x;
  XplorerParams& p = x.vehicle;
  ParamOverrides o(s);
  o.number("mass", p.mass);
  o.number("arm_inertia", p.arm_inertia);
  o.number("arm_damping", p.arm_damping);
  o.number("arm_stiffness", p.arm_stiffness);
  double max_deg = p.arm_max_deflection * 180.0 / M_PI;
  o.number("arm_max_deflection_deg", max_deg);
  p.arm_max_deflection = max_deg * M_PI / 180.0;
  o.flag("rigid_arms", p.rigid_arms);
  o.number("thrust_curve_factor", p.thrust_curve_factor);
  // The flight controller's accelerometer (001: PIXHAWK; the paper gives no
  // figures): ImuParams' BMI088-class defaults (no vibration, no turn-on
  // bias) unless the scenario sets accel_noise_density (propeller vibration)
  // and accel_bias_sigma (residual bias after calibration, 1 sigma per axis).
  x.imu = imu_at(imu_hz);
  o.number("accel_noise_density", x.imu.accel_noise_density);
  o.number("accel_bias_sigma", x.imu.accel_bias_initial_sigma);
  o.check_all_used(
      "mass, arm_inertia, arm_damping, arm_stiffness, arm_max_deflection_deg, rigid_arms, thrust_curve_factor, "
      "accel_noise_density, accel_bias_sigma");
  o.validate(p, x.imu);
  return x;
}

RigidBodyState initial_state(const Scenario& s) {
  RigidBodyState x;
  x.position = s.initial_position;
  x.orientation = Quat(Eigen::AngleAxisd(s.initial_yaw, Vec3::UnitZ()));
  return x;
}

// --- whiskered Crazyflie (paper 000) ------------------------------------------
class CrazyflieVehicle : public SimLogic::Vehicle {
 public:
  CrazyflieVehicle(const Scenario& s, uint64_t seed) : cf_(make_params(s), initial_state(s), stream_seed(seed, kStreamVehicle)),
        imu_(imu_at(kImuHz), seed) {
    WhiskerBarometerParams bp;
    baro_[0] = std::make_unique<WhiskerBarometerModel>(bp, stream_seed(seed, kStreamBarometerLeft));
    baro_[1] = std::make_unique<WhiskerBarometerModel>(bp, stream_seed(seed, kStreamBarometerRight));
  }

  tactile_common::RobotModel model() const override { return tactile_sim::robot_model(cf_.params()); }

  static CrazyflieParams make_params(const Scenario& s) {
    CrazyflieParams p;
    ParamOverrides o(s);
    o.number("mass", p.mass);
    o.number("drag_coeff", p.drag_coeff);
    o.number("guard_radius", p.guard_radius);
    o.flag("whiskers_enabled", p.whiskers_enabled);
    o.number("whisker_spacing", p.whisker_spacing);
    o.number("whisker_base_x", p.whisker_base_x);
    o.number("whisker_length", p.whisker.length);
    double placement_deg = std::numeric_limits<double>::quiet_NaN();
    o.number("whisker_placement_deg", placement_deg);
    if (std::isfinite(placement_deg)) p.whisker.placement_angle = placement_deg * M_PI / 180.0;
    o.number("mocap_position_noise", p.mocap_position_noise);
    o.number("flow_scale_error", p.flow_deck.flow_scale_error);
    o.number("gyro_bias", p.flow_deck.gyro_bias);
    o.number("accel_bias", p.flow_deck.accel_bias);
    o.check_all_used(
        "mass, drag_coeff, guard_radius, whiskers_enabled, whisker_spacing, whisker_base_x, whisker_length, "
        "whisker_placement_deg, mocap_position_noise, flow_scale_error, gyro_bias, accel_bias");
    p.estimate_mode = s.state_estimate == "flow_deck" ? StateEstimateMode::kFlowDeck
                      : s.state_estimate == "imu_tof" ? StateEstimateMode::kImuTof
                                                      : StateEstimateMode::kMocap;
    p.flow_deck.use_flow = p.estimate_mode != StateEstimateMode::kImuTof;
    p.validate();
    return p;
  }

  void step(double dt, const Arena& arena) override { cf_.step(dt, arena); }
  const RigidBodyState& truth() const override { return cf_.state(); }
  RigidBodyState estimate() const override { return cf_.estimate(); }
  Vec3 external_force_world() const override { return cf_.external_force_world(); }
  std::vector<CollisionEvent> take_collisions() override { return cf_.take_collisions(); }
  bool hover_setpoint(const HoverSetpoint& sp) override {
    cf_.set_setpoint(sp);
    return true;
  }

  void sense(int64_t k, double physics_hz, int64_t now_ns, const Arena& arena, SimLogic::Outputs& out,
             std::vector<Vec2>& contacts) override {
    if (every(k, physics_hz, kImuHz)) {
      const ImuSample s = imu_.sample(cf_.specific_force_body(), cf_.state().angular_velocity);
      out.imu.push_back({"imu", imu_msg(s, cf_.estimate().orientation, now_ns, frames)});
    }
    if (every(k, physics_hz, kBarometerHz)) {
      for (int i = 0; i < 2; ++i) {
        const auto& w = cf_.whiskers()[static_cast<size_t>(i)];
        const double noise_scale =
            w.contact && w.obstacle_id >= 0 ? material_scale(arena, w) : 1.0;
        const auto sample = baro_[static_cast<size_t>(i)]->step(1.0 / kBarometerHz, w.base_moment, cf_.motors_on(),
                                                               noise_scale);
        tactile_msgs::msg::WhiskerPressure p;
        stamp(p.header.stamp, now_ns);
        p.header.frame_id = frames.whisker[i];
        p.whisker_id = static_cast<uint8_t>(i);
        for (size_t c = 0; c < 3; ++c) {
          p.pressure[c] = sample.pressure[c];
          p.temperature[c] = sample.temperature[c];
        }
        p.sequence = sequence_[static_cast<size_t>(i)]++;
        static constexpr std::string_view kPressureTopics[2] = {"whisker/left/pressure", "whisker/right/pressure"};
        out.pressure.push_back({kPressureTopics[i], p});

        tactile_msgs::msg::WhiskerGroundTruth gt;
        gt.header = p.header;
        gt.whisker_id = p.whisker_id;
        gt.contact = w.contact;
        gt.load = w.base_moment;
        gt.depth = w.depth;
        gt.motors_on = cf_.motors_on();
        static constexpr std::string_view kTruthTopics[2] = {"ground_truth/whisker/left/contact",
                                                             "ground_truth/whisker/right/contact"};
        out.whisker_truth.push_back({kTruthTopics[i], gt});

        if (w.contact) {
          contacts.push_back(w.contact_point);
          contact_samples_[static_cast<size_t>(i)]++;
          max_moment_ = std::max(max_moment_, w.base_moment);
          if (std::isfinite(w.depth)) max_depth_[static_cast<size_t>(i)] = std::max(max_depth_[static_cast<size_t>(i)], w.depth);
          if (std::isnan(first_contact_s_)) first_contact_s_ = tactile_common::to_seconds(now_ns);
        }
        if (cf_.motors_on()) flying_samples_[static_cast<size_t>(i)]++;
      }
    }
    const auto& deck = cf_.flow_deck();
    if (cf_.params().estimate_mode != StateEstimateMode::kMocap) {
      if (deck.flow_updated()) out.flow.push_back({"flow", flow_msg(deck.last_flow(), now_ns, frames)});
      if (deck.range_updated()) {
        out.range.push_back({"tof", range_msg(deck.last_range(), deck.params().range, now_ns, frames)});
      }
    }
  }

  std::vector<std::pair<std::string, std::string>> topics() const override {
    std::vector<std::pair<std::string, std::string>> t = {
        {"imu", kImuType},
        {"whisker/left/pressure", kPressure},
        {"whisker/right/pressure", kPressure},
        {"ground_truth/whisker/left/contact", kTruthType},
        {"ground_truth/whisker/right/contact", kTruthType}};
    if (cf_.params().estimate_mode == StateEstimateMode::kFlowDeck) t.emplace_back("flow", kFlowType);
    if (cf_.params().estimate_mode != StateEstimateMode::kMocap) t.emplace_back("tof", kRangeType);
    return t;
  }

  void summarize(SimLogic::Summary& s) const override {
    static const char* kSides[2] = {"left", "right"};
    for (size_t i = 0; i < 2; ++i) {
      s[std::string("whisker_contact_fraction_") + kSides[i]] =
          flying_samples_[i] ? static_cast<double>(contact_samples_[i]) / static_cast<double>(flying_samples_[i]) : 0.0;
      s[std::string("max_true_depth_") + kSides[i] + "_m"] = max_depth_[i];
    }
    s["max_whisker_base_moment_nm"] = max_moment_;
    s["first_whisker_contact_s"] = first_contact_s_;
  }

 private:
  static double material_scale(const Arena& arena, const WhiskerCrazyflie::Whisker& w) {
    const Hit h = arena.closest(w.contact_point, 0.01);
    return h.hit ? arena.material(h.material).signal_noise_scale : 1.0;
  }

  // The Crazyflie's IMU as the ground station sees it: state logged over the
  // radio at 100 Hz (the onboard 1 kHz loop is inside the vehicle model).
  static constexpr double kImuHz = 100.0;
  static constexpr double kBarometerHz = 50.0;  // 000: whisker deck at 50 Hz
  WhiskerCrazyflie cf_;
  ImuModel imu_;
  std::array<std::unique_ptr<WhiskerBarometerModel>, 2> baro_;
  std::array<uint32_t, 2> sequence_{};
  std::array<uint64_t, 2> contact_samples_{}, flying_samples_{};
  std::array<double, 2> max_depth_{0.0, 0.0};
  double max_moment_ = 0.0;
  double first_contact_s_ = std::numeric_limits<double>::quiet_NaN();
};

// --- ducted quadrotor (paper 004) ------------------------------------------------
class DuctedVehicle : public SimLogic::Vehicle {
 public:
  DuctedVehicle(const Scenario& s, uint64_t seed) : DuctedVehicle(s, seed, ducted_setup(s, kImuHz)) {}
  DuctedVehicle(const Scenario& s, uint64_t seed, const DuctedSetup& d)
      : quad_(d.vehicle, initial_state(s)), imu_(d.imu, seed), tof_(RangeParams{}, seed), flow_(FlowParams{}, seed) {
    quad_.set_position_setpoint(hold_initial(s));
  }
  void step(double dt, const Arena& arena) override { quad_.step(dt, arena); }
  tactile_common::RobotModel model() const override { return tactile_sim::robot_model(quad_.params()); }
  const RigidBodyState& truth() const override { return quad_.state(); }
  RigidBodyState estimate() const override { return quad_.state(); }  // motion capture
  Vec3 external_force_world() const override { return quad_.external_force_world() + quad_.wall_force_world(); }
  std::vector<CollisionEvent> take_collisions() override { return quad_.take_collisions(); }
  bool position_setpoint(const Vec3& p, double yaw) override {
    quad_.set_position_setpoint(tactile_sim::position_setpoint(p, yaw));
    return true;
  }
  bool rotor_thrust(const std::array<double, 4>& t) override {
    quad_.set_rotor_thrusts(t);
    return true;
  }
  void sense(int64_t k, double physics_hz, int64_t now_ns, const Arena& arena, SimLogic::Outputs& out,
             std::vector<Vec2>&) override {
    const auto& x = quad_.state();
    const double height = x.position.z() - arena.floor_z();
    if (every(k, physics_hz, kImuHz)) {
      const ImuSample s = imu_.sample(quad_.specific_force_body(), x.angular_velocity);
      out.imu.push_back({"imu", imu_msg(s, x.orientation, now_ns, frames)});
    }
    if (every(k, physics_hz, tof_.params().rate_hz)) {
      out.range.push_back({"tof", range_msg(tof_.sample(height, x.orientation), tof_.params(), now_ns, frames)});
    }
    if (every(k, physics_hz, flow_.params().rate_hz)) {
      out.flow.push_back({"flow", flow_msg(flow_.sample(x.velocity, x.orientation, x.angular_velocity, height), now_ns, frames)});
    }
    if (every(k, physics_hz, 50.0)) {
      tactile_msgs::msg::ThrustCommand t;
      stamp(t.header.stamp, now_ns);
      t.header.frame_id = frames.base_link;
      t.normalized = std::numeric_limits<double>::quiet_NaN();
      t.total_thrust = quad_.collective_thrust();
      t.rotor_thrust.assign(quad_.rotor_commands().begin(), quad_.rotor_commands().end());
      out.thrust.push_back({"thrust_command", t});
    }
    if (every(k, physics_hz, 100.0)) {
      const WallTruth w = quad_.wall_truth();
      tactile_msgs::msg::WallEstimate m;
      stamp(m.header.stamp, now_ns);
      m.header.frame_id = frames.ground_truth_base_link;  // the true wall, in the true body frame
      m.wall_detected = w.present;
      m.distance = w.present ? w.distance : std::numeric_limits<double>::infinity();
      m.direction = w.direction;
      m.height = w.height;
      const Vec3 v_body = x.orientation.conjugate() * x.velocity;
      m.velocity.x = v_body.x();
      m.velocity.y = v_body.y();
      m.velocity.z = v_body.z();
      out.wall.push_back({"ground_truth/wall", m});
      if (w.present) min_wall_ = std::min(min_wall_, w.distance);
    }
  }
  std::vector<std::pair<std::string, std::string>> topics() const override {
    return {{"imu", kImuType}, {"tof", kRangeType}, {"flow", kFlowType}, {"thrust_command", kThrustType},
            {"ground_truth/wall", kWallType}};
  }
  void summarize(SimLogic::Summary& s) const override {
    s["min_wall_distance_m"] = min_wall_;
    // The accelerometer's bias at the end (turn-on bias + random walk), body frame: the truth
    // INDI's bias estimate is compared with.
    s["imu_accel_bias_x"] = imu_.accel_bias().x();
    s["imu_accel_bias_y"] = imu_.accel_bias().y();
    s["imu_accel_bias_z"] = imu_.accel_bias().z();
  }

 private:
  static constexpr double kImuHz = 500.0;
  DuctedQuad quad_;
  ImuModel imu_;
  RangeModel tof_;
  FlowModel flow_;
  double min_wall_ = std::numeric_limits<double>::infinity();
};


// --- XPLORER (paper 001) ------------------------------------------------------------
class XplorerVehicle : public SimLogic::Vehicle {
 public:
  XplorerVehicle(const Scenario& s, uint64_t seed) : XplorerVehicle(s, seed, xplorer_setup(s, kImuHz)) {}
  XplorerVehicle(const Scenario& s, uint64_t seed, const XplorerSetup& x)
      : x_(x.vehicle, initial_state(s)), imu_(x.imu, seed) {
    for (size_t i = 0; i < 4; ++i) {
      arm_imus_[i] = std::make_unique<ImuModel>(imu_at(kArmImuHz), seed, sensor_streams::kArmImuStreamBase + i);
    }
    x_.set_setpoint(hold_initial(s));
  }
  void step(double dt, const Arena& arena) override { x_.step(dt, arena); }
  tactile_common::RobotModel model() const override { return tactile_sim::robot_model(x_.params()); }
  const RigidBodyState& truth() const override { return x_.state(); }
  RigidBodyState estimate() const override { return x_.state(); }  // motion capture (001)
  Vec3 external_force_world() const override { return x_.external_force_world(); }
  std::vector<CollisionEvent> take_collisions() override { return x_.take_collisions(); }
  bool position_setpoint(const Vec3& p, double yaw) override {
    x_.set_setpoint(tactile_sim::position_setpoint(p, yaw));
    return true;
  }
  void sense(int64_t k, double physics_hz, int64_t now_ns, const Arena&, SimLogic::Outputs& out,
             std::vector<Vec2>&) override {
    const auto& st = x_.state();
    if (every(k, physics_hz, kImuHz)) {
      const ImuSample sm = imu_.sample(x_.specific_force_body(), st.angular_velocity);
      out.imu.push_back({"imu", imu_msg(sm, st.orientation, now_ns, frames)});
    }
    if (every(k, physics_hz, kArmImuHz)) {  // 001: arm IMUs at 50 Hz
      tactile_msgs::msg::ArmImuArray a;
      stamp(a.header.stamp, now_ns);
      a.header.frame_id = frames.base_link;
      for (int i = 0; i < 4; ++i) {
        const ArmImuTruth t = x_.arm_imu(i);
        const ImuSample sm = arm_imus_[static_cast<size_t>(i)]->sample(t.accel, t.gyro);
        tactile_msgs::msg::ArmImu m;
        m.arm_id = static_cast<uint8_t>(i);
        m.orientation.x = t.orientation.x();
        m.orientation.y = t.orientation.y();
        m.orientation.z = t.orientation.z();
        m.orientation.w = t.orientation.w();
        m.angular_velocity.x = sm.gyro.x();
        m.angular_velocity.y = sm.gyro.y();
        m.angular_velocity.z = sm.gyro.z();
        m.linear_acceleration.x = sm.accel.x();
        m.linear_acceleration.y = sm.accel.y();
        m.linear_acceleration.z = sm.accel.z();
        m.arm_angle = x_.arm_angles()[static_cast<size_t>(i)];
        a.arms.push_back(m);
        max_arm_ = std::max(max_arm_, std::abs(m.arm_angle));
      }
      out.arm_imu.push_back({"arm_imu", a});
      tactile_msgs::msg::ThrustCommand t;
      t.header = a.header;
      t.normalized = x_.thrust_command();
      t.total_thrust = x_.collective_thrust();
      t.rotor_thrust.assign(x_.rotor_thrusts().begin(), x_.rotor_thrusts().end());
      out.thrust.push_back({"thrust_command", t});
    }
  }
  std::vector<std::pair<std::string, std::string>> topics() const override {
    return {{"imu", kImuType}, {"arm_imu", kArmType}, {"thrust_command", kThrustType}};
  }
  void summarize(SimLogic::Summary& s) const override { s["max_arm_deflection_deg"] = max_arm_ * 180.0 / M_PI; }

 private:
  static constexpr double kImuHz = 500.0;
  static constexpr double kArmImuHz = 50.0;
  Xplorer x_;
  ImuModel imu_;
  std::array<std::unique_ptr<ImuModel>, 4> arm_imus_;
  double max_arm_ = 0.0;
};

// --- whisker on a linear stage (paper 002) --------------------------------------
class WhiskerStageVehicle : public SimLogic::Vehicle {
 public:
  WhiskerStageVehicle(const Scenario& s, uint64_t seed)
      : stage_(make_params(s), s.initial_position, s.initial_yaw, stream_seed(seed, kStreamVehicle)) {}

  static WhiskerStageParams make_params(const Scenario& s) {
    WhiskerStageParams p;
    ParamOverrides o(s);
    o.number("whisker_length", p.beam.length);
    o.number("youngs_modulus", p.beam.youngs_modulus);
    o.number("moment_of_inertia", p.beam.moment_of_inertia);
    o.number("taper_ratio", p.beam.taper_ratio);
    o.number("speed", p.speed);
    o.number("yaw_rate", p.yaw_rate);
    o.number("sample_rate_hz", p.sample_rate_hz);
    o.number("noise_relative", p.noise_relative);
    o.number("noise_absolute", p.noise_absolute);
    o.flag("noise_bounded", p.noise_bounded);
    o.number("pin_radius", p.pin_radius);
    o.check_all_used(
        "whisker_length, youngs_modulus, moment_of_inertia, taper_ratio, speed, yaw_rate, sample_rate_hz, "
        "noise_relative, noise_absolute, noise_bounded, pin_radius");
    o.validate(p);
    return p;
  }

  void step(double dt, const Arena&) override { stage_.step(dt); }
  tactile_common::RobotModel model() const override { return tactile_sim::robot_model(stage_.params()); }
  const RigidBodyState& truth() const override { return stage_.state(); }
  RigidBodyState estimate() const override { return stage_.state(); }  // stage encoders (002: 10 um)
  Vec3 external_force_world() const override { return Vec3::Zero(); }
  std::vector<CollisionEvent> take_collisions() override { return {}; }
  bool position_setpoint(const Vec3& p, double yaw) override {
    stage_.set_setpoint(p, yaw);
    return true;
  }
  void sense(int64_t k, double physics_hz, int64_t now_ns, const Arena& arena, SimLogic::Outputs& out,
             std::vector<Vec2>& contacts) override {
    if (!every(k, physics_hz, stage_.params().sample_rate_hz)) return;
    const WhiskerStage::Reading r = stage_.sense(arena);
    geometry_msgs::msg::WrenchStamped w;
    stamp(w.header.stamp, now_ns);
    w.header.frame_id = frames.whisker_base;
    w.wrench.torque.z = r.m0;
    out.wrench.push_back({"whisker/base_wrench", w});
    geometry_msgs::msg::WrenchStamped t = w;
    t.wrench.torque.z = r.m0_true;
    out.wrench.push_back({"ground_truth/whisker/base_wrench", t});
    ++samples_;
    if (r.contact) {
      contacts.push_back(r.contact_point);
      ++contact_samples_;
      if (!r.ok) ++failures_;
      max_moment_ = std::max(max_moment_, std::abs(r.m0_true));
    }
  }
  std::vector<std::pair<std::string, std::string>> topics() const override {
    return {{"whisker/base_wrench", "geometry_msgs/msg/WrenchStamped"},
            {"ground_truth/whisker/base_wrench", "geometry_msgs/msg/WrenchStamped"}};
  }
  void summarize(SimLogic::Summary& s) const override {
    s["whisker_contact_fraction"] = samples_ ? static_cast<double>(contact_samples_) / static_cast<double>(samples_) : 0.0;
    s["max_whisker_base_moment_nm"] = max_moment_;
    s["whisker_contact_failures"] = static_cast<double>(failures_);
  }

 private:
  WhiskerStage stage_;
  uint64_t samples_ = 0, contact_samples_ = 0, failures_ = 0;
  double max_moment_ = 0.0;
};

}  // namespace

// ---------------------------------------------------------------------------
// Faults

struct SimLogic::FaultSet {
  template <class T>
  using Map = std::map<std::string, TopicFaults<T>, std::less<>>;  // found by string_view
  std::tuple<Map<tactile_msgs::msg::WhiskerPressure>, Map<sensor_msgs::msg::Imu>, Map<sensor_msgs::msg::Range>,
             Map<nav_msgs::msg::Odometry>, Map<tactile_msgs::msg::OpticalFlow>, Map<tactile_msgs::msg::ArmImuArray>,
             Map<tactile_msgs::msg::ThrustCommand>>
      maps;

  /// Message types faults can be injected on (those with FaultChannels).
  template <class T>
  static constexpr bool supports =
      std::disjunction_v<std::is_same<T, tactile_msgs::msg::WhiskerPressure>, std::is_same<T, sensor_msgs::msg::Imu>,
                         std::is_same<T, sensor_msgs::msg::Range>, std::is_same<T, nav_msgs::msg::Odometry>,
                         std::is_same<T, tactile_msgs::msg::OpticalFlow>,
                         std::is_same<T, tactile_msgs::msg::ArmImuArray>,
                         std::is_same<T, tactile_msgs::msg::ThrustCommand>>;

  template <class T>
  TopicFaults<T>* find(std::string_view topic) {
    auto& m = std::get<Map<T>>(maps);
    auto it = m.find(topic);
    return it == m.end() ? nullptr : &it->second;
  }
  template <class T>
  void add(const std::string& topic, std::vector<FaultSpec> rules, uint64_t seed) {
    std::get<Map<T>>(maps).emplace(topic, TopicFaults<T>(std::move(rules), seed));
  }
};

// ---------------------------------------------------------------------------

void SimLogic::Outputs::clear() {
  pressure.clear();
  whisker_truth.clear();
  odometry.clear();
  imu.clear();
  range.clear();
  flow.clear();
  arm_imu.clear();
  thrust.clear();
  wrench.clear();
  wall.clear();
  collisions.clear();
}

size_t SimLogic::Outputs::size() const {
  return pressure.size() + whisker_truth.size() + odometry.size() + imu.size() + range.size() + flow.size() +
         arm_imu.size() + thrust.size() + wrench.size() + wall.size() + collisions.size();
}

SimFrames::SimFrames(std::string_view frame_prefix)
    : prefix(frame_prefix),
      map(tactile_common::frames::kMap),
      odom(tactile_common::prefixed(frame_prefix, tactile_common::frames::kOdom)),
      base_link(tactile_common::prefixed(frame_prefix, tactile_common::frames::kBaseLink)),
      imu(tactile_common::prefixed(frame_prefix, tactile_common::frames::kImu)),
      tof_down(tactile_common::prefixed(frame_prefix, tactile_common::frames::kTofDown)),
      flow(tactile_common::prefixed(frame_prefix, tactile_common::frames::kFlow)),
      whisker_base(tactile_common::prefixed(frame_prefix, "whisker_base")),
      whisker{tactile_common::prefixed(frame_prefix, tactile_common::frames::kWhiskerLeft),
              tactile_common::prefixed(frame_prefix, tactile_common::frames::kWhiskerRight)},
      ground_truth_odom(tactile_common::prefixed(frame_prefix, tactile_common::frames::kGroundTruthOdom)),
      ground_truth_base_link(tactile_common::prefixed(frame_prefix, tactile_common::frames::kGroundTruthBaseLink)) {
  tactile_common::validate_frame_prefix(frame_prefix);
}

SimLogic::SimLogic(const Scenario& scenario, uint64_t seed, double extra_arena_yaw, std::string_view frame_prefix)
    : scenario_(scenario), seed_(seed), frames_(frame_prefix), faults_(std::make_unique<FaultSet>()) {
  arena_ = std::make_unique<Arena>(
      Arena::from_yaml_text(scenario.arena_yaml, scenario.arena_source, scenario.arena_key));
  // Randomised trials rotate the arena about its own origin, then the
  // scenario's transform places it.
  if (extra_arena_yaw != 0.0) arena_->transform(0.0, 0.0, extra_arena_yaw);
  if (scenario.arena_x != 0.0 || scenario.arena_y != 0.0 || scenario.arena_yaw != 0.0) {
    arena_->transform(scenario.arena_x, scenario.arena_y, scenario.arena_yaw);
  }
  period_ns_ = static_cast<int64_t>(std::llround(1e9 / scenario.physics_rate_hz));
  dt_ = 1.0 / scenario.physics_rate_hz;
  switch (scenario.vehicle) {
    case VehicleType::kWhiskerCrazyflie: vehicle_ = std::make_unique<CrazyflieVehicle>(scenario, seed); break;
    case VehicleType::kDuctedQuadrotor: vehicle_ = std::make_unique<DuctedVehicle>(scenario, seed); break;
    case VehicleType::kXplorer: vehicle_ = std::make_unique<XplorerVehicle>(scenario, seed); break;
    case VehicleType::kWhiskerStage: vehicle_ = std::make_unique<WhiskerStageVehicle>(scenario, seed); break;
  }
  vehicle_->frames = frames_;
  robot_model_ = vehicle_->model();
  robot_model_.validate();

  // Faults: every rule must name a topic this simulator publishes, with a
  // message type that supports the fault.
  auto topics = vehicle_->topics();
  topics.emplace_back("odom", "nav_msgs/msg/Odometry");
  topics.emplace_back("ground_truth/odom", "nav_msgs/msg/Odometry");
  topics.emplace_back("ground_truth/external_force", "geometry_msgs/msg/WrenchStamped");
  topics.emplace_back("collisions", "tactile_msgs/msg/CollisionEvent");
  std::map<std::string, std::vector<FaultSpec>> by_topic;
  for (size_t i = 0; i < scenario.faults.size(); ++i) {
    const FaultSpec& f = scenario.faults[i];
    auto it = std::find_if(topics.begin(), topics.end(), [&](const auto& t) { return t.first == f.topic; });
    const std::string where = scenario.source + ": faults[" + std::to_string(i) + "].topic: ";
    if (it == topics.end()) {
      std::string list;
      for (const auto& t : topics) list += (list.empty() ? "" : ", ") + t.first;
      throw ScenarioError(where + "the " + std::string(to_string(scenario.vehicle)) + " simulator publishes no '" +
                          f.topic + "' (it publishes " + list + ")");
    }
    // ThrustCommand: the reported rotor thrusts the wall-effect EKF and xplorer_force_est
    // take; a dropout there stops the wall estimate while the INDI controller, on
    // odometry and IMU, still flies (test_wall_effect_sitl).
    static const std::set<std::string> supported = {kPressure, kImuType, kRangeType, kFlowType, kArmType,
                                                    kThrustType, "nav_msgs/msg/Odometry"};
    if (!supported.count(it->second)) {
      throw ScenarioError(where + "faults are supported on sensor topics (WhiskerPressure, Imu, Range, "
                                  "OpticalFlow, ArmImuArray, ThrustCommand, Odometry), not on " + it->second);
    }
    // A channel the message does not have would corrupt nothing while the fault counts
    // its injections (FaultChannels in faults.hpp numbers the channels).
    static const std::map<std::string, size_t> channels = {{kPressure, 3}, {kImuType, 6}, {kRangeType, 1},
                                                           {kFlowType, 2}, {kArmType, 4}, {kThrustType, 4},
                                                           {"nav_msgs/msg/Odometry", 3}};
    const size_t n = channels.at(it->second);
    if (f.channel >= 0 && static_cast<size_t>(f.channel) >= n) {
      throw ScenarioError(scenario.source + ": faults[" + std::to_string(i) + "].channel: " + it->second +
                          " on " + f.topic + " has channels 0-" + std::to_string(n - 1) + ", got " +
                          std::to_string(f.channel));
    }
    by_topic[f.topic].push_back(f);
  }
  uint64_t index = 0;
  for (auto& [topic, rules] : by_topic) {
    // A named copy for the lambda: capturing a structured binding is C++20 (clang refuses
    // it in C++17, which stopped scripts/fuzz.sh from building).
    const std::string& name = topic;
    const std::string type =
        std::find_if(topics.begin(), topics.end(), [&name](const auto& t) { return t.first == name; })->second;
    const uint64_t s = stream_seed(seed, kStreamFaults + index++);
    if (type == kPressure) faults_->add<tactile_msgs::msg::WhiskerPressure>(topic, rules, s);
    if (type == kImuType) faults_->add<sensor_msgs::msg::Imu>(topic, rules, s);
    if (type == kRangeType) faults_->add<sensor_msgs::msg::Range>(topic, rules, s);
    if (type == kFlowType) faults_->add<tactile_msgs::msg::OpticalFlow>(topic, rules, s);
    if (type == kArmType) faults_->add<tactile_msgs::msg::ArmImuArray>(topic, rules, s);
    if (type == kThrustType) faults_->add<tactile_msgs::msg::ThrustCommand>(topic, rules, s);
    if (type == "nav_msgs/msg/Odometry") faults_->add<nav_msgs::msg::Odometry>(topic, rules, s);
  }
}

SimLogic::~SimLogic() = default;

tactile_common::ParamMap SimLogic::default_parameters() {
  tactile_common::ParamMap p(kNodeName, "defaults");
  // Read at start (the world is built from them): read-only under ROS.
  p.set("scenario", std::string(""),
        {"scenario file to simulate (config/scenarios/*.yaml); required", "", {}, false, tactile_common::choice()});
  p.set("seed", int64_t{-1},
        {"random seed of the run; -1: the scenario's own seed", "",
         tactile_common::at_least(-1), false, tactile_common::choice()});
  p.set("frame_prefix", std::string(""),
        {"prefix of every frame but map, for several vehicles (cf1/: cf1/odom, cf1/base_link, cf1/ground_truth/odom)",
         "", {}, false, tactile_common::choice()});
  return p;
}

tactile_common::ParamMap SimLogic::component_parameters() {
  tactile_common::ParamMap p(kNodeName, "defaults");
  // 1000x: a bound of ours (the wall timer's period is the physics step divided by it).
  p.set("real_time_factor", 1.0,
        {"simulated seconds per wall-clock second (1: real time; a container that cannot keep up advances "
         "simulated time slower)", "", tactile_common::ParamRange{0.0, 1000.0, true, false}, false,
         tactile_common::choice()});
  p.set("wait_for_publisher", std::string(""),
        {"the clock starts once this topic (relative: in the node's namespace) has a publisher; \"\": at once", "",
         {}, false, tactile_common::choice()});
  p.set("wait_for_subscribers", std::string(""),
        {"comma-separated topics of the simulator's; it holds t = 0 until each has a subscriber in another "
         "process; \"\": none", "", {}, false, tactile_common::choice()});
  return p;
}

SimLogic::ComponentParams SimLogic::component_params_from(const tactile_common::ParamMap& params) {
  ComponentParams c;
  c.real_time_factor = params.get_double("real_time_factor");
  if (!(c.real_time_factor > 0.0) || c.real_time_factor > 1000.0) {
    throw params.error("real_time_factor", "must be in (0, 1000], got " + std::to_string(c.real_time_factor));
  }
  c.wait_for_publisher = params.get_string("wait_for_publisher");
  c.wait_for_subscribers = params.get_string("wait_for_subscribers");
  return c;
}

std::unique_ptr<SimLogic> SimLogic::from_parameters(const tactile_common::ParamMap& params) {
  const std::string path = params.get_string("scenario");
  if (path.empty()) throw params.error("scenario", "must name a scenario file (config/scenarios/*.yaml)");
  const int64_t seed = params.get_int64("seed", -1, std::numeric_limits<int64_t>::max());  // -1: the scenario's seed
  const std::string frame_prefix = params.get_string("frame_prefix");
  try {
    tactile_common::validate_frame_prefix(frame_prefix);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    throw params.error("frame_prefix", what.substr(what.find(": ") + 2));
  }
  const Scenario scenario = load_scenario(path);
  return std::make_unique<SimLogic>(scenario, seed < 0 ? scenario.seed : static_cast<uint64_t>(seed), 0.0,
                                    frame_prefix);
}

std::vector<tactile_common::StaticFrame> SimLogic::static_frames() const {
  std::vector<tactile_common::StaticFrame> out;
  out.push_back({frames_.map, frames_.odom, {}});
  out.push_back({frames_.map, frames_.ground_truth_odom, {}});
  for (auto& f : tactile_common::static_frames(robot_model_, frames_.prefix)) out.push_back(std::move(f));
  return out;
}

std::string SimLogic::robot_description() const {
  return tactile_common::to_urdf(robot_model_, frames_.prefix);
}

const Arena& SimLogic::arena() const { return *arena_; }

void SimLogic::on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg) {
  if (!std::isfinite(msg.vx) || !std::isfinite(msg.vy) || !std::isfinite(msg.yaw_rate) || !std::isfinite(msg.height)) {
    ++dropped_setpoints_;
    return;
  }
  HoverSetpoint sp;
  sp.vx = msg.vx;
  sp.vy = msg.vy;
  sp.yaw_rate = msg.yaw_rate;
  sp.height = msg.height;
  sp.land = msg.land;
  if (!vehicle_->hover_setpoint(sp)) ++dropped_setpoints_;
}

void SimLogic::on_position_setpoint(const geometry_msgs::msg::PoseStamped& msg) {
  const auto& p = msg.pose.position;
  const auto& q = msg.pose.orientation;
  const Quat quat(q.w, q.x, q.y, q.z);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(quat.norm()) ||
      quat.norm() < 1e-6) {
    ++dropped_setpoints_;
    return;
  }
  if (!vehicle_->position_setpoint(Vec3(p.x, p.y, p.z), heading(quat.normalized()))) ++dropped_setpoints_;
}

void SimLogic::on_rotor_thrust(const tactile_msgs::msg::ThrustCommand& msg) {
  if (msg.rotor_thrust.size() != 4 ||
      !std::all_of(msg.rotor_thrust.begin(), msg.rotor_thrust.end(), [](double t) { return std::isfinite(t); })) {
    ++dropped_setpoints_;
    return;
  }
  std::array<double, 4> t{};
  std::copy(msg.rotor_thrust.begin(), msg.rotor_thrust.end(), t.begin());
  if (!vehicle_->rotor_thrust(t)) ++dropped_setpoints_;
}

namespace {
template <class Map, class T>
void flush_delayed(Map& faults, std::vector<Published<T>>& out, int64_t now_ns) {
  for (auto& [topic, f] : faults) {
    std::vector<T> due;
    f.flush(now_ns, due);
    for (auto& d : due) out.push_back({topic, std::move(d)});
  }
}
}  // namespace

template <class T>
void SimLogic::emit(std::vector<Published<T>>& out, std::string_view topic, T msg, int64_t now_ns) {
  if constexpr (FaultSet::supports<T>) {
    if (auto* f = faults_->find<T>(topic)) {
      std::vector<T> delivered;
      f->push(std::move(msg), now_ns, delivered, fault_counts_);
      for (auto& m : delivered) out.push_back({topic, std::move(m)});
      return;
    }
  }
  out.push_back({topic, std::move(msg)});
}

void SimLogic::step(int64_t now_ns, Outputs& out) {
  if (started_) {
    vehicle_->step(dt_, *arena_);
    ++k_;
  }
  started_ = true;
  const double hz = scenario_.physics_rate_hz;

  Outputs& raw = scratch_;
  raw.clear();
  vehicle_->sense(k_, hz, now_ns, *arena_, raw, whisker_contacts_);
  const RigidBodyState& truth = vehicle_->truth();
  if (every(k_, hz, 100.0)) {
    const RigidBodyState est = vehicle_->estimate();
    // The estimate in odom -> base_link; the truth under its own pair (REP 105 frames
    // have one publisher each: ground truth must not fight the estimate for base_link).
    raw.odometry.push_back({"odom", odometry(est, now_ns, frames_.odom, frames_.base_link)});
    raw.odometry.push_back(
        {"ground_truth/odom", odometry(truth, now_ns, frames_.ground_truth_odom, frames_.ground_truth_base_link)});
    trajectory_.push_back({tactile_common::to_seconds(now_ns), truth, est});
    geometry_msgs::msg::WrenchStamped w;
    stamp(w.header.stamp, now_ns);
    w.header.frame_id = frames_.ground_truth_odom;  // a truth in the world frame
    const Vec3 f = vehicle_->external_force_world();
    max_external_force_ = std::max(max_external_force_, f.norm());
    w.wrench.force.x = f.x();
    w.wrench.force.y = f.y();
    w.wrench.force.z = f.z();
    raw.wrench.push_back({"ground_truth/external_force", w});
  }
  for (auto& c : vehicle_->take_collisions()) {
    tactile_msgs::msg::CollisionEvent m;
    stamp(m.header.stamp, now_ns);
    m.header.frame_id = frames_.ground_truth_odom;  // the true contact point, world frame
    m.part = c.part;
    m.point.x = c.point.x();
    m.point.y = c.point.y();
    m.point.z = truth.position.z();
    m.normal.x = c.normal.x();
    m.normal.y = c.normal.y();
    m.impact_speed = c.impact_speed;
    m.obstacle_id = c.obstacle_id;
    raw.collisions.push_back({"collisions", m});
    collisions_.push_back(c);
  }

  // Route everything through the fault injection, in a fixed order.
  for (auto& p : raw.pressure) emit(out.pressure, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.whisker_truth) emit(out.whisker_truth, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.odometry) emit(out.odometry, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.imu) emit(out.imu, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.range) emit(out.range, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.flow) emit(out.flow, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.arm_imu) emit(out.arm_imu, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.thrust) emit(out.thrust, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.wrench) emit(out.wrench, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.wall) emit(out.wall, p.topic, std::move(p.msg), now_ns);
  for (auto& p : raw.collisions) emit(out.collisions, p.topic, std::move(p.msg), now_ns);
  // Messages held back by a latency fault that are due now.
  flush_delayed(std::get<0>(faults_->maps), out.pressure, now_ns);
  flush_delayed(std::get<1>(faults_->maps), out.imu, now_ns);
  flush_delayed(std::get<2>(faults_->maps), out.range, now_ns);
  flush_delayed(std::get<3>(faults_->maps), out.odometry, now_ns);
  flush_delayed(std::get<4>(faults_->maps), out.flow, now_ns);
  flush_delayed(std::get<5>(faults_->maps), out.arm_imu, now_ns);
}

bool SimLogic::finished(int64_t now_ns) const {
  return tactile_common::to_seconds(now_ns) >= scenario_.duration_s - 0.5 * dt_;
}

SimLogic::Summary SimLogic::summary() const {
  Summary s;
  double path = 0.0, max_speed = 0.0, max_err = 0.0;
  double min_clear = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < trajectory_.size(); ++i) {
    const auto& p = trajectory_[i];
    if (i > 0) path += (p.truth.position - trajectory_[i - 1].truth.position).norm();
    max_speed = std::max(max_speed, p.truth.velocity.norm());
    max_err = std::max(max_err, (p.estimate.position - p.truth.position).norm());
    const Hit h = arena_->closest(p.truth.position.head<2>(), 100.0);
    if (h.hit) min_clear = std::min(min_clear, h.distance);
  }
  s["max_external_force_n"] = max_external_force_;
  s["path_length_m"] = path;
  s["max_speed_mps"] = max_speed;
  s["min_obstacle_distance_m"] = min_clear;
  s["max_estimate_error_m"] = max_err;
  if (!trajectory_.empty()) {
    const auto& last = trajectory_.back();
    s["final_x_m"] = last.truth.position.x();
    s["final_y_m"] = last.truth.position.y();
    s["final_z_m"] = last.truth.position.z();
    s["final_estimate_error_m"] = (last.estimate.position - last.truth.position).norm();
  }
  vehicle_->summarize(s);
  return s;
}

}  // namespace tactile_sim
