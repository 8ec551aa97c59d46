// Node logic tests: parameters, message mapping and bad-input handling.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
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
  EXPECT_EQ(p.max_sample_gap_s, 5.0);
  EXPECT_EQ(p.clock.nominal_period_s, 0.02);  // 000: 50 Hz
  EXPECT_EQ(p.clock.tolerance_s, 0.1);
  EXPECT_EQ(p.clock.max_late_samples, 50);
  EXPECT_EQ(p.clock.step_samples, 25);
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
  EXPECT_EQ(p.clock.nominal_period_s, d.clock.nominal_period_s);
  EXPECT_EQ(p.clock.tolerance_s, d.clock.tolerance_s);
  // The workspace extensions the repository runs with (README "Sustained contact").
  EXPECT_EQ(p.tdorc.learn_delay, 10);
  EXPECT_TRUE(p.tdorc.contact_hold);
  EXPECT_EQ(p.tdorc.max_contact_hold, 1000);
  EXPECT_EQ(p.tdorc.hold_release_fraction, 0.1);
  EXPECT_EQ(p.tdorc.hold_release_samples, 3);
  EXPECT_EQ(p.tdorc.hold_release_drop, 0.25);
  EXPECT_EQ(p.tdorc.hold_level_samples, 50);
  EXPECT_EQ(p.tdorc.max_drift_slope, 0.5);
  EXPECT_EQ(p.tdorc.hold_quiet_rms, 0.0);  // issue 17: measured, not switched on (README)
  EXPECT_EQ(p.tdorc.hold_quiet_samples, 25);
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
  m.set("hold_quiet_samples", int64_t{1});
  EXPECT_NE(param_error(m).find("hold_quiet_samples: must be in [2, 10000], got 1"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("hold_quiet_rms", -1.0);
  EXPECT_NE(param_error(m).find("hold_quiet_rms: must be finite and >= 0"), std::string::npos);

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
  m.set("stamp_tolerance_s", -1.0);
  EXPECT_NE(param_error(m).find("stamp_tolerance_s: must be in (0, 60], got -1"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("clock_step_samples", int64_t{1});
  EXPECT_NE(param_error(m).find("clock_step_samples: must be in [2, 1000000], got 1"), std::string::npos);

  m = TdorcFilterLogic::default_parameters();
  m.set("window", std::string("100"));  // wrong type
  EXPECT_NE(param_error(m).find("window"), std::string::npos);
}

// Every integer parameter set to its default + 2^32, which static_cast<int>
// turns back into the default, is rejected with its key and the value as given.
TEST(TdorcFilterLogic, IntegerParametersAreCheckedBeforeTheyAreNarrowed) {
  const auto wrapped = tactile_common::wrapped_integers(TdorcFilterLogic::default_parameters(),
                                                        [](const ParamMap& m) { TdorcFilterLogic::params_from(m); });
  EXPECT_EQ(wrapped.size(), 8u);  // window ... clock_step_samples
  for (const auto& [key, w] : wrapped) EXPECT_TRUE(w.rejected_as_given()) << key << ": " << w.error;
}

// The parameter spec: every key described, and no described range wider than what
// params_from()/validate() accept (ros2 param describe shows what the node takes).
TEST(TdorcFilterLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  const ParamMap d = TdorcFilterLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  for (const auto& leak : tactile_common::range_leaks(d, [](const ParamMap& m) { TdorcFilterLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  ASSERT_NE(d.info("window"), nullptr);
  EXPECT_EQ(d.info("window")->range->text(), "[2, 100000]");
  EXPECT_EQ(d.info("contact_threshold")->unit, "Pa");
  std::vector<std::string> live;
  for (const auto& [key, info] : d.infos()) {
    if (info.live) live.push_back(key);
  }
  EXPECT_EQ(live, std::vector<std::string>{"contact_threshold"});
}

// contact_threshold applies from the next sample on, the drift window kept: the +400 Pa
// sample of FillsEverySignalField (S_p = 22.56) is a contact at T_c = 20, none at 25.
TEST(TdorcFilterLogic, LiveContactThresholdAppliesFromTheNextSample) {
  ParamMap m = TdorcFilterLogic::default_parameters();
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(m));
  for (int k = 0; k <= 100; ++k) ASSERT_TRUE(logic.on_pressure(pressure(k)));
  m.set("contact_threshold", 25.0);
  logic.set_params(TdorcFilterLogic::params_from(m));
  EXPECT_EQ(logic.params().tdorc.contact_threshold, 25.0);
  EXPECT_EQ(logic.whisker().params().contact_threshold, 25.0);
  const auto s = logic.on_pressure(pressure(101, WhiskerPressure::WHISKER_LEFT, 400.0));
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->compensated[1], 22.56, 1e-6);  // same filter state
  EXPECT_FALSE(s->contact);
  EXPECT_EQ(s->window_fill, 100u);
}

// Every other field is read at start: a change of one is refused and nothing changes.
TEST(TdorcFilterLogic, SetParamsRefusesAChangeOfAKeyThatIsNotLive) {
  ParamMap m = TdorcFilterLogic::default_parameters();
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(m));
  for (const auto& [key, value] : std::vector<std::pair<std::string, tactile_common::ParamValue>>{
           {"window", int64_t{50}}, {"max_sample_gap_s", 1.0}, {"sample_period_s", 0.01}, {"mode", std::string("tdoc")}}) {
    ParamMap changed = m;
    changed.set("contact_threshold", 30.0);
    changed.set(key, value);
    try {
      logic.set_params(TdorcFilterLogic::params_from(changed));
      ADD_FAILURE() << key << " changed while running";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("only contact_threshold may change"), std::string::npos) << e.what();
    }
    EXPECT_EQ(logic.params().tdorc.contact_threshold, 20.0) << key;
  }
  // An invalid live value is refused by validate(): absolute_threshold needs T_c >= 0.
  m.set("absolute_threshold", true);
  TdorcFilterLogic absolute(TdorcFilterLogic::params_from(m));
  auto p = absolute.params();
  p.tdorc.contact_threshold = -1.0;
  EXPECT_THROW(absolute.set_params(p), std::invalid_argument);
  EXPECT_EQ(absolute.whisker().params().contact_threshold, 20.0);
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

TEST(TdorcFilterLogic, DropsWrongWhiskerDuplicateAndLate) {
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters()));
  ASSERT_TRUE(logic.on_pressure(pressure(0, WhiskerPressure::WHISKER_RIGHT)));
  EXPECT_FALSE(logic.on_pressure(pressure(1, WhiskerPressure::WHISKER_LEFT)));  // latched right
  EXPECT_FALSE(logic.on_pressure(pressure(2, 7)));                             // unknown id
  EXPECT_EQ(logic.stats().dropped_wrong_whisker, 2u);
  ASSERT_TRUE(logic.on_pressure(pressure(3, WhiskerPressure::WHISKER_RIGHT)));
  EXPECT_FALSE(logic.on_pressure(pressure(3, WhiskerPressure::WHISKER_RIGHT)));  // same sequence and stamp
  EXPECT_FALSE(logic.on_pressure(pressure(1, WhiskerPressure::WHISKER_RIGHT)));  // sequence behind: late
  EXPECT_EQ(logic.stats().dropped_duplicate, 1u);
  EXPECT_EQ(logic.stats().dropped_late, 1u);
  EXPECT_EQ(logic.stats().dropped_out_of_order, 2u);
  // Sequence 0 -> 3 skipped two numbers: counted once, sample kept, and the
  // sample index advanced over the two missing periods (0, then 3).
  EXPECT_EQ(logic.stats().sequence_gaps, 1u);
  EXPECT_EQ(logic.stats().samples_missing, 2u);
  EXPECT_EQ(logic.whisker().samples(), 4);
}

TEST(TdorcFilterLogic, GapUpToMaxSampleGapIsBridgedLongerResets) {
  TdorcFilterLogic logic(TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters()));
  for (int k = 0; k < 150; ++k) ASSERT_TRUE(logic.on_pressure(pressure(k)));
  ASSERT_TRUE(logic.whisker().channel(0).ready());
  // 248 missing samples (4.98 s gap): bridged, the filter stays ready.
  auto s = logic.on_pressure(pressure(150 + 248));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->calibrated_ready);
  EXPECT_EQ(logic.stats().resets_on_gap, 0u);
  EXPECT_EQ(logic.stats().gaps_bridged, 1u);
  EXPECT_EQ(logic.whisker().samples(), 399);
  // 251 missing samples (5.04 s): reset, the window refills.
  s = logic.on_pressure(pressure(398 + 252));
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->calibrated_ready);
  EXPECT_EQ(s->window_fill, 1u);
  EXPECT_EQ(logic.stats().resets_on_gap, 1u);
}

// ---------------------------------------------------------------- time faults
// Each bad-stamp case against the clean stream (README "Time"). The input is a
// noise-free drift ramp (pressure(k): +0.02 Pa and -0.01 Pa per sample), on
// which TDORC's outputs are S_c = S_p = 0 once ready; a sample index that
// lost track of time by one sample would give S_c = 0.02 Pa on channel 0.

namespace {

struct Arrival {
  WhiskerPressure msg;
  int64_t receive_ns;
};

std::vector<Arrival> clean_stream(int n) {
  std::vector<Arrival> s;
  for (int k = 0; k < n; ++k) s.push_back({pressure(k), 1000000000LL + k * kStepNs});
  return s;
}

std::vector<std::optional<WhiskerSignal>> feed(TdorcFilterLogic& l, const std::vector<Arrival>& s, bool receive = true) {
  std::vector<std::optional<WhiskerSignal>> out;
  for (const auto& a : s) out.push_back(l.on_pressure(a.msg, receive ? std::optional<int64_t>(a.receive_ns) : std::nullopt));
  return out;
}

TdorcFilterLogic::Params paper_params() {
  return TdorcFilterLogic::params_from(TdorcFilterLogic::default_parameters());
}

/// Output of sample `seq` in `out` (nullptr if none).
const WhiskerSignal* find_seq(const std::vector<std::optional<WhiskerSignal>>& out,
                              const std::vector<Arrival>& in, uint32_t seq) {
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] && in[i].msg.sequence == seq) return &*out[i];
  }
  return nullptr;
}

/// Every output of the faulty run equals the clean run's output of the same
/// sample (stamp, S_c, S_p, contact), within 1e-9 Pa.
void expect_same_as_clean(const std::vector<std::optional<WhiskerSignal>>& clean, const std::vector<Arrival>& clean_in,
                          const std::vector<std::optional<WhiskerSignal>>& faulty, const std::vector<Arrival>& faulty_in) {
  for (size_t i = 0; i < faulty.size(); ++i) {
    if (!faulty[i]) continue;
    const WhiskerSignal* c = find_seq(clean, clean_in, faulty_in[i].msg.sequence);
    ASSERT_NE(c, nullptr) << i;
    EXPECT_EQ(tactile_common::from_stamp(faulty[i]->header.stamp), tactile_common::from_stamp(c->header.stamp)) << i;
    EXPECT_EQ(faulty[i]->calibrated_ready, c->calibrated_ready) << i;
    EXPECT_EQ(faulty[i]->contact, c->contact) << i;
    for (size_t ch = 0; ch < 3; ++ch) {
      EXPECT_NEAR(faulty[i]->calibrated[ch], c->calibrated[ch], 1e-9) << i << " ch " << ch;
      EXPECT_NEAR(faulty[i]->compensated[ch], c->compensated[ch], 1e-9) << i << " ch " << ch;
    }
  }
}

}  // namespace

TEST(TdorcFilterLogicTime, StampTwentySecondsAheadOrBehindCostsNoSample) {
  for (const int64_t jump : {20000000000LL, -20000000000LL}) {
    for (const bool receive : {true, false}) {  // without receive time the sequence decides
      TdorcFilterLogic clean(paper_params()), faulty(paper_params());
      const auto in = clean_stream(400);
      auto bad = in;
      tactile_common::to_stamp(tactile_common::from_stamp(bad[200].msg.header.stamp) + jump, bad[200].msg.header.stamp);
      const auto a = feed(clean, in, receive);
      const auto b = feed(faulty, bad, receive);
      for (size_t i = 0; i < b.size(); ++i) ASSERT_TRUE(b[i]) << i;  // nothing dropped
      expect_same_as_clean(a, in, b, bad);
      // The repaired stamp is the clean one: t0 + 200 T.
      EXPECT_EQ(tactile_common::from_stamp(b[200]->header.stamp), 1000000000LL + 200 * kStepNs);
      const auto& s = faulty.stats();
      EXPECT_EQ(jump > 0 ? s.stamps_repaired_ahead : s.stamps_repaired_behind, 1u);
      EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind, 1u);
      EXPECT_EQ(s.published, 400u);
      EXPECT_EQ(s.dropped_out_of_order + s.resets_on_gap + s.gaps_bridged + s.clock_steps, 0u);
    }
  }
}

TEST(TdorcFilterLogicTime, TwoSwappedSamplesCostTheLateOneAndKeepTheTimeIndex) {
  TdorcFilterLogic clean(paper_params()), faulty(paper_params());
  const auto in = clean_stream(400);
  auto bad = in;
  std::swap(bad[200].msg, bad[201].msg);  // receive times stay in order
  const auto a = feed(clean, in);
  const auto b = feed(faulty, bad);
  ASSERT_TRUE(b[200]);   // sample 201 first: used, one sample period missing
  EXPECT_FALSE(b[201]);  // sample 200 after it: late, dropped
  expect_same_as_clean(a, in, b, bad);
  const auto& s = faulty.stats();
  EXPECT_EQ(s.dropped_late, 1u);
  EXPECT_EQ(s.dropped_out_of_order, 1u);
  EXPECT_EQ(s.gaps_bridged, 1u);
  EXPECT_EQ(s.samples_missing, 1u);
  EXPECT_EQ(s.published, 399u);
  EXPECT_EQ(faulty.whisker().samples(), clean.whisker().samples());  // 400: the index kept the time
}

TEST(TdorcFilterLogicTime, DuplicateIsDropped) {
  TdorcFilterLogic clean(paper_params()), faulty(paper_params());
  const auto in = clean_stream(400);
  auto bad = in;
  bad.insert(bad.begin() + 201, {in[200].msg, in[200].receive_ns + 1000000});
  const auto a = feed(clean, in);
  const auto b = feed(faulty, bad);
  EXPECT_FALSE(b[201]);
  expect_same_as_clean(a, in, b, bad);
  EXPECT_EQ(faulty.stats().dropped_duplicate, 1u);
  EXPECT_EQ(faulty.stats().published, 400u);
}

TEST(TdorcFilterLogicTime, TwoSecondGapIsBridgedByTheSampleIndex) {
  TdorcFilterLogic clean(paper_params()), faulty(paper_params());
  const auto in = clean_stream(400);
  auto bad = in;
  bad.erase(bad.begin() + 200, bad.begin() + 300);  // 2 s: 100 samples never arrive
  const auto a = feed(clean, in);
  const auto b = feed(faulty, bad);
  for (size_t i = 0; i < b.size(); ++i) ASSERT_TRUE(b[i]) << i;
  // After the gap the drift line, extrapolated over the 100 missing indices,
  // is exact: S_c = S_p = 0 as in the clean run (without the index advance
  // S_c of channel 0 would be 100 * 0.02 = 2 Pa).
  expect_same_as_clean(a, in, b, bad);
  EXPECT_TRUE(b[200]->calibrated_ready);
  const auto& s = faulty.stats();
  EXPECT_EQ(s.gaps_bridged, 1u);
  EXPECT_EQ(s.samples_missing, 100u);
  EXPECT_EQ(s.resets_on_gap, 0u);
  EXPECT_EQ(s.sequence_gaps, 1u);
  EXPECT_EQ(faulty.whisker().samples(), 400);
}

TEST(TdorcFilterLogicTime, StreamDeliveredLateInABurstIsInOrder) {
  TdorcFilterLogic clean(paper_params()), faulty(paper_params());
  const auto in = clean_stream(400);
  auto bad = in;
  for (int k = 200; k < 300; ++k) bad[static_cast<size_t>(k)].receive_ns = in[300].receive_ns;  // stalled, then a burst
  const auto a = feed(clean, in);
  const auto b = feed(faulty, bad);
  expect_same_as_clean(a, in, b, bad);
  const auto& s = faulty.stats();
  EXPECT_EQ(s.published, 400u);
  EXPECT_EQ(s.stamps_repaired_ahead + s.stamps_repaired_behind + s.gaps_bridged + s.dropped_out_of_order, 0u);
}

TEST(TdorcFilterLogicTime, GapLongerThanMaxSampleGapResets) {
  TdorcFilterLogic faulty(paper_params());  // max_sample_gap_s = 5 s
  auto bad = clean_stream(700);
  bad.erase(bad.begin() + 200, bad.begin() + 500);  // 6 s
  const auto b = feed(faulty, bad);
  ASSERT_TRUE(b[200]);
  EXPECT_FALSE(b[200]->calibrated_ready);
  EXPECT_EQ(b[200]->window_fill, 1u);
  EXPECT_EQ(faulty.stats().resets_on_gap, 1u);
  EXPECT_EQ(faulty.stats().gaps_bridged, 0u);
}
