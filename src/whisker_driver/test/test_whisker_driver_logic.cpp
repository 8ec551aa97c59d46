#include <gtest/gtest.h>

#include <cmath>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tactile_common/parameters.hpp"
#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "whisker_driver/sources.hpp"
#include "whisker_driver/whisker_driver_logic.hpp"
#ifdef WHISKER_DRIVER_WITH_BAG
#include "tactile_bag/bag.hpp"
#include "tactile_bag/typed.hpp"
#include "whisker_driver/bag_source.hpp"
#endif

using namespace whisker_driver;
using tactile_common::from_stamp;

namespace {
WhiskerDriverParams sim_params() {
  WhiskerDriverParams p;
  p.source = "sim";
  p.sim_seed = 5;
  p.sim_takeoff_s = 1.0;
  p.sim_hover_s = 30.0;
  p.sim_contact_start_s = {10.0};
  p.sim_contact_duration_s = {2.0};
  p.sim_contact_peak_nm = {2e-4};
  return p;
}

std::vector<WhiskerPressure> run(WhiskerDriverLogic& logic, int64_t t0, int ticks, int64_t period,
                                 int64_t jitter = 0) {
  std::vector<WhiskerPressure> all;
  for (int k = 0; k < ticks; ++k) {
    // Timer ticks a little late on odd ticks: the stamps must not care.
    const int64_t now = t0 + k * period + ((k % 2) ? jitter : 0);
    for (auto& m : logic.on_timer(now).pressure) all.push_back(m);
  }
  return all;
}
}  // namespace

TEST(WhiskerDriverLogic, DefaultParametersRoundTrip) {
  const auto defaults = WhiskerDriverLogic::default_parameters();
  const auto p = WhiskerDriverLogic::params_from(defaults);
  const WhiskerDriverParams d;
  EXPECT_EQ(p.source, d.source);
  EXPECT_EQ(p.protocol, "text");
  EXPECT_DOUBLE_EQ(p.rate_hz, 50.0);
  EXPECT_EQ(p.sim_contact_peak_nm, d.sim_contact_peak_nm);
  EXPECT_STREQ(WhiskerDriverLogic::kOutputTopic, "pressure");
}

TEST(WhiskerDriverLogic, BadParametersNameTheKey) {
  auto m = WhiskerDriverLogic::default_parameters();
  m.set("source", std::string("usb"));
  try {
    WhiskerDriverLogic::params_from(m);
    FAIL();
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("source"), std::string::npos) << e.what();
  }
  m = WhiskerDriverLogic::default_parameters();
  m.set("sim_contact_peak_nm", std::vector<double>{1e-4, 2e-4});
  EXPECT_THROW(WhiskerDriverLogic::params_from(m), tactile_common::ParamError);
  m = WhiskerDriverLogic::default_parameters();
  m.set("whisker_id", int64_t{2});
  EXPECT_THROW(WhiskerDriverLogic::params_from(m), tactile_common::ParamError);
  m = WhiskerDriverLogic::default_parameters();
  m.set("rate_hz", 0.0);
  EXPECT_THROW(WhiskerDriverLogic::params_from(m), tactile_common::ParamError);
}

// The parameter spec: every key described, no described range wider than what
// params_from()/validate() accept, none live (read at configure).
TEST(WhiskerDriverLogic, EveryParameterIsDescribedWithTheRangeValidateAcceptsAndNoneIsLive) {
  const tactile_common::ParamMap d = WhiskerDriverLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { WhiskerDriverLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

// baud was read as int64 and checked only > 0, then narrowed to int for the
// serial port: 2^32 + 115200 opened the port at 115200. Now every integer
// parameter set to its default + 2^32 is rejected with its key and the value
// as given, except sim_seed: a seed is any 64-bit value (its uint64 bit pattern).
TEST(WhiskerDriverLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(WhiskerDriverLogic::default_parameters(),
                                                        [](const tactile_common::ParamMap& m) { WhiskerDriverLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 3u);  // baud, whisker_id, sim_seed
  for (const auto& [key, w] : wrapped) {
    if (key == "sim_seed") {
      EXPECT_EQ(w.error, "");
    } else {
      EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
    }
  }
  WhiskerDriverParams p;  // built in code: validate() has the same bound
  p.baud = (int64_t{1} << 32) + 115200;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(WhiskerDriverLogic, ConfigFileLoads) {
  // The repository's config/whisker_driver.yaml (tests run in the package directory):
  // every key known with the right type; shared values from /**/whisker_driver,
  // per-whisker values from /whisker/<side>/whisker_driver.
  const std::string path = "../../config/whisker_driver.yaml";
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const auto left = WhiskerDriverLogic::params_from(tactile_common::load_node_parameters(
      path, "/whisker/left/whisker_driver", WhiskerDriverLogic::default_parameters()));
  const auto right = WhiskerDriverLogic::params_from(tactile_common::load_node_parameters(
      path, "/whisker/right/whisker_driver", WhiskerDriverLogic::default_parameters()));
  for (const auto& p : {left, right}) {
    EXPECT_DOUBLE_EQ(p.rate_hz, 50.0);
    EXPECT_EQ(p.baud, 115200);
    EXPECT_EQ(p.source, "sim");
  }
  EXPECT_EQ(left.protocol, "text");
  EXPECT_EQ(left.whisker_id, 0);
  EXPECT_EQ(right.protocol, "csv");
  EXPECT_EQ(right.whisker_id, 1);
  EXPECT_NE(left.sim_seed, right.sim_seed);
}

TEST(SimSource, FiftyHertzStampsAndDeterminism) {
  const auto p = sim_params();
  WhiskerDriverLogic a(p), b(p);
  const int64_t t0 = 123456789;
  const int64_t period = 20000000;
  EXPECT_EQ(a.period_ns(), period);
  const auto ma = run(a, t0, 1500, period, 7000000);
  const auto mb = run(b, t0, 1500, period, 0);
  // One sample per period, stamped exactly t0 + k * 20 ms regardless of jitter.
  ASSERT_EQ(ma.size(), 1500u);
  ASSERT_EQ(mb.size(), 1500u);
  for (size_t k = 0; k < ma.size(); ++k) {
    ASSERT_EQ(from_stamp(ma[k].header.stamp), t0 + static_cast<int64_t>(k) * period) << k;
    ASSERT_EQ(ma[k].sequence, k);
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(ma[k].pressure[c], mb[k].pressure[c]) << k;
      ASSERT_EQ(ma[k].temperature[c], mb[k].temperature[c]) << k;
      ASSERT_TRUE(std::isfinite(ma[k].pressure[c]));
    }
    EXPECT_EQ(ma[k].header.frame_id, "whisker_left");
  }
  EXPECT_EQ(a.stats().published, 1500u);
  EXPECT_EQ(a.stats().sequence_gaps, 0u);
  // Another seed gives another trace.
  auto q = p;
  q.sim_seed = 6;
  WhiskerDriverLogic c(q);
  const auto mc = run(c, t0, 10, period);
  EXPECT_NE(mc[5].pressure[0], ma[5].pressure[0]);
}

// The bench rig's stall diagnostics read the age of the stream from it.
TEST(WhiskerDriverLogic, LastOutputTimeIsTheLastTickThatPublished) {
  WhiskerDriverLogic logic(sim_params());
  EXPECT_FALSE(logic.last_output_ns());
  ASSERT_EQ(logic.on_timer(1000).pressure.size(), 1u);
  EXPECT_EQ(logic.last_output_ns(), 1000);
  ASSERT_TRUE(logic.on_timer(2000).pressure.empty());  // the next sample is 20 ms later
  EXPECT_EQ(logic.last_output_ns(), 1000);
  ASSERT_EQ(logic.on_timer(20'001'000).pressure.size(), 1u);
  EXPECT_EQ(logic.last_output_ns(), 20'001'000);
}

TEST(SimSource, LateTimerCatchesUpWithExactStamps) {
  WhiskerDriverLogic logic(sim_params());
  auto out = logic.on_timer(0);
  ASSERT_EQ(out.pressure.size(), 1u);  // sample 0 at t0
  out = logic.on_timer(100000000);     // 100 ms later: samples 1..5
  ASSERT_EQ(out.pressure.size(), 5u);
  EXPECT_EQ(from_stamp(out.pressure.back().header.stamp), 100000000);
  out = logic.on_timer(100000000);     // same time: nothing new
  EXPECT_TRUE(out.pressure.empty());
}

TEST(SimSource, ScriptedContactShowsInThePressure) {
  // Contact 10-12 s (half-sine, 2e-4 N m peak): channel 1 rises by about
  // sensitivity * peak = 200 Pa at the top of the pulse (t = 11 s).
  WhiskerDriverLogic logic(sim_params());
  const auto m = run(logic, 0, 700, 20000000);
  const double before = m[450].pressure[0];  // t = 9 s
  const double peak = m[550].pressure[0];    // t = 11 s
  const tactile_sim::WhiskerBarometerParams model;
  EXPECT_NEAR(peak - before, model.sensitivity_pa_per_nm[0] * 2e-4, 40.0);
  // Motors on after 1 s: the scenario's take-off cools the barometers.
  EXPECT_LT(m[690].temperature[0], m[40].temperature[0] - 0.3);
  SimScenario sc;
  sc.contacts = {{10.0, 2.0, 2e-4}};
  EXPECT_DOUBLE_EQ(sc.load(11.0), 2e-4);
  EXPECT_DOUBLE_EQ(sc.load(9.99), 0.0);
  EXPECT_NEAR(sc.load(10.5), 2e-4 * std::sqrt(0.5), 1e-12);
}

#ifdef WHISKER_DRIVER_WITH_BAG
TEST(BagSource, ReplaysWhiskerPressurePacedByRecordedTime) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("whisker_driver_bag_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  {
    tactile_bag::Writer w;
    w.open(dir.string());
    for (int k = 0; k < 10; ++k) {
      WhiskerPressure m;
      tactile_common::to_stamp(5000000000LL + k * 20000000LL, m.header.stamp);
      m.header.frame_id = "whisker_left";
      m.pressure = {100000.0 + k, 100001.0, 100002.0};
      m.temperature = {25.0, 25.0, 25.0};
      if (k == 4) m.pressure[1] = std::nan("");  // bad sample in the bag: dropped
      m.sequence = static_cast<uint32_t>(k);
      w.write("/whisker/left/pressure", 5000000000LL + k * 20000000LL, m);
    }
    w.close();
  }
  WhiskerDriverParams p;
  p.source = "bag";
  p.bag_path = dir.string();
  p.bag_topic = "/whisker/left/pressure";
  WhiskerDriverLogic logic(p);
  auto out = logic.on_timer(0);
  ASSERT_EQ(out.pressure.size(), 1u);
  EXPECT_EQ(from_stamp(out.pressure[0].header.stamp), 5000000000LL);  // recorded stamp kept
  out = logic.on_timer(50000000);  // 50 ms: recorded offsets 20, 40 ms
  ASSERT_EQ(out.pressure.size(), 2u);
  EXPECT_DOUBLE_EQ(out.pressure[1].pressure[0], 100002.0);
  out = logic.on_timer(1000000000);
  EXPECT_EQ(out.pressure.size(), 6u);  // 3..9 without the NaN one
  EXPECT_TRUE(logic.finished());
  EXPECT_EQ(logic.stats().source_errors, 1u);
  EXPECT_EQ(logic.stats().sequence_gaps, 1u);

  p.bag_topic = "/whisker/right/pressure";
  try {
    WhiskerDriverLogic bad(p);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/whisker/right/pressure"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}
#endif

#ifdef WHISKER_DRIVER_WITH_BAG
namespace {
/// A bag of n left-whisker samples at 50 Hz (stamp = receive time = t0 + k T,
/// sequence k, pressure 100000 + k on channel 0) with `fault` applied, then
/// replayed through the driver by a 50 Hz timer. Returns what it published.
enum class Fault { kNone, kAhead, kBehind, kSwap, kGap, kDuplicate };
std::vector<WhiskerPressure> replay_with(Fault fault, WhiskerDriverLogic::Stats& stats, int n = 250, int at = 120) {
  constexpr int64_t kT0 = 5000000000LL, kT = 20000000LL;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("whisker_driver_fault_" + std::to_string(static_cast<int>(fault)) + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  {
    tactile_bag::Writer w;
    w.open(dir.string());
    std::vector<std::pair<int64_t, WhiskerPressure>> rows;  // (receive, message)
    for (int k = 0; k < n; ++k) {
      WhiskerPressure m;
      tactile_common::to_stamp(kT0 + k * kT, m.header.stamp);
      m.header.frame_id = "whisker_left";
      m.pressure = {100000.0 + k, 100001.0, 100002.0};
      m.temperature = {25.0, 25.0, 25.0};
      m.sequence = static_cast<uint32_t>(k);
      rows.emplace_back(kT0 + k * kT, m);
    }
    auto& m = rows[static_cast<size_t>(at)].second;
    switch (fault) {
      case Fault::kNone: break;
      case Fault::kAhead: tactile_common::to_stamp(kT0 + at * kT + 20000000000LL, m.header.stamp); break;
      case Fault::kBehind: tactile_common::to_stamp(kT0 + at * kT - 20000000000LL, m.header.stamp); break;
      case Fault::kSwap: std::swap(rows[static_cast<size_t>(at)].second, rows[static_cast<size_t>(at) + 1].second); break;
      case Fault::kGap: rows.erase(rows.begin() + at, rows.begin() + at + 100); break;  // 2 s stall, 100 lost
      case Fault::kDuplicate: rows.insert(rows.begin() + at + 1, {kT0 + at * kT + 1000000, m}); break;
    }
    for (const auto& [t, msg] : rows) w.write("/whisker/left/pressure", t, msg);
    w.close();
  }
  WhiskerDriverParams p;
  p.source = "bag";
  p.bag_path = dir.string();
  p.bag_topic = "/whisker/left/pressure";
  WhiskerDriverLogic logic(p);
  std::vector<WhiskerPressure> out;
  for (int64_t now = 0; !logic.finished(); now += kT) {
    for (auto& m : logic.on_timer(now).pressure) out.push_back(m);
  }
  stats = logic.stats();
  std::filesystem::remove_all(dir);
  return out;
}

/// Published samples as (sequence, stamp) and the stamps' strict order.
void expect_clean_stamps(const std::vector<WhiskerPressure>& out) {
  for (size_t i = 0; i < out.size(); ++i) {
    // Every published sample carries its true sampling time t0 + seq T.
    EXPECT_EQ(from_stamp(out[i].header.stamp), 5000000000LL + out[i].sequence * 20000000LL) << i;
    EXPECT_DOUBLE_EQ(out[i].pressure[0], 100000.0 + out[i].sequence) << i;
    if (i > 0) {
      EXPECT_GT(out[i].sequence, out[i - 1].sequence) << i;
    }
  }
}
}  // namespace

TEST(BagSource, StampTwentySecondsAheadIsRepairedNotDropped) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kAhead, s);
  ASSERT_EQ(out.size(), 250u);  // one bad stamp costs no sample
  expect_clean_stamps(out);
  EXPECT_EQ(s.stamps_repaired_ahead, 1u);
  EXPECT_EQ(s.stamps_repaired_behind + s.dropped_late + s.dropped_duplicate + s.gaps + s.clock_steps, 0u);
}

TEST(BagSource, StampTwentySecondsBehindIsRepairedNotDropped) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kBehind, s);
  ASSERT_EQ(out.size(), 250u);
  expect_clean_stamps(out);
  EXPECT_EQ(s.stamps_repaired_behind, 1u);
  EXPECT_EQ(s.stamps_repaired_ahead + s.dropped_late + s.dropped_duplicate + s.gaps, 0u);
}

TEST(BagSource, TwoSwappedSamplesCostTheLateOne) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kSwap, s);
  ASSERT_EQ(out.size(), 249u);  // sample 121 first, then 120 is late: dropped
  expect_clean_stamps(out);
  EXPECT_EQ(out[120].sequence, 121u);
  EXPECT_EQ(s.dropped_late, 1u);
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_EQ(s.samples_missing, 1u);
  EXPECT_EQ(s.sequence_gaps, 1u);
  EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind + s.dropped_duplicate, 0u);
}

TEST(BagSource, StallIsAGapOfTheMissingSamples) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kGap, s);
  ASSERT_EQ(out.size(), 150u);
  expect_clean_stamps(out);
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_EQ(s.samples_missing, 100u);
  EXPECT_EQ(s.sequence_gaps, 100u);
  EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind + s.dropped_late + s.dropped_duplicate, 0u);
}

TEST(BagSource, DuplicateIsDropped) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kDuplicate, s);
  ASSERT_EQ(out.size(), 250u);
  expect_clean_stamps(out);
  EXPECT_EQ(s.dropped_duplicate, 1u);
  EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind + s.dropped_late + s.gaps, 0u);
}

TEST(BagSource, CleanBagNeedsNoDecision) {
  WhiskerDriverLogic::Stats s;
  const auto out = replay_with(Fault::kNone, s);
  ASSERT_EQ(out.size(), 250u);
  expect_clean_stamps(out);
  EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind + s.dropped_late + s.dropped_duplicate + s.gaps +
                s.clock_steps + s.sequence_restarts,
            0u);
}
#endif
