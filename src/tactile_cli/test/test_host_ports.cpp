// HostPorts: a logic's ports, declared once in its wire(), on the host's Bus and Executor.
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "crazyflie_bridge/bridge_runner.hpp"
#include "std_msgs/msg/float64.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/host_ports.hpp"
#include "tactile_common/ports.hpp"

namespace {

using std_msgs::msg::Float64;
using tactile_common::ports::Clock;
using tactile_common::ports::Pub;
using tactile_common::ports::Sub;

Float64 value(double v) {
  Float64 m;
  m.data = v;
  return m;
}

/// A node logic with the three kinds of port: doubles what arrives on "in" (remembering
/// the receive time), counts "tick" messages without a receive time, publishes -1 every 10 ms.
struct EchoLogic {
  static constexpr int64_t kPeriodNs = 10'000'000;
  std::vector<int64_t> receive_ns;
  int ticks_seen = 0;

  template <class Ports>
  static void wire(Ports& p, EchoLogic& l) {
    auto out = p.template publisher<Float64>("out", Pub::kData);
    p.template subscribe<Float64>("in", Sub::kSensorData, [&l, out](const Float64& m, int64_t receive_ns) {
      l.receive_ns.push_back(receive_ns);
      out(value(2.0 * m.data));
    });
    p.template subscribe<Float64>("/tick", Sub::kReliable, [&l](const Float64&) { ++l.ticks_seen; });
    p.timer(kPeriodNs, [out](int64_t) { out(value(-1.0)); }, Clock::kNode);
  }
};

/// Every message on `topic`, with the bus timestamp it was published at.
struct Recorded {
  std::vector<double> data;
  std::vector<int64_t> stamp_ns;
};
Recorded* record(tactile_cli::Host& host, const std::string& topic) {
  auto r = std::make_shared<Recorded>();
  Recorded* raw = host.keep(r);
  const tactile_cli::Executor* ex = &host.executor();
  host.bus().subscribe<Float64>(topic, [raw, ex](const Float64& m) {
    raw->data.push_back(m.data);
    raw->stamp_ns.push_back(ex->now_ns());
  });
  return raw;
}

TEST(HostPorts, LogicReceivesAndPublishesOnItsDeclaredTopicsInItsNamespace) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  host.executor().set_time(1'000'000'000);
  EchoLogic logic;
  tactile_cli::wire(host, "whisker/left", logic);
  Recorded* out = record(host, "/whisker/left/out");

  // The timer: first call at wiring time, then every period.
  host.executor().run_until(1'025'000'000);
  EXPECT_EQ(out->data, (std::vector<double>{-1.0, -1.0, -1.0}));
  EXPECT_EQ(out->stamp_ns, (std::vector<int64_t>{1'000'000'000, 1'010'000'000, 1'020'000'000}));

  // The subscription: in the namespace only, receive time = the host's clock.
  host.bus().publish("/in", value(7.0), host.executor().now_ns());
  EXPECT_TRUE(logic.receive_ns.empty());
  host.bus().publish("/whisker/left/in", value(3.0), 0);  // the bag stamp is not the receive time
  ASSERT_EQ(logic.receive_ns.size(), 1u);
  EXPECT_EQ(logic.receive_ns[0], 1'025'000'000);
  EXPECT_EQ(out->data.back(), 6.0);
  EXPECT_EQ(out->stamp_ns.back(), 1'025'000'000);

  // An absolute topic stays absolute; a handler without a receive time works too.
  host.bus().publish("/tick", value(0.0), 0);
  host.bus().publish("/whisker/left/tick", value(0.0), 0);
  EXPECT_EQ(logic.ticks_seen, 1);

  const auto counts = host.bus().published_counts();
  EXPECT_EQ(counts.at("/whisker/left/out"), 4u);
  EXPECT_EQ(counts.count("/out"), 0u);
}

// A real-time host delivers between the executor's runs: with a clock given, receive times
// and publish stamps are that clock's; the timer still runs on the executor.
TEST(HostPorts, AGivenClockIsTheNodesClockForReceiveTimesAndPublishStamps) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  int64_t wall_ns = 5'000'000;
  EchoLogic logic;
  tactile_cli::HostPorts ports(host, "", {}, [&wall_ns] { return wall_ns; });
  EchoLogic::wire(ports, logic);
  std::vector<int64_t> bag_stamps;
  struct Tap : tactile_cli::BusTap {
    std::vector<int64_t>* stamps;
    void on_message(const tactile_cli::TapTopic& t, int64_t stamp_ns,
                    const std::function<void(std::vector<uint8_t>&)>&) override {
      if (t.name == "/out") stamps->push_back(stamp_ns);
    }
  } tap;
  tap.stamps = &bag_stamps;
  host.bus().add_tap(&tap);
  host.executor().run_until(0);  // the timer's first call: at the executor's 0, stamped on the clock
  ASSERT_EQ(bag_stamps.size(), 1u);
  EXPECT_EQ(bag_stamps[0], 5'000'000);
  wall_ns = 7'000'000;
  host.bus().publish("/in", value(1.0), 0);
  ASSERT_EQ(logic.receive_ns.size(), 1u);
  EXPECT_EQ(logic.receive_ns[0], 7'000'000);  // not the executor's 0
  EXPECT_EQ(bag_stamps.back(), 7'000'000);
}

// The bridge's ports in `tactile fly` (BridgeRunner::wire, as its component wires them):
// the link's sinks publish the pressures and odometry on the bus at the host clock, and a
// setpoint on cmd_hover reaches the host's handler.
TEST(HostPorts, BridgeWireDeclaresTheLinksOutputsAndTheSetpointInput) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  int64_t wall_ns = 3'000'000;
  tactile_cli::HostPorts ports(host, "", {}, [&wall_ns] { return wall_ns; });
  int setpoints = 0;
  const auto sinks = crazyflie_bridge::BridgeRunner::wire(
      ports, [&setpoints](const tactile_msgs::msg::HoverSetpoint&) { ++setpoints; });
  struct Tap : tactile_cli::BusTap {
    std::map<std::string, int64_t> last_stamp;
    void on_message(const tactile_cli::TapTopic& t, int64_t stamp_ns,
                    const std::function<void(std::vector<uint8_t>&)>&) override {
      last_stamp[t.name] = stamp_ns;
    }
  } tap;
  host.bus().add_tap(&tap);
  sinks.left(tactile_msgs::msg::WhiskerPressure());
  wall_ns = 4'000'000;
  sinks.right(tactile_msgs::msg::WhiskerPressure());
  sinks.odom(nav_msgs::msg::Odometry());
  EXPECT_EQ(tap.last_stamp, (std::map<std::string, int64_t>{{"/whisker/left/pressure", 3'000'000},
                                                            {"/whisker/right/pressure", 4'000'000},
                                                            {"/odom", 4'000'000}}));
  host.bus().publish("/cmd_hover", tactile_msgs::msg::HoverSetpoint(), 0);
  EXPECT_EQ(setpoints, 1);
}

TEST(HostPorts, RemapMovesADeclaredTopic) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  EchoLogic logic;
  tactile_cli::wire(host, "", logic, {{"/out", "/evaluation/out"}});
  Recorded* own = record(host, "/out");
  Recorded* moved = record(host, "/evaluation/out");
  host.bus().publish("/in", value(1.5), 0);
  EXPECT_TRUE(own->data.empty());
  EXPECT_EQ(moved->data, (std::vector<double>{3.0}));
}

TEST(HostPorts, RemapOfATopicTheNodeDoesNotDeclareIsAnError) {
  tactile_cli::Host host(TACTILE_CONFIG_DIR);
  EchoLogic logic;
  try {
    tactile_cli::wire(host, "whisker/left", logic, {{"/out", "/evaluation/out"}});  // the node's is /whisker/left/out
    FAIL() << "expected std::logic_error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("remapping /out -> /evaluation/out in namespace 'whisker/left'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
