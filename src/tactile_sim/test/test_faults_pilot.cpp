// Fault injection rules and the scenario pilot's sequencing, against
// hand-worked expectations.
#include <gtest/gtest.h>

#include <cmath>

#include "tactile_common/time.hpp"
#include "tactile_sim/logic/faults.hpp"
#include "tactile_sim/logic/pilot_logic.hpp"

using tactile_msgs::msg::WhiskerPressure;
using tactile_sim::FaultSpec;
using tactile_sim::PilotStep;
using tactile_sim::ScriptedPilotLogic;
using tactile_sim::TopicFaults;

namespace {

WhiskerPressure sample(double base) {
  WhiskerPressure m;
  m.pressure = {base, base + 1.0, base + 2.0};
  return m;
}

FaultSpec rule(FaultSpec::Type type) {
  FaultSpec f;
  f.type = type;
  f.topic = "whisker/left/pressure";
  return f;
}

int64_t ms(double t) { return tactile_common::from_seconds(t / 1000.0); }

}  // namespace

TEST(Faults, StuckHoldsTheChannelOnlyInsideItsWindow) {
  FaultSpec f = rule(FaultSpec::Type::kStuck);
  f.channel = 1;
  f.start_s = 0.04;
  f.duration_s = 0.04;
  TopicFaults<WhiskerPressure> faults({f}, 1);
  tactile_sim::FaultCounts counts;
  std::vector<WhiskerPressure> out;
  for (int k = 0; k < 6; ++k) faults.push(sample(100.0 * k), ms(20.0 * k), out, counts);
  ASSERT_EQ(out.size(), 6u);
  // t = 0, 20 ms: untouched; 40, 60 ms: channel 1 stuck at its 40 ms value; 80 ms: free again.
  EXPECT_DOUBLE_EQ(out[1].pressure[1], 101.0);
  EXPECT_DOUBLE_EQ(out[2].pressure[1], 201.0);
  EXPECT_DOUBLE_EQ(out[3].pressure[1], 201.0);
  EXPECT_DOUBLE_EQ(out[3].pressure[0], 300.0);  // other channels untouched
  EXPECT_DOUBLE_EQ(out[4].pressure[1], 401.0);
  EXPECT_EQ(counts["stuck"], 2u);
}

TEST(Faults, SpikeNanOutOfRangeAndDropout) {
  FaultSpec spike = rule(FaultSpec::Type::kSpike);
  spike.channel = 2;
  spike.magnitude = 50.0;
  FaultSpec drop = rule(FaultSpec::Type::kDropout);
  drop.start_s = 0.1;
  drop.duration_s = 0.05;
  TopicFaults<WhiskerPressure> faults({spike, drop}, 1);
  tactile_sim::FaultCounts counts;
  std::vector<WhiskerPressure> out;
  for (int k = 0; k < 10; ++k) faults.push(sample(0.0), ms(20.0 * k), out, counts);
  // Messages at 100, 120, 140 ms fall into the dropout.
  EXPECT_EQ(out.size(), 7u);
  EXPECT_EQ(counts["dropout"], 3u);
  for (const auto& m : out) EXPECT_DOUBLE_EQ(m.pressure[2], 52.0);

  FaultSpec nan = rule(FaultSpec::Type::kNan);
  FaultSpec oor = rule(FaultSpec::Type::kOutOfRange);
  oor.channel = 0;
  out.clear();
  TopicFaults<WhiskerPressure>({nan}, 1).push(sample(0.0), 0, out, counts);
  TopicFaults<WhiskerPressure>({oor}, 1).push(sample(0.0), 0, out, counts);
  ASSERT_EQ(out.size(), 2u);
  for (double v : out[0].pressure) EXPECT_TRUE(std::isnan(v));
  EXPECT_DOUBLE_EQ(out[1].pressure[0], 1e9);
  EXPECT_DOUBLE_EQ(out[1].pressure[1], 1.0);
}

TEST(Faults, LossFollowsItsProbabilityAndLatencyDelaysInOrder) {
  FaultSpec loss = rule(FaultSpec::Type::kLoss);
  loss.probability = 0.25;
  TopicFaults<WhiskerPressure> lossy({loss}, 7);
  tactile_sim::FaultCounts counts;
  std::vector<WhiskerPressure> out;
  const int n = 20000;
  for (int k = 0; k < n; ++k) lossy.push(sample(k), ms(k), out, counts);
  EXPECT_NEAR(static_cast<double>(counts["loss"]) / n, 0.25, 0.01);
  EXPECT_EQ(out.size() + counts["loss"], static_cast<size_t>(n));

  FaultSpec lat = rule(FaultSpec::Type::kLatency);
  lat.delay_s = 0.05;
  TopicFaults<WhiskerPressure> late({lat}, 1);
  out.clear();
  std::vector<int64_t> delivered_at;
  for (int k = 0; k < 10; ++k) {
    const size_t before = out.size();
    late.push(sample(k), ms(20.0 * k), out, counts);
    late.flush(ms(20.0 * k), out);
    for (size_t i = before; i < out.size(); ++i) delivered_at.push_back(ms(20.0 * k));
  }
  // 50 ms delay at 20 ms spacing: sample k comes out at tick k + 3 (60 ms later), in order.
  ASSERT_EQ(out.size(), 7u);
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_DOUBLE_EQ(out[i].pressure[0], static_cast<double>(i));
    EXPECT_EQ(delivered_at[i], ms(20.0 * (static_cast<double>(i) + 3)));
  }
}

TEST(Pilot, FliesTheDataCollectionProtocol) {
  PilotStep takeoff;
  takeoff.kind = PilotStep::Kind::kTakeoff;
  takeoff.height = 0.4;
  takeoff.duration_s = 1.0;
  PilotStep forward;
  forward.kind = PilotStep::Kind::kVelocity;
  forward.velocity = {0.2, 0.0};
  forward.until = "contact";
  forward.timeout_s = 5.0;
  PilotStep sweep;
  sweep.kind = PilotStep::Kind::kVelocity;
  sweep.velocity = {0.0, -0.2};
  sweep.duration_s = 2.0;
  PilotStep land;
  land.kind = PilotStep::Kind::kLand;
  ScriptedPilotLogic pilot({takeoff, forward, sweep, land}, tactile_sim::VehicleType::kWhiskerCrazyflie,
                           tactile_sim::Vec3::Zero(), 0.0);
  auto at = [&](double t) { return *pilot.on_timer(tactile_common::from_seconds(t)).hover; };
  EXPECT_DOUBLE_EQ(at(0.0).height, 0.4);
  EXPECT_DOUBLE_EQ(at(0.5).vx, 0.0);
  EXPECT_DOUBLE_EQ(at(1.0).vx, 0.2);   // takeoff done: forward
  EXPECT_DOUBLE_EQ(at(2.0).vx, 0.2);   // no contact yet
  tactile_msgs::msg::WhiskerSignal sig;
  sig.contact = true;
  pilot.on_whisker_signal(sig);
  auto sp = at(2.02);                  // contact: sweep right, height held
  EXPECT_DOUBLE_EQ(sp.vx, 0.0);
  EXPECT_DOUBLE_EQ(sp.vy, -0.2);
  EXPECT_DOUBLE_EQ(sp.height, 0.4);
  EXPECT_NEAR(pilot.stats().contact_time_s, 2.02, 1e-9);
  EXPECT_FALSE(at(4.0).land);
  EXPECT_TRUE(at(4.02).land);          // 2 s sweep done: land
  EXPECT_TRUE(pilot.stats().finished);
  EXPECT_EQ(pilot.stats().steps_timed_out, 0u);
}

TEST(Pilot, UntilTimesOutAndPositionStepsNeedAPositionVehicle) {
  PilotStep forward;
  forward.kind = PilotStep::Kind::kVelocity;
  forward.velocity = {0.3, 0.0};
  forward.until = "contact";
  forward.timeout_s = 1.0;
  PilotStep land;
  land.kind = PilotStep::Kind::kLand;
  ScriptedPilotLogic pilot({forward, land}, tactile_sim::VehicleType::kXplorer, tactile_sim::Vec3(0, 0, 1), 0.0);
  // Position vehicle: the setpoint moves at 0.3 m/s along +x.
  pilot.on_timer(0);
  const auto p = *pilot.on_timer(tactile_common::from_seconds(0.5)).position;
  EXPECT_NEAR(p.pose.position.x, 0.15, 1e-9);
  pilot.on_timer(tactile_common::from_seconds(1.0));
  EXPECT_EQ(pilot.stats().steps_timed_out, 1u);
  EXPECT_TRUE(pilot.stats().finished);

  PilotStep pos;
  pos.kind = PilotStep::Kind::kPosition;
  EXPECT_THROW(ScriptedPilotLogic({pos}, tactile_sim::VehicleType::kWhiskerCrazyflie, tactile_sim::Vec3::Zero(), 0.0),
               tactile_sim::ScenarioError);
}
