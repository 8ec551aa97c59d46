// SampleClock: each bad-stamp case against a hand-computed decision.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "tactile_common/sample_clock.hpp"

using tactile_common::SampleClock;
using tactile_common::SampleClockParams;
using tactile_common::SampleDecision;
using tactile_common::SampleKind;

namespace {

constexpr int64_t kT = 20000000;  // 50 Hz
constexpr int64_t kT0 = 1000000000;

struct Sample {
  uint32_t seq;
  int64_t stamp;
  int64_t receive;
};

/// Clean stream of n samples, sample k stamped and received at kT0 + k T.
std::vector<Sample> clean(int n) {
  std::vector<Sample> s;
  for (int k = 0; k < n; ++k) s.push_back({static_cast<uint32_t>(k), kT0 + k * kT, kT0 + k * kT});
  return s;
}

std::vector<SampleDecision> run(SampleClock& c, const std::vector<Sample>& s, bool with_receive = true) {
  std::vector<SampleDecision> out;
  for (const auto& x : s) {
    out.push_back(c.classify(x.seq, x.stamp, with_receive ? std::optional<int64_t>(x.receive) : std::nullopt));
  }
  return out;
}

}  // namespace

TEST(SampleClock, CleanStreamIsInOrder) {
  SampleClock c;
  const auto d = run(c, clean(10));
  EXPECT_EQ(d[0].kind, SampleKind::kFirst);
  for (int k = 1; k < 10; ++k) {
    EXPECT_EQ(d[k].kind, SampleKind::kInOrder);
    EXPECT_EQ(d[k].stamp_ns, kT0 + k * kT);
    EXPECT_EQ(d[k].elapsed_ns, kT);
    EXPECT_EQ(d[k].missing, 0);
  }
  EXPECT_EQ(c.stats().in_order, 10u);
}

TEST(SampleClock, StampTwentySecondsAheadIsRepairedAndCostsNoSample) {
  for (bool rx : {true, false}) {
    SampleClock c;
    auto s = clean(10);
    s[5].stamp += 20000000000LL;
    const auto d = run(c, s, rx);
    // Sequence (+1) and receive time (+20 ms) agree; the stamp alone is off:
    // replaced by t4 + T = the clean stamp of sample 5.
    EXPECT_EQ(d[5].kind, SampleKind::kRepairedAhead);
    EXPECT_TRUE(d[5].accept);
    EXPECT_EQ(d[5].stamp_ns, kT0 + 5 * kT);
    for (int k = 6; k < 10; ++k) {
      EXPECT_EQ(d[k].kind, SampleKind::kInOrder) << k;
      EXPECT_EQ(d[k].stamp_ns, kT0 + k * kT) << k;
    }
    EXPECT_EQ(c.stats().repaired_ahead, 1u);
    EXPECT_EQ(c.stats().in_order, 9u);
  }
}

TEST(SampleClock, StampTwentySecondsBehindIsRepaired) {
  SampleClock c;
  auto s = clean(10);
  s[5].stamp -= 20000000000LL;
  const auto d = run(c, s);
  EXPECT_EQ(d[5].kind, SampleKind::kRepairedBehind);
  EXPECT_EQ(d[5].stamp_ns, kT0 + 5 * kT);
  EXPECT_EQ(d[6].kind, SampleKind::kInOrder);
  EXPECT_EQ(c.stats().repaired_behind, 1u);
}

TEST(SampleClock, TwoSwappedSamplesCostTheLateOne) {
  SampleClock c;
  auto s = clean(10);
  std::swap(s[4].seq, s[5].seq);
  std::swap(s[4].stamp, s[5].stamp);  // receive times stay in bag order
  const auto d = run(c, s);
  // Sample 5 arrives first: two sequence steps and two periods, one missing.
  EXPECT_EQ(d[4].kind, SampleKind::kInOrder);
  EXPECT_EQ(d[4].stamp_ns, kT0 + 5 * kT);
  EXPECT_EQ(d[4].missing, 1);
  // Sample 4 after it: late, dropped.
  EXPECT_EQ(d[5].kind, SampleKind::kLate);
  EXPECT_FALSE(d[5].accept);
  EXPECT_EQ(d[6].kind, SampleKind::kInOrder);
  EXPECT_EQ(d[6].missing, 0);
  EXPECT_EQ(c.stats().late, 1u);
  EXPECT_EQ(c.stats().gaps, 1u);
  EXPECT_EQ(c.stats().missing, 1u);
}

TEST(SampleClock, DuplicateIsDropped) {
  SampleClock c;
  auto s = clean(10);
  s.insert(s.begin() + 6, Sample{5, kT0 + 5 * kT, kT0 + 5 * kT + 1000});
  const auto d = run(c, s);
  EXPECT_EQ(d[6].kind, SampleKind::kDuplicate);
  EXPECT_FALSE(d[6].accept);
  EXPECT_EQ(d[7].kind, SampleKind::kInOrder);
  EXPECT_EQ(d[7].stamp_ns, kT0 + 6 * kT);
  EXPECT_EQ(c.stats().duplicates, 1u);
}

TEST(SampleClock, TwoSecondStallIsAGapWhetherSamplesAreLostOrTheSourcePaused) {
  // Lost: samples 5..104 never arrive (sequence, stamp and receive time jump 2 s).
  {
    SampleClock c;
    auto s = clean(110);
    s.erase(s.begin() + 5, s.begin() + 105);
    const auto d = run(c, s);
    EXPECT_EQ(d[5].kind, SampleKind::kInOrder);
    EXPECT_EQ(d[5].elapsed_ns, 101 * kT);
    EXPECT_EQ(d[5].missing, 100);
    EXPECT_EQ(c.stats().gaps, 1u);
    EXPECT_EQ(c.stats().missing, 100u);
  }
  // Paused: the sequence goes on by one, stamp and receive time jump 2 s:
  // the two clocks agree, the stamp is kept and 99 periods are missing.
  {
    SampleClock c;
    auto s = clean(10);
    for (int k = 5; k < 10; ++k) s[k].stamp += 2000000000, s[k].receive += 2000000000;
    const auto d = run(c, s);
    EXPECT_EQ(d[5].kind, SampleKind::kInOrder);
    EXPECT_EQ(d[5].stamp_ns, kT0 + 5 * kT + 2000000000);
    EXPECT_EQ(d[5].missing, 100);
  }
  // Delivered late in a burst: stamps and sequence continuous, receive time
  // stalls; the stamp agrees with the sequence: nothing missing.
  {
    SampleClock c;
    auto s = clean(10);
    for (int k = 5; k < 10; ++k) s[k].receive = kT0 + 4 * kT + 2000000000;
    const auto d = run(c, s);
    for (int k = 5; k < 10; ++k) {
      EXPECT_EQ(d[k].kind, SampleKind::kInOrder) << k;
      EXPECT_EQ(d[k].missing, 0) << k;
    }
  }
}

TEST(SampleClock, PersistentForwardStepIsTakenAfterStepSamples) {
  SampleClockParams p;
  p.step_samples = 5;
  SampleClock c(p);
  auto s = clean(20);
  for (int k = 5; k < 20; ++k) s[k].stamp += 20000000000LL;
  const auto d = run(c, s);
  for (int k = 5; k < 9; ++k) {
    EXPECT_EQ(d[k].kind, SampleKind::kRepairedAhead) << k;
    EXPECT_EQ(d[k].stamp_ns, kT0 + k * kT) << k;
  }
  EXPECT_EQ(d[9].kind, SampleKind::kClockStep);
  EXPECT_EQ(d[9].stamp_ns, s[9].stamp);
  EXPECT_EQ(d[9].missing, 0);  // the trusted elapsed time is one period
  for (int k = 10; k < 20; ++k) EXPECT_EQ(d[k].kind, SampleKind::kInOrder) << k;
  EXPECT_EQ(c.stats().clock_steps, 1u);
}

TEST(SampleClock, SequenceRestartIsKept) {
  SampleClock c;
  auto s = clean(300);
  for (int k = 200; k < 300; ++k) s[k].seq = static_cast<uint32_t>(k - 200);
  const auto d = run(c, s);
  EXPECT_TRUE(d[200].accept);
  EXPECT_TRUE(d[200].restart);
  EXPECT_EQ(d[200].kind, SampleKind::kInOrder);
  EXPECT_EQ(d[201].kind, SampleKind::kInOrder);
  EXPECT_EQ(c.stats().restarts, 1u);
}

TEST(SampleClock, PeriodIsEstimatedFromTheStream) {
  SampleClock c;  // nominal 50 Hz, stream at 100 Hz
  std::vector<Sample> s;
  for (int k = 0; k < 200; ++k) s.push_back({static_cast<uint32_t>(k), kT0 + k * kT / 2, kT0 + k * kT / 2});
  // then 100 samples lost (1 s at 100 Hz)
  s.push_back({300, kT0 + 300 * kT / 2, kT0 + 300 * kT / 2});
  const auto d = run(c, s);
  EXPECT_NEAR(c.period_ns(), kT / 2, 1000);
  EXPECT_EQ(d.back().missing, 100);
}

TEST(SampleClock, ValidateNamesTheField) {
  SampleClockParams p;
  p.tolerance_s = 0.0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SampleClockParams.tolerance_s"), std::string::npos);
  }
}
