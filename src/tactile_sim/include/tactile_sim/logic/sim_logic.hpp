// Node logic of the simulator: the SITL world of a scenario stepped at the
// physics rate on the host's clock, publishing sensor and ground-truth
// messages at their own rates and taking setpoints. Topics and rates:
// docs/sitl_design.md. No ROS: the standalone host (and an rclcpp component
// where ROS 2 exists) call step() from a timer at period_ns().
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "sensor_msgs/msg/range.hpp"
#include "tactile_msgs/msg/arm_imu_array.hpp"
#include "tactile_msgs/msg/collision_event.hpp"
#include "tactile_msgs/msg/hover_setpoint.hpp"
#include "tactile_msgs/msg/optical_flow.hpp"
#include "tactile_msgs/msg/thrust_command.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "tactile_msgs/msg/whisker_ground_truth.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "tactile_common/frames.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_sim/arena.hpp"
#include "tactile_sim/logic/faults.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_sim {

/// A message and the topic it goes to. `topic` views a name that lives as long as the
/// SimLogic (a string literal or a name the simulator keeps), so emitting a message does
/// not copy its topic name (issue 18: a heap string per message before).
template <class T>
struct Published {
  std::string_view topic;
  T msg;
};

/// The frame names the simulator's messages and transforms carry, every one
/// behind the frame_prefix (tactile_common/frames.hpp has the tree) except
/// map, which all vehicles of one world share.
struct SimFrames {
  SimFrames() : SimFrames("") {}
  explicit SimFrames(std::string_view prefix);
  std::string prefix;
  std::string map, odom, base_link, imu, tof_down, flow, whisker_base;
  std::string whisker[2];  ///< left, right
  std::string ground_truth_odom, ground_truth_base_link;
};

/// One point of the recorded trajectory (100 Hz): truth and state estimate.
struct TrajectoryPoint {
  double t = 0.0;
  RigidBodyState truth;
  RigidBodyState estimate;
};

class SimLogic {
 public:
  static constexpr const char* kNodeName = "tactile_sim";
  static constexpr const char* kHoverSetpointTopic = "cmd_hover";
  static constexpr const char* kPositionSetpointTopic = "cmd_position";
  static constexpr const char* kRotorThrustTopic = "cmd_rotor_thrust";

  struct Outputs {
    std::vector<Published<tactile_msgs::msg::WhiskerPressure>> pressure;
    std::vector<Published<tactile_msgs::msg::WhiskerGroundTruth>> whisker_truth;
    std::vector<Published<nav_msgs::msg::Odometry>> odometry;
    std::vector<Published<sensor_msgs::msg::Imu>> imu;
    std::vector<Published<sensor_msgs::msg::Range>> range;
    std::vector<Published<tactile_msgs::msg::OpticalFlow>> flow;
    std::vector<Published<tactile_msgs::msg::ArmImuArray>> arm_imu;
    std::vector<Published<tactile_msgs::msg::ThrustCommand>> thrust;
    std::vector<Published<geometry_msgs::msg::WrenchStamped>> wrench;
    std::vector<Published<tactile_msgs::msg::WallEstimate>> wall;
    std::vector<Published<tactile_msgs::msg::CollisionEvent>> collisions;
    void clear();
    size_t size() const;
  };

  /// Ground-truth summary of a run (metrics.json), by name.
  using Summary = std::map<std::string, double>;

  /// Builds the world of `scenario` for one run: arena (with the scenario's
  /// transform plus `extra_arena_yaw` [rad] about the arena transform's
  /// origin, for randomised trials), vehicle, sensors, faults; all noise
  /// seeded from `seed`. Throws ScenarioError / ArenaError /
  /// std::invalid_argument naming the file, key and reason.
  /// `frame_prefix` goes before every frame name but map (tactile_common::validate_frame_prefix).
  SimLogic(const Scenario& scenario, uint64_t seed, double extra_arena_yaw = 0.0, std::string_view frame_prefix = "");

  /// Node parameters of the simulator when it runs as a node (rclcpp
  /// component): `scenario` (path of the scenario file), `seed` (-1: the
  /// scenario's own seed) and `frame_prefix` (string before every frame name
  /// but map, "" or ending in '/': "cf1/" gives cf1/base_link).
  static tactile_common::ParamMap default_parameters();
  /// Loads the scenario named by the parameters and builds the world.
  /// Errors name the parameter source or the scenario file, key and reason.
  static std::unique_ptr<SimLogic> from_parameters(const tactile_common::ParamMap& params);

  /// The rclcpp component's own keys, beside default_parameters() on the same node (the
  /// standalone host steps the world itself and reads none): `real_time_factor`
  /// (simulated seconds per wall-clock second, (0, 1000]), `wait_for_publisher` and
  /// `wait_for_subscribers` (README "ROS 2 component"). Read at start (read-only).
  static tactile_common::ParamMap component_parameters();
  struct ComponentParams {
    double real_time_factor = 1.0;
    std::string wait_for_publisher;    ///< "" : the clock starts at once
    std::string wait_for_subscribers;  ///< comma-separated topics; "" : none
  };
  /// The component's keys from `params`; ParamError naming the key for a value outside
  /// its range.
  static ComponentParams component_params_from(const tactile_common::ParamMap& params);
  ~SimLogic();
  SimLogic(const SimLogic&) = delete;
  SimLogic& operator=(const SimLogic&) = delete;

  /// Physics step [ns].
  int64_t period_ns() const { return period_ns_; }

  void on_hover_setpoint(const tactile_msgs::msg::HoverSetpoint& msg);
  void on_position_setpoint(const geometry_msgs::msg::PoseStamped& msg);
  void on_rotor_thrust(const tactile_msgs::msg::ThrustCommand& msg);

  /// The simulator's inputs, the ports its rclcpp component and the `tactile` host share
  /// (tactile_common/ports.hpp): the three setpoint topics, best effort (Sub::kSensorData:
  /// a controller's reliable or best-effort setpoints both match). on_setpoint(stamp) is
  /// called with each setpoint's header stamp before it is applied (the component's
  /// setpoint latency; the host passes a no-op). The rest is each host's own: the
  /// outputs' topics are known only at each step (Outputs), and the component paces the
  /// world on a wall timer scaled by real_time_factor, publishes /clock, TF, the URDF and
  /// sim/done, while the host steps it on its executor.
  template <class Ports, class OnSetpoint>
  static void wire_setpoints(Ports& p, SimLogic& l, OnSetpoint on_setpoint) {
    using tactile_common::ports::Sub;
    p.template subscribe<tactile_msgs::msg::HoverSetpoint>(
        kHoverSetpointTopic, Sub::kSensorData, [&l, on_setpoint](const tactile_msgs::msg::HoverSetpoint& m) {
          on_setpoint(m.header.stamp);
          l.on_hover_setpoint(m);
        });
    p.template subscribe<geometry_msgs::msg::PoseStamped>(
        kPositionSetpointTopic, Sub::kSensorData, [&l, on_setpoint](const geometry_msgs::msg::PoseStamped& m) {
          on_setpoint(m.header.stamp);
          l.on_position_setpoint(m);
        });
    p.template subscribe<tactile_msgs::msg::ThrustCommand>(
        kRotorThrustTopic, Sub::kSensorData, [&l, on_setpoint](const tactile_msgs::msg::ThrustCommand& m) {
          on_setpoint(m.header.stamp);
          l.on_rotor_thrust(m);
        });
  }

  /// Called every period_ns() from now_ns = 0: advances the world to now_ns
  /// (the first call only samples the initial state) and appends the
  /// messages due at this instant, after fault injection.
  void step(int64_t now_ns, Outputs& out);

  /// The scenario duration has elapsed.
  bool finished(int64_t now_ns) const;

  const Arena& arena() const;
  const SimFrames& frames() const { return frames_; }
  /// The vehicle's links (tactile_sim/robot_model.hpp), from the parameters its physics uses.
  const tactile_common::RobotModel& robot_model() const { return robot_model_; }
  /// Static transforms of the frame tree (prefixed): map -> odom and map ->
  /// ground_truth/odom (identity: the simulated estimate starts at the world
  /// origin, and the world is the map), base_link -> every sensor/arm link.
  std::vector<tactile_common::StaticFrame> static_frames() const;
  /// The URDF of robot_model() (prefixed links), for robot_description.
  std::string robot_description() const;
  const Scenario& scenario() const { return scenario_; }
  uint64_t seed() const { return seed_; }
  const std::vector<TrajectoryPoint>& trajectory() const { return trajectory_; }
  const std::vector<CollisionEvent>& collisions() const { return collisions_; }
  /// Whisker contact points (world x, y) sampled at 50 Hz while in contact.
  const std::vector<Vec2>& whisker_contacts() const { return whisker_contacts_; }
  Summary summary() const;
  const FaultCounts& fault_counts() const { return fault_counts_; }
  /// Setpoints that arrived with non-finite values (dropped, counted).
  uint64_t dropped_setpoints() const { return dropped_setpoints_; }

  class Vehicle;  // per-vehicle model + sensors (sim_logic.cpp)

 private:
  template <class T>
  void emit(std::vector<Published<T>>& out, std::string_view topic, T msg, int64_t now_ns);

  Scenario scenario_;
  uint64_t seed_;
  SimFrames frames_;
  tactile_common::RobotModel robot_model_;
  std::unique_ptr<Arena> arena_;
  std::unique_ptr<Vehicle> vehicle_;
  int64_t period_ns_;
  double dt_;
  int64_t k_ = 0;
  bool started_ = false;
  std::vector<TrajectoryPoint> trajectory_;
  Outputs scratch_;  ///< step()'s sensor outputs before fault injection, reused (no allocation per step)
  std::vector<CollisionEvent> collisions_;
  std::vector<Vec2> whisker_contacts_;
  FaultCounts fault_counts_;
  uint64_t dropped_setpoints_ = 0;
  double max_external_force_ = 0.0;
  struct FaultSet;
  std::unique_ptr<FaultSet> faults_;
};

}  // namespace tactile_sim
