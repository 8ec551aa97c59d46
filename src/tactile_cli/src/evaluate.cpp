#include "tactile_cli/evaluate.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <array>
#include <map>
#include <optional>
#include <variant>
#include <random>
#include <stdexcept>
#include <vector>

#include "graphs/xplorer_area.hpp"
#include "graphs/xplorer_nodes.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/typed.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/sim_graph.hpp"
#include "tactile_cli/wall_effect_eval.hpp"
#include "tactile_cli/whisker_eval.hpp"
#include "tactile_common/geometry.hpp"
#include "tactile_common/time.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "wall_effect_ekf/wall_effect_ekf_logic.hpp"
#include "wall_effect_ekf/wall_trajectory.hpp"
#include "tactile_fsm/whisker_fsm_logic.hpp"
#include "tactile_msgs/msg/collision_event.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/whisker_ground_truth.hpp"
#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"
#include "tactile_sim/types.hpp"

namespace tactile_cli {

namespace {

namespace fs = std::filesystem;
using tactile_msgs::msg::CollisionEvent;
using tactile_msgs::msg::FsmState;
using tactile_msgs::msg::WhiskerGroundTruth;

constexpr uint64_t kStreamTrialYaw = 30;  // tactile_sim stream id of the trial's arena rotation (as sim_run.cpp)
constexpr const char* kCollisionsTopic = "collisions";
constexpr const char* kTruthTopics[2] = {"ground_truth/whisker/left/contact", "ground_truth/whisker/right/contact"};

/// The trial's random arena rotation, as `tactile sim` draws it from the seed.
double trial_arena_yaw(const tactile_sim::Scenario& s, uint64_t seed) {
  if (!s.randomize_arena_yaw) return 0.0;
  tactile_sim::Rng rng(tactile_sim::stream_seed(seed, kStreamTrialYaw));
  return std::uniform_real_distribution<double>(s.randomize_arena_yaw->first, s.randomize_arena_yaw->second)(rng);
}

/// The bag's topic of a node logic topic name (relative): the host records at the root
/// namespace (executor.hpp root_topic), as did the bags recorded before.
const tactile_bag::TopicInfo* find_topic(const tactile_bag::Reader& in, const std::string& name) {
  return in.find_topic(root_topic(name));
}

void require_topic(const tactile_bag::Reader& in, const std::string& bag, const std::string& name,
                   const std::string& type, const std::string& why) {
  const std::string topic = root_topic(name);
  const tactile_bag::TopicInfo* t = in.find_topic(topic);
  if (!t) throw std::runtime_error(bag + ": no topic " + topic + " (" + why + ")");
  if (t->type != type) throw std::runtime_error(bag + ": topic " + topic + " has type " + t->type + ", expected " + type);
}

/// Common top-level fields of metrics.json (the keys `tactile sim` writes
/// that a bag can give).
nlohmann::json header(const tactile_sim::Scenario& s, const EvaluateOptions& o, uint64_t seed, double arena_yaw,
                      const tactile_bag::Reader& in) {
  nlohmann::json m;
  m["scenario"] = s.name;
  m["scenario_file"] = s.source;
  m["vehicle"] = tactile_sim::to_string(s.vehicle);
  m["seed"] = seed;
  m["arena_yaw_deg"] = (s.arena_yaw + arena_yaw) * 180.0 / M_PI;
  m["graph"] = s.graph;
  m["source"] = "bag";
  m["bag"] = o.bag;
  m["bag_messages"] = in.message_count();
  m["physics_rate_hz"] = s.physics_rate_hz;
  return m;
}

void add_collisions(nlohmann::json& m, const std::vector<CollisionEvent>& collisions) {
  m["collisions"] = collisions.size();
  m["collision_events"] = nlohmann::json::array();
  for (const auto& c : collisions) {
    m["collision_events"].push_back({{"t", tactile_common::to_seconds(tactile_common::from_stamp(c.header.stamp))},
                                     {"part", c.part},
                                     {"x", c.point.x},
                                     {"y", c.point.y},
                                     {"impact_speed", c.impact_speed},
                                     {"obstacle_id", c.obstacle_id}});
  }
}

/// Replays a bag's messages onto the host's bus in timestamp order: each topic
/// registered with topic<T>() is decoded as T and published at its bag
/// timestamp; with run_executor, the host's timers due before each message run
/// first (as in flight). Counts the messages per topic.
class BagReplay {
 public:
  BagReplay(tactile_bag::Reader& in, Host& host, bool run_executor = false)
      : in_(in), host_(host), run_executor_(run_executor) {}

  template <class T>
  BagReplay& topic(const std::string& name) {
    decoders_[root_topic(name)] = [this](const tactile_bag::SerializedMessage& msg) {
      host_.bus().publish(msg.topic, tactile_bag::decode<T>(msg), msg.timestamp_ns);
    };
    return *this;
  }

  void run() {
    std::vector<std::string> topics;
    for (const auto& [name, decode] : decoders_) topics.push_back(name);
    in_.set_topic_filter(topics);
    tactile_bag::SerializedMessage msg;
    while (in_.read_next(msg)) {
      if (run_executor_) host_.executor().run_until(msg.timestamp_ns);
      last_ns_ = std::max(last_ns_, msg.timestamp_ns);
      ++counts_[msg.topic];
      decoders_.at(msg.topic)(msg);
    }
  }

  /// sim_time_s (the last message's time) and the "topics" counts of metrics.json.
  void write(nlohmann::json& m) const {
    m["sim_time_s"] = tactile_common::to_seconds(last_ns_);
    for (const auto& [topic, n] : counts_) m["topics"][topic] = n;
  }

 private:
  tactile_bag::Reader& in_;
  Host& host_;
  bool run_executor_;
  std::map<std::string, std::function<void(const tactile_bag::SerializedMessage&)>> decoders_;
  int64_t last_ns_ = 0;
  std::map<std::string, uint64_t> counts_;
};

/// Graph whisker_fsm (src/graphs/whisker_fsm.cpp): WallFollowingEvaluation
/// over the recorded truth and FSM states, the FSM's parameters as the graph
/// sets them (config/tactile_fsm.yaml <- scenario node_parameters <- target).
nlohmann::json evaluate_whisker_fsm(const tactile_sim::Scenario& s, const EvaluateOptions& o, uint64_t seed) {
  using Logic = tactile_fsm::WhiskerFsmLogic;
  tactile_bag::Reader in(o.bag);
  for (const char* t : kTruthTopics) {
    require_topic(in, o.bag, t, tactile_msgs::cdr::MessageTraits<WhiskerGroundTruth>::type_name,
                  "the whisker ground truth the wall-following evaluation compares with");
  }
  require_topic(in, o.bag, Logic::kStateTopic, tactile_msgs::cdr::MessageTraits<FsmState>::type_name,
                "the FSM states: wall-following episodes and the target");
  const bool have_collisions = find_topic(in, kCollisionsTopic) != nullptr;
  if (have_collisions) {
    require_topic(in, o.bag, kCollisionsTopic, tactile_msgs::cdr::MessageTraits<CollisionEvent>::type_name,
                  "collision events");
  }

  const double arena_yaw = trial_arena_yaw(s, seed);
  Host host(o.config_dir);
  WhiskerTruth truth(host);
  GraphContext ctx{s, host, nullptr, seed, arena_yaw, o.out_dir, &truth};
  tactile_common::ParamMap extra;
  if (auto t = ctx.target()) {
    extra.set("target_x", t->x());
    extra.set("target_y", t->y());
  }
  const auto params = Logic::params_from(
      host.load_parameters("", Logic::kNodeName, Logic::default_parameters(), ctx.overrides("whisker_fsm", extra)));
  const auto& fp = params.fsm;
  WallFollowingEvaluation eval(host, truth, fp.t_min, fp.t_max, fp.whisker_spacing);
  std::vector<CollisionEvent> collisions;
  host.bus().subscribe<CollisionEvent>(kCollisionsTopic, [&collisions](const CollisionEvent& c) { collisions.push_back(c); });

  BagReplay replay(in, host);
  replay.topic<WhiskerGroundTruth>(kTruthTopics[0]).topic<WhiskerGroundTruth>(kTruthTopics[1]);
  replay.topic<FsmState>(Logic::kStateTopic);
  if (have_collisions) replay.topic<CollisionEvent>(kCollisionsTopic);
  replay.run();

  nlohmann::json m = header(s, o, seed, arena_yaw, in);
  replay.write(m);
  add_collisions(m, collisions);
  nlohmann::json f = eval.metrics();
  f["target"] = {params.target_x, params.target_y};
  // 000 Methods: the FSM lands when the target is reached (as WhiskerFsmGraph::reached_goal).
  const std::string& last = eval.last_state();
  const bool reached = last == "LANDING" || last == "LANDED";
  f["reached_target"] = reached;
  m["fsm"] = f;
  m["success"] = reached && (ctx.flag("allow_collisions") || collisions.empty());
  return m;
}

/// Graph xplorer, mission explore (src/graphs/xplorer.cpp, 001 Sec. V-C/V-D):
/// loop closure from the recorded FSM states (the FSM enters "done" when it
/// closes the loop) and the contact map rebuilt by xplorer_mapping from the
/// recorded body wrench, odometry, arm IMUs and FSM states with the graph's
/// mapping parameters, measured as XplorerGraph::explore_metrics does.
nlohmann::json evaluate_xplorer(const tactile_sim::Scenario& s, const EvaluateOptions& o, uint64_t seed) {
  using MapLogic = mapping_pcl::XplorerMapLogic;
  using FsmLogic = tactile_fsm::XplorerFsmLogic;
  tactile_bag::Reader in(o.bag);
  const auto wrench_type = tactile_msgs::cdr::MessageTraits<geometry_msgs::msg::WrenchStamped>::type_name;
  require_topic(in, o.bag, MapLogic::kWrenchBodyTopic, wrench_type, "the body wrench the contact map is built from");
  require_topic(in, o.bag, MapLogic::kOdometryTopic, tactile_msgs::cdr::MessageTraits<nav_msgs::msg::Odometry>::type_name,
                "the pose the contact map is built in");
  require_topic(in, o.bag, FsmLogic::kStateTopic, tactile_msgs::cdr::MessageTraits<FsmState>::type_name,
                "the FSM states: loop closure");
  const bool have_arms = find_topic(in, MapLogic::kArmImuTopic) != nullptr;
  const bool have_collisions = find_topic(in, kCollisionsTopic) != nullptr;

  const double arena_yaw = trial_arena_yaw(s, seed);
  const tactile_sim::SimLogic world(s, seed, arena_yaw);  // the arena's floor, as the graph
  Host host(o.config_dir);
  GraphContext ctx{s, host, nullptr, seed, arena_yaw, o.out_dir, nullptr};
  const auto fsm_params = FsmLogic::params_from(host.load_parameters(
      "", FsmLogic::kNodeName, FsmLogic::default_parameters(), ctx.overrides("xplorer_fsm")));
  if (fsm_params.fsm.mission != tactile_fsm::XplorerMission::kExplore) {
    throw std::runtime_error(s.source + ": xplorer_fsm mission '" + tactile_fsm::to_string(fsm_params.fsm.mission) +
                             "': tactile evaluate knows the mission explore only");
  }
  const XplorerAreaGoal area_goal = XplorerAreaGoal::from(s);
  tactile_common::ParamMap map_extra;
  map_extra.set("floor_z", world.arena().floor_z());
  map_extra.set("publish_rate_hz", 0.1);
  host.executor().set_time(in.start_time_ns());
  auto map = add_xplorer_mapping(host, ctx.overrides("xplorer_mapping", map_extra));
  std::vector<std::pair<double, std::string>> states;
  host.bus().subscribe<FsmState>(FsmLogic::kStateTopic, [&states](const FsmState& m) {
    if (states.empty() || states.back().second != m.state)
      states.emplace_back(tactile_common::to_seconds(tactile_common::from_stamp(m.header.stamp)), m.state);
  });
  std::vector<CollisionEvent> collisions;
  host.bus().subscribe<CollisionEvent>(kCollisionsTopic, [&collisions](const CollisionEvent& c) { collisions.push_back(c); });

  BagReplay replay(in, host, /*run_executor=*/true);
  replay.topic<geometry_msgs::msg::WrenchStamped>(MapLogic::kWrenchBodyTopic);
  replay.topic<nav_msgs::msg::Odometry>(MapLogic::kOdometryTopic);
  replay.topic<FsmState>(FsmLogic::kStateTopic);
  if (have_arms) replay.topic<tactile_msgs::msg::ArmImuArray>(MapLogic::kArmImuTopic);
  if (have_collisions) replay.topic<CollisionEvent>(kCollisionsTopic);
  replay.run();

  nlohmann::json x;
  x["mission"] = "explore";
  x["final_state"] = states.empty() ? "" : states.back().second;
  double closure = -1.0;
  for (const auto& [t, state] : states) {
    if (state == "done") {
      closure = t;
      break;
    }
  }
  x["loop_closed"] = closure >= 0;
  x["loop_closure_time_s"] = closure >= 0 ? nlohmann::json(closure) : nlohmann::json(nullptr);
  add_turn_outcomes(states, x);  // as XplorerGraph::explore_metrics
  const auto& ms = map->mapper().stats();
  x["slabs"] = ms.slabs;
  x["map_raw_points"] = map->map().size();
  x["corner_slabs"] = ms.corner_slabs;
  const auto area = measure_map_area(map->map(), area_goal, object_hull_area(world.arena()), x);

  nlohmann::json m = header(s, o, seed, arena_yaw, in);
  replay.write(m);
  add_collisions(m, collisions);
  m["xplorer"] = x;
  // As XplorerGraph::reached_goal for explore without metrics.min_traversed_m:
  // the loop closed and, with metrics.min_area_accuracy, the map's area accuracy.
  if (s.metrics.count("min_traversed_m")) {
    throw std::runtime_error(s.source + ": metrics.min_traversed_m: the traversed path is the FSM's own; "
                                        "tactile evaluate judges explore flights by loop closure only");
  }
  const bool area_ok = !area_goal.min_accuracy || (area && *area >= *area_goal.min_accuracy);
  m["success"] = closure >= 0 && area_ok && (ctx.flag("allow_collisions") || collisions.empty());
  return m;
}

/// Graph wall_effect (src/graphs/wall_effect.cpp, 004 Fig. 4a): the EKF's
/// published estimate against /ground_truth/wall -- RMSE of distance and
/// direction within 20 cm of the wall over the scenario's window, NEES of
/// (distance, direction) with the published covariance -- and the tracking
/// errors of the motion-capture odometry against the setpoint script. These
/// are WallEffectGraph's accumulations over the same messages, in the same
/// order (test_evaluate.py checks that they equal the in-flight numbers); the
/// full-state NEES needs the EKF's internal state and is not in a bag.
nlohmann::json evaluate_wall_effect(const tactile_sim::Scenario& s, const EvaluateOptions& o, uint64_t seed) {
  using tactile_msgs::msg::WallEstimate;
  using Ekf = wall_effect_ekf::WallEffectEkfLogic;
  using Traj = wall_effect_ekf::WallTrajectoryLogic;
  constexpr const char* kTruthWall = WallEffectEvaluation::kTruthWallTopic;
  constexpr const char* kTruthOdom = WallEffectEvaluation::kTruthOdomTopic;
  tactile_bag::Reader in(o.bag);
  const auto wall_type = tactile_msgs::cdr::MessageTraits<WallEstimate>::type_name;
  const auto odom_type = tactile_msgs::cdr::MessageTraits<nav_msgs::msg::Odometry>::type_name;
  require_topic(in, o.bag, kTruthWall, wall_type, "the true wall distance and direction");
  require_topic(in, o.bag, Ekf::kOutputTopic, wall_type, "the EKF's estimate");
  require_topic(in, o.bag, kTruthOdom, odom_type, "the pose the tracking errors are taken of");
  require_topic(in, o.bag, Traj::kOutputTopic, odom_type, "the setpoint script");
  const bool have_collisions = find_topic(in, kCollisionsTopic) != nullptr;

  const double arena_yaw = trial_arena_yaw(s, seed);
  Host host(o.config_dir);
  GraphContext ctx{s, host, nullptr, seed, arena_yaw, o.out_dir, nullptr};
  const auto tp = Traj::params_from(
      host.load_parameters("", Traj::kNodeName, Traj::default_parameters(), ctx.overrides("wall_trajectory")));
  if (tp.mode == "sweep") {
    throw std::runtime_error(s.source + ": wall_trajectory mode 'sweep': tactile evaluate knows the modes "
                                        "estimation_flight and hold");
  }
  WallEffectEvaluation eval(tp);
  eval.subscribe(host.bus());
  std::vector<CollisionEvent> collisions;
  host.bus().subscribe<CollisionEvent>(kCollisionsTopic, [&collisions](const CollisionEvent& c) { collisions.push_back(c); });

  BagReplay replay(in, host);
  replay.topic<WallEstimate>(kTruthWall).topic<nav_msgs::msg::Odometry>(kTruthOdom);
  replay.topic<nav_msgs::msg::Odometry>(Traj::kOutputTopic).topic<WallEstimate>(Ekf::kOutputTopic);
  if (have_collisions) replay.topic<CollisionEvent>(kCollisionsTopic);
  replay.run();
  nlohmann::json w;
  eval.write(w);

  nlohmann::json m = header(s, o, seed, arena_yaw, in);
  replay.write(m);
  add_collisions(m, collisions);
  m["wall_effect"] = w;
  m["success"] = ctx.flag("allow_collisions") || collisions.empty();  // the graph has no goal
  return m;
}

}  // namespace

nlohmann::json run_evaluate(const EvaluateOptions& o) {
  const tactile_sim::Scenario scenario = tactile_sim::load_scenario(o.scenario);
  const uint64_t seed = o.seed.value_or(scenario.seed);
  if (!fs::is_directory(o.bag)) throw std::runtime_error(o.bag + ": not a rosbag2 directory");
  nlohmann::json m;
  if (scenario.graph == "whisker_fsm") {
    m = evaluate_whisker_fsm(scenario, o, seed);
  } else if (scenario.graph == "xplorer") {
    m = evaluate_xplorer(scenario, o, seed);
  } else if (scenario.graph == "wall_effect") {
    m = evaluate_wall_effect(scenario, o, seed);
  } else {
    throw std::runtime_error(scenario.source + ": graph: '" + scenario.graph +
                             "': tactile evaluate knows the graphs whisker_fsm, xplorer (explore) and "
                             "wall_effect (estimation_flight, hold)");
  }
  fs::create_directories(o.out_dir);
  const fs::path path = fs::path(o.out_dir) / "metrics.json";
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << m.dump(2) << "\n";
  if (!out) throw std::runtime_error(path.string() + ": write failed");
  return m;
}

}  // namespace tactile_cli
