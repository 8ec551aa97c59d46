// Node logic tests: parameters, message mapping and bad-input handling.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/parameters.hpp"
#include "tactile_common/time.hpp"
#include "tdorc_filter/tdorc_filter_logic.hpp"

using tactile_common::ParamError;
using tactile_common::ParamMap;
using tactile_msgs::msg::WhiskerPressure;
using tactile_msgs::msg::WhiskerSignal;
using tdorc_filter::TdorcFilterLogic;

namespace {

constexpr int64_t kStepNs = 20000000;  // 50 Hz

WhiskerPressure pressure(int k, uint8_t id = WhiskerPressure::WHISKER_LEFT, double bump = 0.0) {
  WhiskerPressure m;
  tactile_common::to_stamp(1000000000LL + k * kStepNs, m.header.stamp);
  m.header.frame_id = "whisker_left";
  m.whisker_id = id;
  m.pressure = {{100000.0 + 0.02 * k, 99500.0 - 0.01 * k + bump, 100800.0}};
  m.temperature = {{25.0, 25.0, std::nan("")}};
  m.sequence = static_cast<uint32_t>(k);
  return m;
}

std::string param_error(const ParamMap& m) {
  try {
    TdorcFilterLogic::params_from(m);
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(TdorcFilterLogic, DefaultsArePaperValues) {
  const auto p = TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters());
  EXPECT_EQ(p.tdorc.mode, tdorc_filter::Mode::kTdorc);
  EXPECT_EQ(p.tdorc.window, 100);
  EXPECT_EQ(p.tdorc.contact_threshold, 20.0);
  EXPECT_FALSE(p.tdorc.absolute_threshold);
  EXPECT_EQ(p.tdorc.learn_delay, 0);      // eq. 8 as written
  EXPECT_FALSE(p.tdorc.contact_hold);
  EXPECT_EQ(p.tdorc.bandpass_b, (std::array<double, 3>{{0.0564, 0.0, -0.0564}}));
  EXPECT_EQ(p.tdorc.bandpass_a, (std::array<double, 3>{{1.0, -1.8865, 0.8872}}));
  EXPECT_EQ(p.max_sample_gap_s, 0.5);
  EXPECT_STREQ(TdorcFilterLogic::kInputTopic, "pressure");
  EXPECT_STREQ(TdorcFilterLogic::kOutputTopic, "signal");
}

TEST(TdorcFilterLogic, RepositoryConfigIsPaperValuesPlusSustainedContact) {
  // The test runs in the package source directory.
  const ParamMap m = tactile_common::load_node_parameters("../../config/tdorc_filter.yaml", "/whisker/left/tdorc_filter",
                                                          TdorcFilterLogic::default_parameters());
  const auto p = TdorcFilterLogic::params_from(m);
  const auto d = TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters());
  EXPECT_EQ(p.tdorc.mode, d.tdorc.mode);
  EXPECT_EQ(p.tdorc.window, d.tdorc.window);
  EXPECT_EQ(p.tdorc.contact_threshold, d.tdorc.contact_threshold);
  EXPECT_EQ(p.tdorc.bandpass_b, d.tdorc.bandpass_b);
  EXPECT_EQ(p.tdorc.bandpass_a, d.tdorc.bandpass_a);
  EXPECT_EQ(p.max_sample_gap_s, d.max_sample_gap_s);
  // The workspace extensions the repository runs with (README "Sustained contact").
  EXPECT_EQ(p.tdorc.learn_delay, 10);
  EXPECT_TRUE(p.tdorc.contact_hold);
  EXPECT_EQ(p.tdorc.max_contact_hold, 1000);
  EXPECT_EQ(p.tdorc.hold_release_fraction, 0.1);
  EXPECT_EQ(p.tdorc.hold_release_samples, 3);
  EXPECT_EQ(p.tdorc.hold_release_drop, 0.25);
  EXPECT_EQ(p.tdorc.hold_level_samples, 50);
  EXPECT_EQ(p.tdorc.max_drift_slope, 0.5);
}

TEST(TdorcFilterLogic, ParameterErrorsNameTheKey) {
  ParamMap m = TdorcFilterLogic::default_parameters();
  m.set("mode", std::string("kalman"));
  EXPECT_NE(param_error(m).find("mode"), std::string::npos);
  EXPECT_NE(param_error(m).find("kalman"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("window", int64_t{1});
  EXPECT_NE(param_error(m).find("window"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("bandpass_b", std::vector<double>{0.0564, 0.0});
  EXPECT_NE(param_error(m).find("bandpass_b: must have 3 elements"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("bandpass_a", std::vector<double>{1.0, -2.0, 1.0});
  EXPECT_NE(param_error(m).find("bandpass_a: poles"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("hold_release_samples", int64_t{0});
  EXPECT_NE(param_error(m).find("hold_release_samples: must be in [1, 10000], got 0"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("hold_release_drop", 1.0);
  EXPECT_NE(param_error(m).find("hold_release_drop: must be in [0, 1), got 1"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("hold_level_samples", int64_t{0});
  EXPECT_NE(param_error(m).find("hold_level_samples: must be in [1, 100000], got 0"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("max_drift_slope", -0.5);
  EXPECT_NE(param_error(m).find("max_drift_slope: must be finite and >= 0, got -0.5"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("contact_threshold", std::nan(""));
  EXPECT_NE(param_error(m).find("contact_threshold: must be finite"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("max_sample_gap_s", 0.0);
  EXPECT_NE(param_error(m).find("max_sample_gap_s"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("window", std::string("100"));  // wrong type
  EXPECT_NE(param_error(m).find("window"), std::string::npos);
}

TEST(TdorcFilterLogic, FillsEverySignalField) {
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters()));
  std::optional<WhiskerSignal> s;
  for (int k = 0; k < 100; ++k) {
    s = logic.on_pressure(pressure(k));
    ASSERT_TRUE(s);
    EXPECT_FALSE(s->calibrated_ready);
    EXPECT_EQ(s->window_fill, static_cast<uint32_t>(k + 1));
    EXPECT_EQ(s->compensated[0], 0.0);
  }
  s = logic.on_pressure(pressure(100));
  ASSERT_TRUE(s);
  const auto in = pressure(100);
  EXPECT_EQ(s->header.stamp.sec, in.header.stamp.sec);
  EXPECT_EQ(s->header.stamp.nanosec, in.header.stamp.nanosec);
  EXPECT_EQ(s->header.frame_id, "whisker_left");
  EXPECT_EQ(s->whisker_id, WhiskerPressure::WHISKER_LEFT);
  EXPECT_EQ(s->mode, WhiskerSignal::MODE_TDORC);
  EXPECT_EQ(s->raw, in.pressure);
  EXPECT_TRUE(s->calibrated_ready);
  EXPECT_FALSE(s->contact);
  EXPECT_FALSE(s->drift_frozen);
  EXPECT_EQ(s->window_fill, 100u);
  // Exact lines: S_c = 0, slope a per channel, intercept at the window's first sample (k = 0).
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(s->calibrated[i], 0.0, 1e-9);
    EXPECT_NEAR(s->compensated[i], 0.0, 1e-9);
    EXPECT_FALSE(s->channel_contact[i]);
  }
  EXPECT_NEAR(s->drift_slope[0], 0.02, 1e-12);
  EXPECT_NEAR(s->drift_slope[1], -0.01, 1e-12);
  EXPECT_NEAR(s->drift_slope[2], 0.0, 1e-12);
  EXPECT_NEAR(s->drift_intercept[0], 100000.0, 1e-8);
  EXPECT_NEAR(s->drift_intercept[1], 99500.0, 1e-8);
  // Contact on channel 1: +400 Pa -> S_p = 22.56 > 20, drift frozen.
  s = logic.on_pressure(pressure(101, WhiskerPressure::WHISKER_LEFT, 400.0));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->contact);
  EXPECT_TRUE(s->channel_contact[1]);
  EXPECT_FALSE(s->channel_contact[0]);
  EXPECT_TRUE(s->drift_frozen);
  EXPECT_NEAR(s->compensated[1], 22.56, 1e-6);
  EXPECT_EQ(logic.stats().published, 102u);
}

TEST(TdorcFilterLogic, ModeConstantFollowsParameter) {
  ParamMap m = TdorcFilterLogic::default_parameters();
  m.set("mode", std::string("bandpass"));
  TdorcFilterLogic b(TdorcFilterLogic::params_from(m));
  auto s = b.on_pressure(pressure(0));
  ASSERT_TRUE(s);
  EXPECT_EQ(s->mode, WhiskerSignal::MODE_BANDPASS);
  EXPECT_TRUE(s->calibrated_ready);
  EXPECT_EQ(s->calibrated, s->raw);
  m.set("mode", std::string("tdoc"));
  TdorcFilterLogic o(TdorcFilterLogic::params_from(m));
  EXPECT_EQ(o.on_pressure(pressure(0))->mode, WhiskerSignal::MODE_TDOC);
}

TEST(TdorcFilterLogic, DropsNonFiniteSamplesWithoutTouchingState) {
  const auto params = TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters());
  TdorcFilterLogic clean(params), dirty(params);
  for (int k = 0; k < 300; ++k) {
    const auto a = clean.on_pressure(pressure(k));
    if (k % 7 == 3) {
      auto bad = pressure(k);
      bad.pressure[k % 3] = (k % 2) ? std::numeric_limits<double>::quiet_NaN()
                                    : -std::numeric_limits<double>::infinity();
      EXPECT_FALSE(dirty.on_pressure(bad));
    }
    const auto b = dirty.on_pressure(pressure(k));
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->calibrated, b->calibrated) << k;
    EXPECT_EQ(a->compensated, b->compensated) << k;
  }
  EXPECT_EQ(dirty.stats().dropped_nonfinite, 43u);  // k % 7 == 3 for k < 300
  EXPECT_EQ(dirty.stats().received, 343u);
  EXPECT_EQ(dirty.stats().published, 300u);
  EXPECT_EQ(clean.stats().dropped_nonfinite, 0u);
  // NaN temperature is allowed (sources without temperature report NaN).
  EXPECT_EQ(clean.stats().published, 300u);
}

TEST(TdorcFilterLogic, DropsWrongWhiskerAndOutOfOrder) {
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters()));
  ASSERT_TRUE(logic.on_pressure(pressure(0, WhiskerPressure::WHISKER_RIGHT)));
  EXPECT_FALSE(logic.on_pressure(pressure(1, WhiskerPressure::WHISKER_LEFT)));  // latched right
  EXPECT_FALSE(logic.on_pressure(pressure(2, 7)));                             // unknown id
  EXPECT_EQ(logic.stats().dropped_wrong_whisker, 2u);
  ASSERT_TRUE(logic.on_pressure(pressure(3, WhiskerPressure::WHISKER_RIGHT)));
  EXPECT_FALSE(logic.on_pressure(pressure(3, WhiskerPressure::WHISKER_RIGHT)));  // same stamp
  EXPECT_FALSE(logic.on_pressure(pressure(1, WhiskerPressure::WHISKER_RIGHT)));  // older
  EXPECT_EQ(logic.stats().dropped_out_of_order, 2u);
  EXPECT_EQ(logic.whisker().samples(), 2);
  // Sequence 0 -> 3 skipped two numbers: counted once, sample kept.
  EXPECT_EQ(logic.stats().sequence_gaps, 1u);
}

TEST(TdorcFilterLogic, GapResetsFilter) {
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters()));
  for (int k = 0; k < 150; ++k) ASSERT_TRUE(logic.on_pressure(pressure(k)));
  ASSERT_TRUE(logic.whisker().channel(0).ready());
  // 24 missing samples (0.5 s gap exactly): no reset.
  auto s = logic.on_pressure(pressure(150 + 24));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->calibrated_ready);
  EXPECT_EQ(logic.stats().resets_on_gap, 0u);
  // 26 missing samples (0.54 s): reset, the window refills.
  s = logic.on_pressure(pressure(174 + 27));
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->calibrated_ready);
  EXPECT_EQ(s->window_fill, 1u);
  EXPECT_EQ(logic.stats().resets_on_gap, 1u);
}
