// DriverHealth: the bench-rig whisker deck's diagnostics (stall, frame errors, device gone),
// evaluated per diagnostics period from the driver's counters.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/parameters.hpp"
#include "whisker_driver/driver_health.hpp"

namespace whisker_driver {
namespace {

using Level = DriverHealth::Level;

WhiskerDriverLogic::Stats streaming(uint64_t frames) {
  WhiskerDriverLogic::Stats s{};
  s.parse.lines = 6 * frames;  // text protocol: P1..P3, T1..T3
  s.parse.frames = frames;
  s.published = frames;
  return s;
}

std::string value(const DriverHealth::Check& c, const std::string& key) {
  for (const auto& [k, v] : c.values) {
    if (k == key) return v;
  }
  return "<missing>";
}

TEST(DriverHealth, StreamingIsOk) {
  DriverHealth h{DriverHealth::Params{}};
  auto c = h.update(streaming(50), 0.01);
  EXPECT_EQ(c.level, Level::kOk) << c.message;
  c = h.update(streaming(100), 0.02);
  EXPECT_EQ(c.level, Level::kOk) << c.message;
  EXPECT_EQ(value(c, "samples_in_period"), "50");
  EXPECT_EQ(value(c, "lines_in_period"), "300");
}

TEST(DriverHealth, StallWarnsThenErrs) {
  DriverHealth h{DriverHealth::Params{}};  // 0.1 s WARN, 1.0 s ERROR
  h.update(streaming(50), 0.01);
  auto c = h.update(streaming(50), 0.5);
  EXPECT_EQ(c.level, Level::kWarn);
  EXPECT_NE(c.message.find("late: no sample for 0.50 s > stall_warn_s 0.10 s"), std::string::npos) << c.message;
  c = h.update(streaming(50), 1.5);
  EXPECT_EQ(c.level, Level::kError);
  EXPECT_NE(c.message.find("stalled: no sample for 1.50 s"), std::string::npos) << c.message;
  // Never a sample (NaN age): stalled.
  DriverHealth fresh{DriverHealth::Params{}};
  EXPECT_EQ(fresh.update(WhiskerDriverLogic::Stats{}, std::numeric_limits<double>::quiet_NaN()).level, Level::kError);
}

TEST(DriverHealth, DeviceGoneNeedsErrorsAndAStall) {
  DriverHealth h{DriverHealth::Params{}};
  auto s = streaming(50);
  h.update(s, 0.01);
  s.source_errors = 1;  // a hang-up, the source reopened it and samples flow again
  EXPECT_EQ(h.update(s, 0.02).level, Level::kOk);
  s.source_errors = 3;  // reopen failed twice, nothing since
  const auto c = h.update(s, 2.0);
  EXPECT_EQ(c.level, Level::kError);
  EXPECT_NE(c.message.find("device gone: 2 device error(s) and no sample for 2.0 s"), std::string::npos) << c.message;
  EXPECT_EQ(value(c, "device_errors"), "3");
}

TEST(DriverHealth, FrameErrorsAsAFractionOfThePeriod) {
  DriverHealth h{DriverHealth::Params{}};  // 1 % WARN, 10 % ERROR
  auto s = streaming(50);
  h.update(s, 0.01);
  s = streaming(100);
  s.parse.malformed_lines = 6;  // 6 of 300 lines in this period: 2 %
  auto c = h.update(s, 0.01);
  EXPECT_EQ(c.level, Level::kWarn);
  EXPECT_NE(c.message.find("frame errors: 6 of 300 lines dropped > frame_error_warn 0.01"), std::string::npos)
      << c.message;
  s = streaming(150);
  s.parse.malformed_lines = 6;  // none new: OK again
  EXPECT_EQ(h.update(s, 0.01).level, Level::kOk);
  s = streaming(200);
  s.parse.malformed_lines = 6 + 20;
  s.parse.invalid_frames = 20;  // 40 of 300: 13 %
  c = h.update(s, 0.01);
  EXPECT_EQ(c.level, Level::kError) << c.message;
  EXPECT_EQ(value(c, "dropped_in_period"), "40");
}

TEST(DriverHealth, ParametersValidatedWithTheirNames) {
  auto m = DriverHealth::default_parameters();
  m.set("stall_error_s", 0.05);
  try {
    DriverHealth::params_from(m);
    FAIL() << "stall_error_s below stall_warn_s accepted";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("stall_warn_s (0.100000) must be below stall_error_s (0.050000)"),
              std::string::npos)
        << e.what();
  }
  m = DriverHealth::default_parameters();
  m.set("frame_error_error", 2.0);
  EXPECT_THROW(DriverHealth::params_from(m), tactile_common::ParamError);
}

TEST(DriverHealth, RepositoryConfigIsTheDefaults) {
  const auto p = DriverHealth::params_from(tactile_common::load_node_parameters(
      TACTILE_CONFIG_DIR "/whisker_driver_health.yaml", "/whisker/left/whisker_driver", DriverHealth::default_parameters()));
  const DriverHealth::Params d;
  EXPECT_EQ(p.diagnostics_period_s, d.diagnostics_period_s);
  EXPECT_EQ(p.stall_warn_s, d.stall_warn_s);
  EXPECT_EQ(p.stall_error_s, d.stall_error_s);
  EXPECT_EQ(p.frame_error_warn, d.frame_error_warn);
  EXPECT_EQ(p.frame_error_error, d.frame_error_error);
}

// The parameter spec: every key described, no described range wider than what
// params_from()/validate() accept, none live (read at configure).
TEST(DriverHealth, EveryParameterIsDescribedWithTheRangeValidateAcceptsAndNoneIsLive) {
  const tactile_common::ParamMap d = DriverHealth::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { DriverHealth::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  for (const auto& [key, info] : d.infos()) EXPECT_FALSE(info.live) << key;
}

}  // namespace
}  // namespace whisker_driver
