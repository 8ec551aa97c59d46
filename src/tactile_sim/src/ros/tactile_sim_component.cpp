// rclcpp component of the simulator: a mechanical adapter around SimLogic
// (all behaviour lives there). ROS builds only. The world runs on simulated
// time from 0, stepped by a wall timer and published on /clock, so the other
// nodes run with use_sim_time:=true.
//
// Parameters besides SimLogic's (scenario, seed, frame_prefix), declared with them from
// SimLogic::component_parameters() (descriptions, range) and read at start:
//   real_time_factor (double, default 1.0): the timer period is the physics
//     period divided by it. 1.0 flies in real time (what an operator at a
//     ground station expects); CI flies faster. If the container cannot keep
//     up, simulated time simply advances slower (every physics step is still
//     taken); the achieved factor is logged at the end.
//   wait_for_publisher (string, default ""): when set, the world stays at
//     t = 0 (nothing published) until some node publishes on this topic, e.g.
//     the graph's setpoint topic: a launch file loads the simulator first and
//     the controller last, and the standalone host starts them together.
//   wait_for_subscribers (string, default ""): comma-separated topics of the
//     simulator's; when set, the world takes its first step (t = 0, which
//     creates the publishers) and holds its messages until each of these
//     topics has a subscription outside this process matched by the
//     simulator's publisher, e.g. a recorder's. Publishers are created on their
//     first message, and a DDS subscriber only receives from a writer once
//     discovery has matched them: without the wait, a recorder in another
//     process missed the first seconds of a flight on a loaded machine.
//
// Frames (tactile_common/frames.hpp, README "Frames"): where tf2_ros is found
// (tactile_component_tf) the simulator broadcasts /tf_static once (map -> odom and
// map -> ground_truth/odom identity, base_link -> the vehicle's sensor, whisker,
// arm and rotor links from SimLogic::static_frames()) and, with every odometry
// message it publishes, the transform of that message: odom -> base_link (/odom,
// the estimate) and ground_truth/odom -> ground_truth/base_link (/ground_truth/odom).
// A dropped or delayed /odom (fault injection) drops or delays its transform too.
// Every frame is behind the frame_prefix parameter. It publishes the vehicle's
// URDF (SimLogic::robot_description(), the same links) on robot_description as
// std_msgs/String, reliable and transient local (latched_publisher: RViz's
// RobotModel display and a late subscriber get it).
//
// Where the toolchain has visualization_msgs (TACTILE_SIM_HAVE_VISUALIZATION_MSGS), the
// arena of the run (with the scenario's transform and the trial's randomised yaw) is
// published once on sim/arena as visualization_msgs/MarkerArray in frame map
// (arena_markers(), logic/arena_markers.hpp), latched like robot_description.
//
// At the scenario's end (duration_s) the simulator stops stepping and
// publishing, logs one line "tactile_sim: scenario ... ended" with the
// achieved real-time factor and the setpoint latency, and publishes
// std_msgs/Bool true on sim/done (relative, as every topic of the simulator's;
// reliable, transient local: a subscriber
// that joins later still gets it).
//
// /clock of a step's time t is published one timer period after the step's
// messages, at the start of the next step, so a node timer due at t (the
// controllers' 50/100 Hz ticks) runs after the messages of t have gone through
// the pipeline, as in process, where the world steps first and then node timers
// due at the same instant run (ties go to the timer created first, the
// simulator's). Publishing /clock(t) before the messages of t let, e.g., the
// whisker FSM's tick at t act on the depth of t - 20 ms: the component
// container's executor runs ready timers before ready subscriptions, and the
// FSM's clock (its own /clock subscription) reached t while the pressure of t
// was still queued for TDORC. The price: a setpoint stamped t reaches the world
// at t + 2 steps instead of t + 1 (the "late" count below: 2-3 ms ages).
//
// Setpoint latency: the age of each setpoint (/cmd_hover, /cmd_position,
// /cmd_rotor_thrust) when it reaches the simulator, in simulated time (the
// simulator's clock minus the setpoint's header stamp). The standalone host
// applies a setpoint at most one physics step after its stamp; over DDS
// (separate executors, /clock delivered per node) it can be older. A setpoint
// older than two physics steps is counted as late.
#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rclcpp/rclcpp.hpp"
#include "rclcpp_components/register_node_macro.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "std_msgs/msg/bool.hpp"
#include "std_msgs/msg/string.hpp"
#include "tactile_common/ros_parameters.hpp"
#include "tactile_common/ros_ports.hpp"
#include "tactile_common/ros_qos.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#ifdef TACTILE_SIM_HAVE_VISUALIZATION_MSGS
#include "tactile_sim/logic/arena_markers.hpp"
#endif
#ifdef TACTILE_HAVE_TF2
#include "tactile_common/ros_tf.hpp"
#endif

namespace tactile_sim {

class TactileSimComponent : public rclcpp::Node {
 public:
  static constexpr const char * kDoneTopic = "sim/done";
  static constexpr const char * kRobotDescriptionTopic = "robot_description";
  static constexpr const char * kArenaTopic = "sim/arena";

  explicit TactileSimComponent(const rclcpp::NodeOptions & options)
  : Node(SimLogic::kNodeName, options),
    // The simulation's keys and the component's own (real_time_factor, wait_for_*): read
    // at start, read-only, so `ros2 param set` refuses them.
    parameters_(*this, {SimLogic::default_parameters(), SimLogic::component_parameters()}),
    logic_(SimLogic::from_parameters(parameters_.values()))
  {
    const SimLogic::ComponentParams host = SimLogic::component_params_from(parameters_.values());
    real_time_factor_ = host.real_time_factor;
    wait_for_publisher_ = host.wait_for_publisher;
    const std::string & subscribers = host.wait_for_subscribers;
    for (size_t begin = 0; begin < subscribers.size(); ) {
      size_t end = subscribers.find(',', begin);
      if (end == std::string::npos) {end = subscribers.size();}
      std::string topic = subscribers.substr(begin, end - begin);
      topic.erase(0, topic.find_first_not_of(' '));
      topic.erase(topic.find_last_not_of(' ') + 1);
      // Resolved like the publishers' names: a relative topic is the one in this node's
      // namespace (cf1/odom under /cf1).
      if (!topic.empty()) {
        wait_for_subscribers_.push_back(get_node_topics_interface()->resolve_topic_name(topic));
      }
      begin = end + 1;
    }
    // /clock is absolute (rclcpp's time source subscribes /clock); the launch files remap it
    // into the vehicle's namespace, with every node's, where two simulators share a domain.
    clock_publisher_ = create_publisher<rosgraph_msgs::msg::Clock>("/clock", rclcpp::ClockQoS());
    // Latched (transient local), so a subscriber that joins later still gets it; never
    // intra-process (tactile_common/ros_qos.hpp: Humble refuses the combination).
    done_publisher_ = tactile_common::latched_publisher<std_msgs::msg::Bool>(*this, kDoneTopic);
    description_publisher_ =
      tactile_common::latched_publisher<std_msgs::msg::String>(*this, kRobotDescriptionTopic);
    std_msgs::msg::String description;
    description.data = logic_->robot_description();
    description_publisher_->publish(description);
#ifdef TACTILE_SIM_HAVE_VISUALIZATION_MSGS
    arena_publisher_ =
      tactile_common::latched_publisher<visualization_msgs::msg::MarkerArray>(*this, kArenaTopic);
    arena_publisher_->publish(arena_markers(logic_->arena(), "map"));  // map: never prefixed
#endif
#ifdef TACTILE_HAVE_TF2
    static_broadcaster_ = tactile_common::static_broadcaster(*this);
    static_broadcaster_->sendTransform(
      tactile_common::static_transforms(logic_->static_frames(), builtin_interfaces::msg::Time()));
    broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>(*this);
#else
    RCLCPP_WARN(get_logger(), "tactile_sim: built without tf2_ros: no /tf, /tf_static");
#endif
    // The setpoint inputs, wired as in the standalone host (SimLogic::wire_setpoints): best
    // effort, which matches reliable and best-effort publishers alike (a controller's
    // setpoints with a qos_overrides reliability of best_effort too).
    SimLogic::wire_setpoints(
      ports_, *logic_, [this](const builtin_interfaces::msg::Time & stamp) {count_setpoint(stamp);});
    const auto period = std::max<int64_t>(
      1, static_cast<int64_t>(static_cast<double>(logic_->period_ns()) / real_time_factor_));
    timer_ = create_wall_timer(std::chrono::nanoseconds(period), [this]() {tick();});
    RCLCPP_INFO(
      get_logger(), "tactile_sim: scenario %s, seed %llu, %.1f s at %.2fx real time",
      logic_->scenario().name.c_str(), static_cast<unsigned long long>(logic_->seed()),
      logic_->scenario().duration_s, real_time_factor_);
  }

 private:
  template<class T>
  void publish(const std::vector<Published<T>> & messages)
  {
    auto & publishers = std::get<Publishers<T>>(publishers_);
    for (const auto & m : messages) {
      auto it = publishers.find(m.topic);
      if (it == publishers.end()) {
        // A topic's first message (a collision, a later sensor): its publisher now. Not
        // after shutdown began (Ctrl-C between the context's shutdown and the executor's
        // last timer): creating one then throws, and the container aborted without the
        // other nodes' shutdown work (the XPLORER map's PLY).
        if (!rclcpp::ok(get_node_base_interface()->get_context())) {
          return;
        }
        const std::string topic(m.topic);
        it = publishers.emplace(topic, tactile_common::data_publisher<T>(*this, topic)).first;
      }
      it->second->publish(m.msg);
    }
  }

  template<class T>
  void create_publishers(const std::vector<Published<T>> & messages)
  {
    auto & publishers = std::get<Publishers<T>>(publishers_);
    for (const auto & m : messages) {
      const std::string topic(m.topic);
      if (publishers.find(topic) == publishers.end()) {
        publishers.emplace(topic, tactile_common::data_publisher<T>(*this, topic));
      }
      publisher_bases_[publishers.at(topic)->get_topic_name()] = publishers.at(topic);
    }
  }

  void create_publishers()
  {
    create_publishers(outputs_.pressure);
    create_publishers(outputs_.whisker_truth);
    create_publishers(outputs_.odometry);
    create_publishers(outputs_.imu);
    create_publishers(outputs_.range);
    create_publishers(outputs_.flow);
    create_publishers(outputs_.arm_imu);
    create_publishers(outputs_.thrust);
    create_publishers(outputs_.wrench);
    create_publishers(outputs_.wall);
    create_publishers(outputs_.collisions);
  }

  /// Every wait_for_subscribers topic has a subscription in another process
  /// matched by our publisher (rclcpp's own test for an inter-process publish).
  bool subscribers_matched()
  {
    while (!wait_for_subscribers_.empty()) {
      const std::string & topic = wait_for_subscribers_.front();
      auto it = publisher_bases_.find(topic);
      if (it == publisher_bases_.end()) {
        std::string published;
        for (const auto & [t, p] : publisher_bases_) {published += (published.empty() ? "" : ", ") + t;}
        throw std::invalid_argument(
          tactile_common::parameter_source(*this) + ": wait_for_subscribers: the simulator publishes no " +
          topic + " at t = 0 in scenario " + logic_->scenario().name + " (it publishes " + published + ")");
      }
      if (it->second->get_subscription_count() <= it->second->get_intra_process_subscription_count()) {
        if (!waiting_subscribers_logged_) {
          RCLCPP_INFO(get_logger(), "tactile_sim: waiting for a subscriber of %s in another process",
            topic.c_str());
          waiting_subscribers_logged_ = true;
        }
        return false;
      }
      RCLCPP_INFO(get_logger(), "tactile_sim: %s has a subscriber in another process", topic.c_str());
      waiting_subscribers_logged_ = false;
      wait_for_subscribers_.erase(wait_for_subscribers_.begin());
    }
    return true;
  }

  void count_setpoint(const builtin_interfaces::msg::Time & stamp)
  {
    // now_ns_ is the time of the next step: the setpoint is applied there.
    const int64_t age = now_ns_ - tactile_common::from_stamp(stamp);
    ++setpoints_;
    age_sum_ns_ += static_cast<double>(age);
    max_age_ns_ = std::max(max_age_ns_, age);
    if (age > 2 * logic_->period_ns()) {++late_setpoints_;}
  }

  void tick()
  {
    if (done_ || !rclcpp::ok(get_node_base_interface()->get_context())) {
      return;  // finished, or shutting down (nothing is published any more)
    }
    if (logic_->finished(now_ns_)) {
      finish();
      return;
    }
    if (now_ns_ == 0) {
      if (!wait_for_publisher_.empty()) {
        if (count_publishers(wait_for_publisher_) == 0) {
          if (!waiting_logged_) {
            RCLCPP_INFO(get_logger(), "tactile_sim: waiting for a publisher on %s",
              wait_for_publisher_.c_str());
            waiting_logged_ = true;
          }
          return;
        }
        RCLCPP_INFO(get_logger(), "tactile_sim: %s has a publisher, starting",
          wait_for_publisher_.c_str());
        wait_for_publisher_.clear();
      }
      if (!held_) {
        outputs_.clear();
        logic_->step(now_ns_, outputs_);
        held_ = true;
        create_publishers();
      }
      if (!subscribers_matched()) {
        return;
      }
      wall_start_ = std::chrono::steady_clock::now();
    } else {
      // /clock of the previous step, whose messages went out one timer period ago.
      publish_clock(now_ns_ - logic_->period_ns());
      outputs_.clear();
      logic_->step(now_ns_, outputs_);
    }
    publish(outputs_.pressure);
    publish(outputs_.whisker_truth);
    publish(outputs_.odometry);
#ifdef TACTILE_HAVE_TF2
    if (!outputs_.odometry.empty()) {
      transforms_.clear();
      for (const auto & m : outputs_.odometry) {transforms_.push_back(tactile_common::odometry_transform(m.msg));}
      broadcaster_->sendTransform(transforms_);
    }
#endif
    publish(outputs_.imu);
    publish(outputs_.range);
    publish(outputs_.flow);
    publish(outputs_.arm_imu);
    publish(outputs_.thrust);
    publish(outputs_.wrench);
    publish(outputs_.wall);
    publish(outputs_.collisions);
    now_ns_ += logic_->period_ns();
  }

  void publish_clock(int64_t t_ns)
  {
    rosgraph_msgs::msg::Clock clock;
    tactile_common::to_stamp(t_ns, clock.clock);
    clock_publisher_->publish(clock);
  }

  void finish()
  {
    if (now_ns_ > 0) {publish_clock(now_ns_ - logic_->period_ns());}
    done_ = true;
    timer_->cancel();
    const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
    const double sim_s = tactile_common::to_seconds(now_ns_);
    RCLCPP_INFO(
      get_logger(),
      "tactile_sim: scenario %s ended: %.3f s simulated in %.2f s wall (%.2fx real time, "
      "%.2fx requested), %zu collisions; setpoints %llu, late %llu (older than 2 physics "
      "steps), mean age %.2f ms, max age %.2f ms",
      logic_->scenario().name.c_str(), sim_s, wall_s, wall_s > 0 ? sim_s / wall_s : 0.0,
      real_time_factor_, logic_->collisions().size(), static_cast<unsigned long long>(setpoints_),
      static_cast<unsigned long long>(late_setpoints_),
      setpoints_ ? age_sum_ns_ / static_cast<double>(setpoints_) * 1e-6 : 0.0,
      static_cast<double>(max_age_ns_) * 1e-6);
    std_msgs::msg::Bool done;
    done.data = true;
    done_publisher_->publish(done);
  }

  template<class T>
  using Publishers = std::map<std::string, typename rclcpp::Publisher<T>::SharedPtr, std::less<>>;

  /// Declared before logic_: its values configure it; its on-set callback applies or refuses `ros2 param set`.
  tactile_common::NodeParameters parameters_;
  std::unique_ptr<SimLogic> logic_;
  SimLogic::Outputs outputs_;
  int64_t now_ns_ = 0;
  double real_time_factor_ = 1.0;
  bool done_ = false;
  std::string wait_for_publisher_;
  bool waiting_logged_ = false;
  std::vector<std::string> wait_for_subscribers_;
  bool waiting_subscribers_logged_ = false;
  bool held_ = false;  // the t = 0 step was taken, its messages not yet published
  std::map<std::string, rclcpp::PublisherBase::SharedPtr> publisher_bases_;
  std::chrono::steady_clock::time_point wall_start_ = std::chrono::steady_clock::now();
  uint64_t setpoints_ = 0;
  uint64_t late_setpoints_ = 0;
  double age_sum_ns_ = 0.0;
  int64_t max_age_ns_ = 0;
  std::tuple<
    Publishers<tactile_msgs::msg::WhiskerPressure>, Publishers<tactile_msgs::msg::WhiskerGroundTruth>,
    Publishers<nav_msgs::msg::Odometry>, Publishers<sensor_msgs::msg::Imu>,
    Publishers<sensor_msgs::msg::Range>, Publishers<tactile_msgs::msg::OpticalFlow>,
    Publishers<tactile_msgs::msg::ArmImuArray>, Publishers<tactile_msgs::msg::ThrustCommand>,
    Publishers<geometry_msgs::msg::WrenchStamped>, Publishers<tactile_msgs::msg::WallEstimate>,
    Publishers<tactile_msgs::msg::CollisionEvent>> publishers_;
  rclcpp::Publisher<rosgraph_msgs::msg::Clock>::SharedPtr clock_publisher_;
  rclcpp::Publisher<std_msgs::msg::Bool>::SharedPtr done_publisher_;
  rclcpp::Publisher<std_msgs::msg::String>::SharedPtr description_publisher_;
#ifdef TACTILE_SIM_HAVE_VISUALIZATION_MSGS
  rclcpp::Publisher<visualization_msgs::msg::MarkerArray>::SharedPtr arena_publisher_;
#endif
#ifdef TACTILE_HAVE_TF2
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> broadcaster_;
  std::vector<geometry_msgs::msg::TransformStamped> transforms_;
#endif
  rclcpp::TimerBase::SharedPtr timer_;
  /// The setpoint subscriptions (SimLogic::wire_setpoints). Declared after logic_: they go
  /// first, no callback outlives the logic.
  tactile_common::RosPorts<> ports_{*this};
};

}  // namespace tactile_sim

RCLCPP_COMPONENTS_REGISTER_NODE(tactile_sim::TactileSimComponent)
