// tactile_common/ros_parameters.hpp on a real rclcpp::Node: a bad parameter's error names
// the node, the file (or launch override) its value came from, the key and the reason,
// whether the file came as a --params-file argument (ros2 run) or through the
// tactile.parameter_sources list the launch files pass (ros2 launch reads the files itself).

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

#include "rclcpp/rclcpp.hpp"
#include "tactile_common/ros_parameters.hpp"

namespace {

using tactile_common::ParamError;
using tactile_common::ParamMap;

ParamMap defaults() {
  ParamMap d("probe", "defaults");
  d.set("gain", 1.0);
  d.set("window", int64_t{5});
  d.set("frame_id", std::string("base"));
  return d;
}

/// The temporary directories write_file() made; the fixture removes them after each test.
std::vector<std::filesystem::path>& written_dirs() {
  static std::vector<std::filesystem::path> dirs;
  return dirs;
}

/// A parameter file in a fresh temporary directory.
std::string write_file(const std::string& name, const std::string& text) {
  static std::atomic<int> counter{0};
  const auto dir = std::filesystem::temp_directory_path() /
                   ("tactile_ros_parameters_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::create_directories(dir);
  written_dirs().push_back(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

/// A context of its own, initialised with `args` as a process's command line (ros2 run).
std::shared_ptr<rclcpp::Context> context_with(std::vector<std::string> args) {
  args.insert(args.begin(), "probe_node");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  auto context = std::make_shared<rclcpp::Context>();
  context->init(static_cast<int>(argv.size()), argv.data());
  return context;
}

std::string error_of(rclcpp::Node& node) {
  try {
    tactile_common::declare_parameters(node, defaults());
  } catch (const ParamError& e) {
    return e.what();
  }
  return "no error";
}

class RosParameters : public ::testing::Test {
 protected:
  void TearDown() override {
    for (auto& c : contexts_) c->shutdown("test done");
    std::error_code ignored;
    for (const auto& d : written_dirs()) std::filesystem::remove_all(d, ignored);
    written_dirs().clear();
  }
  rclcpp::NodeOptions options(std::vector<std::string> process_args) {
    contexts_.push_back(context_with(std::move(process_args)));
    return rclcpp::NodeOptions().context(contexts_.back());
  }
  std::vector<std::shared_ptr<rclcpp::Context>> contexts_;
};

TEST_F(RosParameters, RosRunParamsFileWithWrongTypeNamesTheFileKeyAndReason) {
  const std::string file = write_file("probe.yaml", "/**:\n  ros__parameters:\n    window: wide\n");
  rclcpp::Node node("probe", "/bench", options({"--ros-args", "--params-file", file}));
  EXPECT_EQ(error_of(node),
            "ros parameters of /bench/probe from " + file +
                ": probe.ros__parameters.window: is a string (wide), expected a integer");
}

// The node logic reads integers with ParamMap's range-checked getters on the map
// declare_parameters returns, so an integer an int would wrap (2^32 + 10 is 10 as an
// int) gets the standalone host's message, naming the file it came from.
TEST_F(RosParameters, IntegerOutOfRangeNamesTheFileLikeTheStandaloneHost) {
  const std::string file = write_file("probe.yaml", "/**:\n  ros__parameters:\n    window: 4294967306\n");
  rclcpp::Node node("probe", "/bench", options({"--ros-args", "--params-file", file}));
  const ParamMap params = tactile_common::declare_parameters(node, defaults());
  try {
    params.get_int("window", 1, 100);
    FAIL() << "4294967306 accepted";
  } catch (const ParamError& e) {
    EXPECT_EQ(std::string(e.what()), "ros parameters of /bench/probe from " + file +
                                         ": probe.ros__parameters.window: must be in [1, 100], got 4294967306");
  }
}

TEST_F(RosParameters, EveryKeyRemembersTheLastFileThatSetItOrThatItIsADefaultOrAnOverride) {
  const std::string a = write_file("a.yaml", "/**:\n  ros__parameters:\n    gain: 2.0\n    window: 7\n");
  const std::string b = write_file("b.yaml", "/bench/probe:\n  ros__parameters:\n    window: 9\n");
  // The process's arguments (ros2 run) and the node's own: rclcpp applies the node's last.
  auto opts = options({"--ros-args", "--params-file", a});
  opts.arguments({"--ros-args", "--params-file", b, "-p", "frame_id:=tool"});
  rclcpp::Node node("probe", "/bench", opts);
  const ParamMap params = tactile_common::declare_parameters(node, defaults());
  EXPECT_EQ(params.get_int("window", 0, 100), 9);
  EXPECT_EQ(params.origin("window"), "ros parameters of /bench/probe from " + b);
  EXPECT_EQ(params.origin("gain"), "ros parameters of /bench/probe from " + a);
  EXPECT_EQ(params.origin("frame_id"),
            "ros parameters of /bench/probe (a launch or -p override; not from " + a + ", " + b + ")");
  // An invalid value found by the node logic names the file too.
  EXPECT_EQ(std::string(params.error("gain", "must be < 1, got 2").what()),
            "ros parameters of /bench/probe from " + a + ": probe.ros__parameters.gain: must be < 1, got 2");
}

TEST_F(RosParameters, AFileThatSetsAnotherValueIsNotBlamedForAnOverride) {
  const std::string a = write_file("a.yaml", "/**:\n  ros__parameters:\n    window: 7\n");
  auto opts = options({});
  opts.arguments({"--ros-args", "--params-file", a, "-p", "window:=1"});
  rclcpp::Node node("probe", opts);
  const ParamMap params = tactile_common::declare_parameters(node, defaults());
  EXPECT_EQ(params.get_int("window", 0, 100), 1);
  EXPECT_EQ(params.origin("window"), "ros parameters of /probe (a launch or -p override; not from " + a + ")");
  EXPECT_EQ(params.origin("gain"), "ros parameters of /probe (default; not set in " + a + ")");
}

// ros2 launch: the container hands the component plain values (NodeOptions parameter
// overrides) and, from launch/launch_common.py, the list of where they came from.
TEST_F(RosParameters, LaunchValueFromAParameterFileNamesTheFile) {
  const std::string a = write_file("tdorc.yaml", "/**/probe:\n  ros__parameters:\n    window: 52.0e9\n");
  auto opts = options({});
  opts.use_global_arguments(false);  // as the component container loads a component
  opts.parameter_overrides({{"window", "52.0e9"},  // what launch's YAML 1.1 reader makes of it
                            {"gain", 3.0},
                            {"tactile.parameter_sources",
                             std::vector<std::string>{a, "launch:gain:gain_arg", "launch:use_sim_time"}}});
  rclcpp::Node node("probe", "/whisker/left", opts);
  EXPECT_EQ(error_of(node), "ros parameters of /whisker/left/probe from " + a +
                                ": probe.ros__parameters.window: is a string (52.0e9), expected a integer");
}

TEST_F(RosParameters, LaunchValueFromALaunchArgumentNamesTheArgument) {
  const std::string a = write_file("probe.yaml", "/**:\n  ros__parameters:\n    gain: 2.0\n");
  auto opts = options({});
  opts.use_global_arguments(false);
  opts.parameter_overrides({{"gain", "high"},
                            {"tactile.parameter_sources", std::vector<std::string>{a, "launch:gain:gain_arg"}}});
  rclcpp::Node node("probe", opts);
  EXPECT_EQ(error_of(node),
            "ros parameters of /probe from the launch file (launch argument gain_arg): "
            "probe.ros__parameters.gain: is a string (high), expected a double (YAML 1.1, which the launch "
            "system reads, takes 52.0e9 as a string: write 52.0e+9)");
}

TEST_F(RosParameters, LaunchValueWithoutSourcesIsAnOverride) {
  auto opts = options({});
  opts.use_global_arguments(false);
  opts.parameter_overrides({{"frame_id", int64_t{3}}});
  rclcpp::Node node("probe", opts);
  EXPECT_EQ(error_of(node), "ros parameters of /probe (a launch or -p override): "
                            "probe.ros__parameters.frame_id: is a integer (3), expected a string");
}

// --- NodeParameters: descriptors and the on-set callback (`ros2 param set`) ----------------

/// The probe's spec: gain live in (0, 10], window read at start in [1, 100], label without a
/// source, frame_id undescribed.
ParamMap described() {
  ParamMap d("probe", "defaults");
  d.set("gain", 1.0, {"controller gain", "1/s", tactile_common::ParamRange{0.0, 10.0, true, false}, true,
                      tactile_common::choice()});
  d.set("window", int64_t{5}, {"samples averaged", "samples", tactile_common::closed(1, 100), false,
                               tactile_common::paper("000 Methods, n = 5")});
  d.set("label", std::string("x"), {"a key not classified yet"});
  d.set("frame_id", std::string("base"));
  return d;
}

/// What the probe's logic would do with new values: params_from + validate (gain < 5 while
/// window > 50, say) and keep them.
struct ProbeLogic {
  double gain = 0.0;
  int applied = 0;
  void apply(const ParamMap& m) {
    const double g = m.get_double("gain");
    if (g >= 5.0 && m.get_int("window", 1, 100) > 4) throw m.error("gain", "must be < 5 with window > 4, got 7");
    gain = g;
    ++applied;
  }
};

rcl_interfaces::msg::SetParametersResult set(rclcpp::Node& node, const rclcpp::Parameter& p) {
  return node.set_parameters({p}).at(0);
}

TEST_F(RosParameters, DescriptorsCarryDescriptionUnitRangeAndReadOnly) {
  rclcpp::Node node("probe", options({}));
  ProbeLogic logic;
  tactile_common::NodeParameters params(node, described(), [&](const ParamMap& m) { logic.apply(m); });
  const auto gain = node.describe_parameter("gain");
  // The description, its unit and where the value comes from (paper / choice / tuned).
  EXPECT_EQ(gain.description, "controller gain [1/s] [choice]");
  ASSERT_EQ(gain.floating_point_range.size(), 1u);
  EXPECT_EQ(gain.floating_point_range[0].from_value, 0.0);
  EXPECT_EQ(gain.floating_point_range[0].to_value, 10.0);
  EXPECT_FALSE(gain.read_only);
  EXPECT_EQ(gain.additional_constraints,
            "range (0, 10]; live: a new value is applied while running, after the node's validation");
  const auto window = node.describe_parameter("window");
  EXPECT_EQ(window.description, "samples averaged [samples] [paper: 000 Methods, n = 5]");
  EXPECT_EQ(node.describe_parameter("label").description, "a key not classified yet");
  ASSERT_EQ(window.integer_range.size(), 1u);
  EXPECT_EQ(window.integer_range[0].from_value, 1);
  EXPECT_EQ(window.integer_range[0].to_value, 100);
  EXPECT_TRUE(window.read_only);
  EXPECT_EQ(window.additional_constraints, "range [1, 100]; read at start: restart the node to change it");
  EXPECT_TRUE(node.describe_parameter("frame_id").read_only);
  EXPECT_EQ(params.live_keys(), std::vector<std::string>{"gain"});
}

TEST_F(RosParameters, ALiveKeyIsAppliedThroughTheLogicOrRefusedWithItsReason) {
  rclcpp::Node node("probe", options({}));
  ProbeLogic logic;
  tactile_common::NodeParameters params(node, described(), [&](const ParamMap& m) { logic.apply(m); });
  // Applied: the logic has it, the node reports it.
  auto r = set(node, rclcpp::Parameter("gain", 2.5));
  EXPECT_TRUE(r.successful) << r.reason;
  EXPECT_EQ(logic.gain, 2.5);
  EXPECT_EQ(node.get_parameter("gain").as_double(), 2.5);
  EXPECT_EQ(params.values().get_double("gain"), 2.5);
  // An integer for a double key (`ros2 param set ... gain 3`) is widened for the logic, as
  // from a file; rclcpp keeps the value as given (an on-set callback cannot change it).
  r = set(node, rclcpp::Parameter("gain", int64_t{3}));
  EXPECT_TRUE(r.successful) << r.reason;
  EXPECT_EQ(logic.gain, 3.0);
  EXPECT_EQ(node.get_parameter("gain").as_int(), 3);
  EXPECT_EQ(params.values().get_double("gain"), 3.0);
  // Its range is checked by the callback (rclcpp checks a double range on doubles only).
  r = set(node, rclcpp::Parameter("gain", int64_t{11}));
  EXPECT_FALSE(r.successful);
  EXPECT_EQ(r.reason, "gain: must be in (0, 10], got 11");
  // Outside the described range: refused with the range, before the logic sees it --
  // by rclcpp outside the descriptor's closed range, by the callback at an open end.
  r = set(node, rclcpp::Parameter("gain", 11.0));
  EXPECT_FALSE(r.successful);
  EXPECT_NE(r.reason.find("gain"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("range"), std::string::npos) << r.reason;
  r = set(node, rclcpp::Parameter("gain", 0.0));
  EXPECT_FALSE(r.successful);
  EXPECT_EQ(r.reason, "gain: must be in (0, 10], got 0");
  // Refused by the logic's validation: its reason, naming the node and key; nothing changes.
  r = set(node, rclcpp::Parameter("gain", 7.0));
  EXPECT_FALSE(r.successful);
  EXPECT_EQ(r.reason, "ros parameters of /probe (set while running): probe.ros__parameters.gain: "
                      "must be < 5 with window > 4, got 7");
  // A wrong type.
  r = set(node, rclcpp::Parameter("gain", "high"));
  EXPECT_FALSE(r.successful);
  EXPECT_EQ(r.reason, "gain: is a string (high), expected a double");
  EXPECT_EQ(logic.gain, 3.0);
  EXPECT_EQ(logic.applied, 2);
  EXPECT_EQ(node.get_parameter("gain").as_int(), 3);
}

TEST_F(RosParameters, EveryOtherKeyIsRefusedAsReadOnly) {
  rclcpp::Node node("probe", options({}));
  ProbeLogic logic;
  tactile_common::NodeParameters params(node, described(), [&](const ParamMap& m) { logic.apply(m); });
  for (const auto& p : {rclcpp::Parameter("window", int64_t{7}), rclcpp::Parameter("frame_id", "tool"),
                        rclcpp::Parameter(tactile_common::ParameterOrigins::kSourcesKey, std::vector<std::string>{})}) {
    const auto r = set(node, p);
    EXPECT_FALSE(r.successful) << p.get_name();
    EXPECT_NE(r.reason.find("read-only"), std::string::npos) << r.reason;
  }
  EXPECT_EQ(node.get_parameter("window").as_int(), 5);
  EXPECT_EQ(logic.applied, 0);
  // Without an apply function no key is live: gain is read-only too.
  rclcpp::Node other("probe2", options({}));
  tactile_common::NodeParameters fixed(other, described());
  EXPECT_TRUE(other.describe_parameter("gain").read_only);
  EXPECT_FALSE(set(other, rclcpp::Parameter("gain", 2.0)).successful);
  EXPECT_TRUE(fixed.live_keys().empty());
  // A parameter the node declares itself, not from the logic's defaults, is left to rclcpp
  // and its own descriptor (as use_sim_time and qos_overrides.* are).
  other.declare_parameter("own", 1.0);
  EXPECT_TRUE(set(other, rclcpp::Parameter("own", 2.0)).successful);
}

TEST_F(RosParameters, AFileValueOutsideTheDescribedRangeNamesTheFileKeyAndRange) {
  const std::string file = write_file("probe.yaml", "/**:\n  ros__parameters:\n    window: 0\n");
  rclcpp::Node node("probe", "/bench", options({"--ros-args", "--params-file", file}));
  try {
    tactile_common::NodeParameters params(node, described());
    FAIL() << "window 0 accepted";
  } catch (const ParamError& e) {
    EXPECT_EQ(std::string(e.what()), "ros parameters of /bench/probe from " + file +
                                         ": probe.ros__parameters.window: must be in [1, 100], got 0");
  }
}

}  // namespace
