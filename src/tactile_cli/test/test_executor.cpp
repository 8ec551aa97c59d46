#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <regex>
#include <string>
#include <unistd.h>
#include <vector>

#include "std_msgs/msg/header.hpp"
#include "std_msgs/msg/float64.hpp"
#include "tactile_cli/executor.hpp"
#include "tactile_cli/host.hpp"
#include "crazyflie_bridge/crazyflie_bridge_logic.hpp"
#include "mapping_pcl/xplorer_map_logic.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/time.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"
#include "xplorer_force_est/xplorer_force_est_logic.hpp"

using tactile_cli::Bus;
using tactile_cli::Executor;
using tactile_cli::resolve_topic;

TEST(ResolveTopic, LikeRclcpp) {
  EXPECT_EQ(resolve_topic("whisker/left", "pressure"), "/whisker/left/pressure");
  EXPECT_EQ(resolve_topic("/whisker/left/", "pressure"), "/whisker/left/pressure");
  EXPECT_EQ(resolve_topic("", "pressure"), "/pressure");
  EXPECT_EQ(resolve_topic("whisker/left", "/abs"), "/abs");
}

TEST(Executor, TimersFireInDueOrderTiesByCreation) {
  Executor ex;
  std::vector<std::string> log;
  ex.add_timer(20, [&](int64_t t) { log.push_back("a" + std::to_string(t)); });
  ex.add_timer(30, [&](int64_t t) { log.push_back("b" + std::to_string(t)); });
  ex.add_timer(60, [&](int64_t t) { log.push_back("c" + std::to_string(t)); }, 10);
  ex.run_until(60);
  const std::vector<std::string> want = {"a0", "b0", "c10", "a20", "b30", "a40", "a60", "b60"};
  EXPECT_EQ(log, want);
  EXPECT_EQ(ex.now_ns(), 60);
}

TEST(Executor, StopEndsRunAndRejectsBadPeriod) {
  Executor ex;
  int n = 0;
  ex.add_timer(10, [&](int64_t) {
    if (++n == 3) ex.stop();
  });
  ex.run_until(1000);
  EXPECT_EQ(n, 3);
  EXPECT_EQ(ex.now_ns(), 20);
  EXPECT_THROW(ex.add_timer(0, [](int64_t) {}), std::invalid_argument);
}

TEST(Executor, StartsAtSetTime) {
  Executor ex;
  ex.set_time(5000);
  std::vector<int64_t> at;
  ex.add_timer(100, [&](int64_t t) { at.push_back(t); }, ex.now_ns());
  ex.run_until(5250);
  EXPECT_EQ(at, (std::vector<int64_t>{5000, 5100, 5200}));
}

namespace {
struct CountingTap : tactile_cli::BusTap {
  std::vector<std::string> seen;
  std::vector<uint8_t> buffer{9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9};
  void on_message(const tactile_cli::TapTopic& topic, int64_t t,
                  const std::function<void(std::vector<uint8_t>&)>& ser) override {
    ser(buffer);  // replaces the old contents
    seen.push_back(topic.name + " " + topic.type_name + " " + std::to_string(t) + " " +
                   std::to_string(buffer.size()));
    EXPECT_FALSE(topic.definition.empty());
  }
};
}  // namespace

TEST(Bus, DeliversInSubscriptionOrderAndTapsSerialize) {
  Bus bus;
  CountingTap tap;
  bus.add_tap(&tap);
  std::vector<std::string> order;
  bus.subscribe<std_msgs::msg::Float64>("/x", [&](const std_msgs::msg::Float64& m) {
    order.push_back("first " + std::to_string(m.data));
  });
  bus.subscribe<std_msgs::msg::Float64>("/x", [&](const std_msgs::msg::Float64&) { order.push_back("second"); });
  std_msgs::msg::Float64 m;
  m.data = 2.0;
  bus.publish("/x", m, 7);
  ASSERT_EQ(order.size(), 2u);
  EXPECT_EQ(order[0].rfind("first 2.0", 0), 0u);
  EXPECT_EQ(order[1], "second");
  // 4-byte encapsulation header + 8-byte double.
  ASSERT_EQ(tap.seen.size(), 1u);
  EXPECT_EQ(tap.seen[0], "/x std_msgs/msg/Float64 7 12");
  // The tap's buffer held 20 stale bytes: serialize_into replaces them, bytes as serialize().
  EXPECT_EQ(tap.buffer, tactile_msgs::cdr::serialize(m));
  EXPECT_EQ(bus.published_counts().at("/x"), 1u);
}

// The node logic's topic names are relative (a ROS namespace moves them); the host runs one
// vehicle at the root, where a relative name and its absolute one are the same topic, and
// bags (old and new) carry the absolute name: a node subscribed to "odom" gets the "/odom"
// a bag replays, and the recorder names what "odom" publishes "/odom".
TEST(Bus, RelativeNamesResolveAtTheRoot) {
  Bus bus;
  CountingTap tap;
  bus.add_tap(&tap);
  int relative = 0;
  int absolute = 0;
  bus.subscribe<std_msgs::msg::Float64>("odom", [&](const std_msgs::msg::Float64&) { ++relative; });
  bus.subscribe<std_msgs::msg::Float64>("/odom", [&](const std_msgs::msg::Float64&) { ++absolute; });
  bus.publish("/odom", std_msgs::msg::Float64{}, 1);  // as a replayed bag
  bus.publish("odom", std_msgs::msg::Float64{}, 2);   // as the node logic
  EXPECT_EQ(relative, 2);
  EXPECT_EQ(absolute, 2);
  ASSERT_EQ(tap.seen.size(), 2u);
  EXPECT_EQ(tap.seen[1], "/odom std_msgs/msg/Float64 2 12");
  EXPECT_EQ(bus.published_counts(), (std::map<std::string, uint64_t>{{"/odom", 2}}));
  EXPECT_EQ(tactile_cli::root_topic("whisker/left/pressure"), "/whisker/left/pressure");
  EXPECT_EQ(tactile_cli::root_topic("/odom"), "/odom");
  // One topic, one type, whichever spelling comes second.
  EXPECT_THROW(bus.subscribe<std_msgs::msg::Header>("/odom", [](const std_msgs::msg::Header&) {}),
               std::logic_error);
}

TEST(Bus, OneTopicOneType) {
  Bus bus;
  bus.subscribe<std_msgs::msg::Float64>("/x", [](const std_msgs::msg::Float64&) {});
  EXPECT_THROW(bus.publish("/x", std_msgs::msg::Header{}, 0), std::logic_error);
}

// The standalone host reads each node's parameters from the file the launch files give
// that node: a launch file's ComposableNode(name='N', parameters=...config('F')...) must
// have parameter_file_name(N) == F.yaml for every node of every launch file. (The whisker
// FSM's file is named after its package; the host looked for whisker_fsm.yaml and ran the
// FSM on its code defaults whatever config/tactile_fsm.yaml said.)
TEST(Host, ParameterFilesAreTheLaunchFilesOnes) {
  namespace fs = std::filesystem;
  const fs::path launch_dir = fs::path(TACTILE_CONFIG_DIR) / ".." / "launch";
  const std::regex node(R"(name='([a-z_]+)',\s*\n?[^)]*?config\('([a-z_]+)'\))");
  int pairs = 0;
  for (const auto& entry : fs::directory_iterator(launch_dir)) {
    if (entry.path().extension() != ".py") continue;
    std::ifstream in(entry.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::sregex_iterator it(text.begin(), text.end(), node), end; it != end; ++it) {
      EXPECT_EQ(tactile_cli::parameter_file_name((*it)[1]), std::string((*it)[2]) + ".yaml")
          << entry.path().filename() << ": node " << (*it)[1];
      ++pairs;
    }
  }
  EXPECT_GE(pairs, 10);  // the regex still finds the launch files' nodes
  EXPECT_EQ(tactile_cli::parameter_file_name("whisker_fsm"), "tactile_fsm.yaml");
}

TEST(Host, LoadsTheWhiskerFsmFromTactileFsmYaml) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tactile_host_cfg_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "tactile_fsm.yaml") << "/**/whisker_fsm:\n  ros__parameters:\n    v_max: 0.123\n";
  tactile_cli::Host host(dir.string());
  tactile_common::ParamMap defaults("whisker_fsm", "defaults");
  defaults.set("v_max", 0.2);
  const auto p = host.load_parameters("", "whisker_fsm", defaults, tactile_common::ParamMap("", "none"));
  EXPECT_DOUBLE_EQ(p.get_double("v_max"), 0.123);
  fs::remove_all(dir);
}

// Parameter profiles (config/profiles/): between the node's file and the overrides; the
// graph's own profile before the user's, so the user's wins.
TEST(Host, ProfilesApplyBetweenTheFileAndTheOverridesTheUsersLast) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("host_profiles_" + std::to_string(::getpid()));
  fs::create_directories(dir / "profiles");
  std::ofstream(dir / "tactile_fsm.yaml") << "/**/whisker_fsm:\n  ros__parameters:\n    v_max: 0.123\n    t_min: 0.06\n";
  std::ofstream(dir / "profiles" / "graph.yaml") << "/**/whisker_fsm:\n  ros__parameters: {v_max: 0.3, t_min: 0.05}\n";
  std::ofstream(dir / "profiles" / "user.yaml") << "/**/whisker_fsm:\n  ros__parameters: {v_max: 0.25}\n";
  tactile_common::ParamMap defaults("whisker_fsm", "defaults");
  defaults.set("v_max", 0.2);
  defaults.set("t_min", 0.07);
  tactile_cli::Host host(dir.string());
  host.use_profile("user");
  host.use_profile("graph", /*graph_default=*/true);  // as gpis_explore does, after the user's was given
  ASSERT_EQ(host.profiles().size(), 2u);
  EXPECT_EQ(fs::path(host.profiles()[0]).filename(), "graph.yaml");
  auto p = host.load_parameters("", "whisker_fsm", defaults, tactile_common::ParamMap("", "none"));
  EXPECT_DOUBLE_EQ(p.get_double("v_max"), 0.25);  // the user's profile wins
  EXPECT_DOUBLE_EQ(p.get_double("t_min"), 0.05);  // the graph's profile over the file
  EXPECT_EQ(fs::path(p.origin("t_min")).filename(), "graph.yaml");
  tactile_common::ParamMap over("whisker_fsm", "overrides");
  over.set("v_max", 0.1);
  p = host.load_parameters("", "whisker_fsm", defaults, over);
  EXPECT_DOUBLE_EQ(p.get_double("v_max"), 0.1);  // overrides (a scenario's node_parameters) last
  try {
    host.use_profile("papr");
    ADD_FAILURE() << "a missing profile accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("papr.yaml: no such parameter profile"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// The shipped exploration profile reaches the TDORC filters of the gpis_explore graph.
TEST(Host, TheExplorationProfileSetsTheProbingRelease) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  const auto without = host.load_parameters("whisker/left", tdorc_filter::TdorcFilterLogic::kNodeName,
                                            tdorc_filter::TdorcFilterLogic::default_parameters(),
                                            tactile_common::ParamMap("", "none"));
  host.use_profile("exploration", true);
  const auto with = host.load_parameters("whisker/left", tdorc_filter::TdorcFilterLogic::kNodeName,
                                         tdorc_filter::TdorcFilterLogic::default_parameters(),
                                         tactile_common::ParamMap("", "none"));
  EXPECT_DOUBLE_EQ(without.get_double("hold_release_fraction"), 0.1);
  EXPECT_DOUBLE_EQ(with.get_double("hold_release_fraction"), 0.25);
}

// Issue 32: the host loads every node from its file and has no file-less
// default (a missing, empty, directory or misnamed file is an error). So every
// node logic the `tactile` commands run must find its file in the repository's
// config/ with a section naming it, and its values must validate.
namespace {
template <class Logic>
void expect_repository_file(const tactile_cli::Host& host, const std::string& ns) {
  SCOPED_TRACE(Logic::kNodeName);
  EXPECT_NO_THROW(Logic::params_from(host.load_parameters(ns, Logic::kNodeName, Logic::default_parameters(),
                                                          tactile_common::ParamMap("", "none"))));
}
}  // namespace

TEST(Host, EveryHostedNodeHasItsParameterFile) {
  const tactile_cli::Host host(TACTILE_CONFIG_DIR);
  expect_repository_file<whisker_driver::WhiskerDriverLogic>(host, "whisker/left");
  expect_repository_file<whisker_driver::WhiskerDriverLogic>(host, "whisker/right");
  expect_repository_file<tdorc_filter::TdorcFilterLogic>(host, "whisker/left");
  expect_repository_file<tactile_depth::TactileDepthLogic>(host, "");
  expect_repository_file<tactile_fsm::WhiskerFsmLogic>(host, "");
  expect_repository_file<gpis_explorer::GpisExplorerLogic>(host, "");
  expect_repository_file<whisker_localization::WhiskerLocalizationLogic>(host, "");
  expect_repository_file<tactile_fsm::WallEffectNavLogic>(host, "");
  expect_repository_file<wall_effect_ekf::WallEffectEkfLogic>(host, "");
  expect_repository_file<wall_effect_ekf::IndiControlLogic>(host, "");
  expect_repository_file<wall_effect_ekf::WallTrajectoryLogic>(host, "");
  expect_repository_file<xplorer_force_est::XplorerForceEstLogic>(host, "");
  expect_repository_file<tactile_fsm::XplorerFsmLogic>(host, "");
  expect_repository_file<mapping_pcl::XplorerMapLogic>(host, "");
  expect_repository_file<crazyflie_bridge::CrazyflieBridgeLogic>(host, "");
}

// add_whisker_fsm with a real-time clock (tactile fly): the FSM steps when a depth
// arrives, at the arrival clock's time, and its 50 Hz timer only steps it when depth
// stops (tactile_common/event_tick.hpp). Without the clock (the simulated hosts) the
// timer steps it every 20 ms and a depth arrival publishes nothing by itself.
TEST(HostWhiskerFsm, StepsOnDepthArrivalWithARealTimeClockAndOnItsTimerWithout) {
  using Logic = tactile_fsm::WhiskerFsmLogic;
  constexpr int64_t kMs = 1'000'000;
  for (const bool real_time : {true, false}) {
    SCOPED_TRACE(real_time ? "arrival clock" : "simulated host");
    tactile_cli::Host host(TACTILE_CONFIG_DIR);
    int64_t clock_ns = 0;
    std::function<int64_t()> arrival;
    if (real_time) arrival = [&clock_ns] { return clock_ns; };
    tactile_cli::add_whisker_fsm(host, tactile_common::ParamMap(), arrival);
    std::vector<int64_t> setpoints;  // stamps
    host.bus().subscribe<tactile_msgs::msg::HoverSetpoint>(Logic::kSetpointTopic, [&](const auto& m) {
      setpoints.push_back(static_cast<int64_t>(m.header.stamp.sec) * 1'000'000'000 + m.header.stamp.nanosec);
    });
    host.executor().run_until(0);  // the timer's first call, at 0
    ASSERT_EQ(setpoints.size(), 1u);
    // Depth at 50 Hz, 7 ms after the timer's phase, for 0.2 s.
    for (int k = 0; k < 10; ++k) {
      clock_ns = k * 20 * kMs + 7 * kMs;
      host.executor().run_until(clock_ns);
      const size_t n = setpoints.size();
      tactile_msgs::msg::TactileDepth d;
      tactile_common::to_stamp(clock_ns, d.header.stamp);
      host.bus().publish(Logic::kDepthTopic, d, clock_ns);
      if (real_time) {
        ASSERT_EQ(setpoints.size(), n + 1) << "depth " << k;  // at once
        EXPECT_EQ(setpoints.back(), clock_ns);
      } else {
        EXPECT_EQ(setpoints.size(), n);
      }
    }
    // Up to 0.187 s: event driven, one step per depth and the timer quiet after its first
    // call (11); timer driven, the timer's calls at 0, 20, ..., 180 ms (10).
    EXPECT_EQ(setpoints.size(), real_time ? 11u : 10u);
    // Depth stops: the timer steps every 20 ms either way.
    const size_t n = setpoints.size();
    host.executor().run_until(400 * kMs);
    EXPECT_GE(setpoints.size() - n, 10u);
    EXPECT_LE(setpoints.size() - n, 11u);
  }
}

// `tactile fly` delivers a depth between the executor's runs: the executor's clock lags the
// arrival clock. The event step runs at the arrival clock (the depth's receive time, not the
// executor's), and an overdue watchdog that steps after it never goes back in time.
TEST(HostWhiskerFsm, RealTimeStepsRunAtTheArrivalClockAndNeverGoBack) {
  using Logic = tactile_fsm::WhiskerFsmLogic;
  constexpr int64_t kMs = 1'000'000;
  struct StampTap : tactile_cli::BusTap {
    std::vector<int64_t> stamps;  // bus (bag) stamps of /cmd_hover
    void on_message(const tactile_cli::TapTopic& t, int64_t stamp_ns,
                    const std::function<void(std::vector<uint8_t>&)>&) override {
      if (t.name == "/cmd_hover") stamps.push_back(stamp_ns);
    }
  } tap;
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  host.bus().add_tap(&tap);
  int64_t clock_ns = 0;
  tactile_cli::add_whisker_fsm(host, tactile_common::ParamMap(), [&clock_ns] { return clock_ns; });
  std::vector<int64_t> setpoints;  // message stamps: the step's time
  host.bus().subscribe<tactile_msgs::msg::HoverSetpoint>(Logic::kSetpointTopic, [&](const auto& m) {
    setpoints.push_back(static_cast<int64_t>(m.header.stamp.sec) * 1'000'000'000 + m.header.stamp.nanosec);
  });
  host.executor().run_until(0);  // the watchdog's first call, at 0
  ASSERT_EQ(setpoints.size(), 1u);
  auto depth_at = [&](int64_t t_ns) {
    clock_ns = t_ns;
    tactile_msgs::msg::TactileDepth d;
    tactile_common::to_stamp(t_ns, d.header.stamp);
    host.bus().publish(Logic::kDepthTopic, d, host.executor().now_ns());
  };
  depth_at(35 * kMs);  // the executor is still at 0
  ASSERT_EQ(setpoints.size(), 2u);
  EXPECT_EQ(setpoints.back(), 35 * kMs);
  EXPECT_EQ(tap.stamps.back(), 35 * kMs);
  depth_at(36 * kMs);  // within T/2 of the last event step: held back for the watchdog
  EXPECT_EQ(setpoints.size(), 2u);
  // The overdue watchdog due at 20 ms steps for the held-back depth, at 35 ms, not 20.
  host.executor().run_until(20 * kMs);
  ASSERT_EQ(setpoints.size(), 3u);
  EXPECT_EQ(setpoints.back(), 35 * kMs);
}
