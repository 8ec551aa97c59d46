// Core tests of TDORC (paper 000 eq. 4-11). Expected values are derived by
// hand from the equations in the comments next to them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "tdorc_filter/tdorc.hpp"

using tdorc_filter::BandpassBiquad;
using tdorc_filter::DriftFit;
using tdorc_filter::LineFit;
using tdorc_filter::Mode;
using tdorc_filter::Params;
using tdorc_filter::TdorcChannel;
using tdorc_filter::TdorcWhisker;
using tdorc_filter::WhiskerOutput;

namespace {

const std::array<double, 3> kB{{0.0564, 0.0, -0.0564}};
const std::array<double, 3> kA{{1.0, -1.8865, 0.8872}};

std::string error_of(const Params& p) {
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// ------------------------------------------------------------------ biquad

TEST(BandpassBiquad, ParamsDefaultsArePaperCoefficients) {
  const Params p;
  EXPECT_EQ(p.bandpass_b, kB);
  EXPECT_EQ(p.bandpass_a, kA);
  EXPECT_EQ(p.window, 100);
  EXPECT_EQ(p.contact_threshold, 20.0);
  EXPECT_FALSE(p.absolute_threshold);
  EXPECT_EQ(p.mode, Mode::kTdorc);
}

TEST(BandpassBiquad, ImpulseResponseByHand) {
  // Unit impulse, zero state, eq. 9-11 by hand:
  // k=0: S_p = b0 = 0.0564;  z0 = -a1*0.0564 = 0.1063986;  z1 = b2 - a2*0.0564 = -0.10643808
  // k=1: S_p = z0 = 0.1063986; z0 = 1.8865*0.1063986 - 0.10643808 = 0.0942828789;
  //      z1 = -0.8872*0.1063986 = -0.09439683792
  // k=2: S_p = 0.0942828789; z0 = 1.8865*0.0942828789 - 0.09439683792 = 0.08346781312...
  // k=3: S_p = 0.0834678131
  BandpassBiquad f(kB, kA);
  EXPECT_NEAR(f.step(1.0), 0.0564, 1e-12);
  EXPECT_NEAR(f.z0(), 0.1063986, 1e-12);
  EXPECT_NEAR(f.z1(), -0.10643808, 1e-12);
  EXPECT_NEAR(f.step(0.0), 0.1063986, 1e-12);
  EXPECT_NEAR(f.z1(), -0.09439683792, 1e-12);
  EXPECT_NEAR(f.step(0.0), 0.0942828789, 1e-12);
  EXPECT_NEAR(f.step(0.0), 0.0834678131, 1e-10);
}

TEST(BandpassBiquad, DcGainIsZero) {
  // H(1) = (b0 + b1 + b2) / (1 + a1 + a2) = 0: a step decays to 0.
  BandpassBiquad f(kB, kA);
  double y = 0.0;
  for (int k = 0; k < 20000; ++k) y = f.step(5.0);
  EXPECT_NEAR(y, 0.0, 1e-9);
}

TEST(BandpassBiquad, RampSteadyState) {
  // B(q) = 0.0564 (1 - q^2) = 0.0564 (1 - q)(1 + q), q = z^-1. A ramp x_k = c*k
  // differenced once is c, so the output settles at
  // c * 0.0564 * 2 / A(1) = c * 0.1128 / (1 - 1.8865 + 0.8872) = c * 161.142857...
  BandpassBiquad f(kB, kA);
  const double c = 0.01;
  double y = 0.0;
  for (int k = 0; k < 20000; ++k) y = f.step(c * k);
  EXPECT_NEAR(y, c * 0.1128 / 0.0007, 1e-8);
}

TEST(BandpassBiquad, SteadyStateInitGivesZeroForConstantInput) {
  BandpassBiquad f(kB, kA);
  f.init_steady_state(101325.0);
  // z1 = b2 x, z0 = b1 x + z1 (steady output 0): next output b0 x + z0 = 0.
  EXPECT_DOUBLE_EQ(f.z1(), -0.0564 * 101325.0);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(f.step(101325.0), 0.0);
}

// ------------------------------------------------------------------ least squares

TEST(DriftFit, ThreePointsByHand) {
  // t = 0,1,2; S = 0,1,5: sum t = 3, sum t^2 = 5, sum S = 6, sum tS = 11.
  // eq. 6: a = (3*11 - 3*6) / (3*5 - 9) = 15/6 = 2.5; eq. 7: b = (6 - 2.5*3)/3 = -0.5.
  DriftFit f(3);
  f.push(0, 0.0);
  f.push(1, 1.0);
  f.push(2, 5.0);
  ASSERT_TRUE(f.full());
  LineFit l = f.fit();
  EXPECT_NEAR(l.slope, 2.5, 1e-12);
  EXPECT_NEAR(l.intercept, -0.5, 1e-12);
  EXPECT_EQ(l.first_index, 0);
  // Slide: window S = 1,5,2 at t = 0,1,2: sum S = 8, sum tS = 9;
  // a = (27 - 24)/6 = 0.5, b = (8 - 1.5)/3 = 13/6 (at index 1).
  f.push(3, 2.0);
  l = f.fit();
  EXPECT_NEAR(l.slope, 0.5, 1e-12);
  EXPECT_NEAR(l.intercept, 13.0 / 6.0, 1e-12);
  EXPECT_EQ(l.first_index, 1);
  EXPECT_NEAR(l.at(4), 13.0 / 6.0 + 1.5, 1e-12);
}

TEST(DriftFit, GapKeepsTrueTimeIndex) {
  // Indices 0,1,5, S = 0,1,5: sum t = 6, sum t^2 = 26, sum S = 6, sum tS = 26;
  // a = (78 - 36)/(78 - 36) = 1, b = (6 - 6)/3 = 0.
  DriftFit f(3);
  f.push(0, 0.0);
  f.push(1, 1.0);
  f.push(5, 5.0);
  const LineFit l = f.fit();
  EXPECT_NEAR(l.slope, 1.0, 1e-12);
  EXPECT_NEAR(l.intercept, 0.0, 1e-12);
}

TEST(DriftFit, ExactLineGivesExactParameters) {
  DriftFit f(100);
  for (int k = 0; k < 250; ++k) f.push(k, 101325.0 + 0.02 * k);
  const LineFit l = f.fit();
  EXPECT_NEAR(l.slope, 0.02, 1e-12);
  EXPECT_EQ(l.first_index, 150);
  EXPECT_NEAR(l.intercept, 101325.0 + 0.02 * 150, 1e-9);
}

TEST(DriftFit, RunningSumsMatchTwoPassFitAfterMillionSamples) {
  // Running sums over 1e6 noisy samples (many wraps) versus a fresh two-pass
  // fit of the final window.
  const int n = 100;
  DriftFit f(n);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<double> last(n);
  const int total = 1000000;
  for (int k = 0; k < total; ++k) {
    const double v = 100000.0 + 1e-4 * k + 20.0 * std::sin(k * 1e-3) + noise(rng);
    f.push(k, v);
    if (k >= total - n) last[k - (total - n)] = v;
  }
  double mt = 0, my = 0;
  for (int i = 0; i < n; ++i) {
    mt += i;
    my += last[i];
  }
  mt /= n;
  my /= n;
  double sxy = 0, sxx = 0;
  for (int i = 0; i < n; ++i) {
    sxy += (i - mt) * (last[i] - my);
    sxx += (i - mt) * (i - mt);
  }
  const double a = sxy / sxx;
  const double b = my - a * mt;
  const LineFit l = f.fit();
  EXPECT_NEAR(l.slope, a, 1e-10);
  EXPECT_NEAR(l.intercept, b, 1e-8);
}

TEST(DriftFit, StateIsAllocatedOnce) {
  DriftFit f(100);
  const std::size_t before = f.state_size_bytes();
  for (int k = 0; k < 1000; ++k) f.push(k, 1.0 * k);
  EXPECT_EQ(f.state_size_bytes(), before);
  EXPECT_EQ(before, sizeof(DriftFit) + 100 * (sizeof(double) + sizeof(int64_t)));
}

// ------------------------------------------------------------------ channel / whisker

TEST(TdorcChannel, NotReadyUntilWindowFull) {
  Params p;
  p.window = 10;
  TdorcChannel c(p);
  for (int k = 0; k < 10; ++k) {
    const auto o = c.update(k, 1000.0 + k);
    EXPECT_FALSE(o.ready);
    EXPECT_EQ(o.calibrated, 0.0);
    EXPECT_EQ(o.compensated, 0.0);
    EXPECT_FALSE(o.contact);
  }
  // Fitted after the n-th sample; the first output is for sample n and
  // extrapolates the line (S_c = 1010 - (1*10 + 1000) = 0).
  EXPECT_EQ(c.fit_count(), 1u);
  const auto o = c.update(10, 1010.0);
  EXPECT_TRUE(o.ready);
  EXPECT_NEAR(o.calibrated, 0.0, 1e-9);
  EXPECT_NEAR(o.drift_slope, 1.0, 1e-12);
  EXPECT_NEAR(o.drift_intercept, 1000.0, 1e-9);
  EXPECT_EQ(c.fit_count(), 2u);
}

TEST(TdorcChannel, NoiseFreeRampIsCompensatedToZero) {
  for (Mode m : {Mode::kTdorc, Mode::kTdoc}) {
    Params p;
    p.mode = m;
    TdorcChannel c(p);
    for (int k = 0; k < 1000; ++k) {
      const auto o = c.update(k, 98000.0 + 0.05 * k);
      EXPECT_EQ(o.ready, k >= 100);
      if (k >= 100) {
        ASSERT_TRUE(o.ready);
        EXPECT_NEAR(o.calibrated, 0.0, 1e-9) << k;  // eq. 5 with the exact line
        EXPECT_NEAR(o.compensated, 0.0, 1e-9) << k;
        EXPECT_NEAR(o.drift_slope, 0.05, 1e-12);
      }
    }
  }
}

TEST(TdorcChannel, BandpassModePassesRawToFilter) {
  Params p;
  p.mode = Mode::kBandpass;
  TdorcChannel c(p);
  auto o = c.update(0, 101325.0);
  EXPECT_TRUE(o.ready);
  EXPECT_EQ(o.calibrated, 101325.0);  // S_c = S_r
  EXPECT_EQ(o.compensated, 0.0);      // steady-state start
  // A +100 Pa step: S_p jumps by b0 * 100 = 5.64.
  o = c.update(1, 101425.0);
  EXPECT_NEAR(o.compensated, 5.64, 1e-9);
  EXPECT_EQ(c.fit_count(), 0u);
}

namespace {
// Drifting whisker: ramp + contact bump on channel 1 between samples [300, 400).
std::array<double, 3> sample(int k, bool bump) {
  const double drift = 0.03 * k;
  const double b = bump ? 400.0 : 0.0;
  return {{100000.0 + drift, 99000.0 - drift + b, 101000.0 + 0.5 * drift}};
}
}  // namespace

TEST(TdorcWhisker, FreezesAllChannelsDuringContactAndRefitsAfter) {
  // 000 eq. 8: a sample in whisker contact (any channel) re-fits no channel;
  // a free-flight sample re-fits every channel.
  Params p;
  TdorcWhisker w(p);
  int first_contact = -1, last_contact = -1, contact_samples = 0;
  for (int k = 0; k < 1200; ++k) {
    std::array<uint64_t, 3> fits_before{};
    std::array<LineFit, 3> line_before{};
    for (int i = 0; i < 3; ++i) {
      fits_before[i] = w.channel(i).fit_count();
      line_before[i] = w.channel(i).line();
    }
    const auto o = w.update(sample(k, k >= 300 && k < 400));
    if (k < 100) continue;  // first window
    ASSERT_TRUE(o.ready);
    EXPECT_EQ(o.drift_frozen, o.contact) << k;
    for (int i = 0; i < 3; ++i) {
      if (o.contact) {
        EXPECT_EQ(w.channel(i).fit_count(), fits_before[i]) << k;
        EXPECT_EQ(w.channel(i).line().slope, line_before[i].slope) << k;
        EXPECT_EQ(w.channel(i).line().intercept, line_before[i].intercept) << k;
        EXPECT_EQ(w.channel(i).line().first_index, line_before[i].first_index) << k;
      } else {
        EXPECT_EQ(w.channel(i).fit_count(), fits_before[i] + 1) << k;
      }
    }
    if (o.contact) {
      if (first_contact < 0) first_contact = k;
      last_contact = k;
      ++contact_samples;
    }
  }
  // A 400 Pa step gives S_p = 0.0564 * 400 = 22.56 > 20 at once.
  ASSERT_EQ(first_contact, 300);
  ASSERT_GT(contact_samples, 1);
  ASSERT_LT(last_contact, 1100);
  // Long after contact the windows hold pure drift again: exact slopes.
  EXPECT_NEAR(w.channel(0).line().slope, 0.03, 1e-9);
  EXPECT_NEAR(w.channel(1).line().slope, -0.03, 1e-9);
  EXPECT_NEAR(w.channel(2).line().slope, 0.015, 1e-9);
}

TEST(TdorcWhisker, ContactOnsetNeverEntersTheWindow) {
  // The onset sample is judged before learning, so with a held +400 Pa the
  // frozen line extrapolates the pre-contact drift exactly: S_c = 400 while
  // the whisker stays in contact.
  Params p;
  TdorcWhisker w(p);
  for (int k = 0; k < 300; ++k) w.update(sample(k, false));
  const auto o = w.update(sample(300, true));
  ASSERT_TRUE(o.contact);
  EXPECT_TRUE(o.channel[1].contact);
  EXPECT_FALSE(o.channel[0].contact);
  EXPECT_NEAR(o.channel[1].calibrated, 400.0, 1e-6);
  EXPECT_NEAR(o.channel[1].compensated, 0.0564 * 400.0, 1e-6);
  EXPECT_NEAR(o.channel[0].calibrated, 0.0, 1e-6);
  const auto o2 = w.update(sample(301, true));
  ASSERT_TRUE(o2.contact);
  EXPECT_NEAR(o2.channel[1].calibrated, 400.0, 1e-6);
  EXPECT_NEAR(o2.channel[1].drift_slope, -0.03, 1e-9);
}

// ------------------------------------------------------ sustained contact

namespace {
// Drifting whisker pressed for samples [start, end) with a held +200 Pa on
// channel 1 (no other dynamics): the case the band-pass alone loses.
struct HeldRun {
  int first = -1, last = -1, samples = 0, held = 0;
  bool lost_while_pressed = false;  // a free sample inside [first, end)
  bool contact_after = false;       // contact at any sample >= end + 50
  double sc_at_onset = 0.0, max_abs_sc_after = 0.0;  // channel 1, after = [end, total)
};
/// The outputs of a drifting whisker (+-0.03 Pa/sample) whose channel 1 is
/// pushed by push(k) Pa at sample k, for samples [0, total).
std::vector<WhiskerOutput> run_pushed(const Params& p, int total, const std::function<double(int)>& push) {
  TdorcWhisker w(p);
  std::vector<WhiskerOutput> out;
  for (int k = 0; k < total; ++k) {
    const double drift = 0.03 * k;
    out.push_back(w.update({{100000.0 + drift, 99000.0 - drift + push(k), 101000.0}}));
  }
  return out;
}

/// Last sample in contact, -1 if none.
int last_contact(const std::vector<WhiskerOutput>& outs) {
  for (int k = static_cast<int>(outs.size()) - 1; k >= 0; --k) {
    if (outs[static_cast<size_t>(k)].contact) return k;
  }
  return -1;
}

/// The contact hold with a 10-sample learn delay (as in config/), the base of
/// the hold and release tests.
Params holding() {
  Params p;
  p.contact_hold = true;
  p.learn_delay = 10;
  return p;
}

HeldRun run_held(Params p, int start, int end, int total = 2000) {
  HeldRun r;
  const auto outs = run_pushed(p, total, [&](int k) { return (k >= start && k < end) ? 200.0 : 0.0; });
  for (int k = 0; k < total; ++k) {
    const auto& o = outs[static_cast<size_t>(k)];
    if (o.contact) {
      if (r.first < 0) r.sc_at_onset = o.channel[1].calibrated, r.first = k;
      r.last = k;
      ++r.samples;
      if (k >= end + 50) r.contact_after = true;
    } else if (r.first >= 0 && k < end) {
      r.lost_while_pressed = true;
    }
    if (o.contact_held) ++r.held;
    if (k >= end) r.max_abs_sc_after = std::max(r.max_abs_sc_after, std::fabs(o.channel[1].calibrated));
  }
  return r;
}
}  // namespace

TEST(TdorcWhisker, PaperRuleLosesAHeldContactAndThenLocks) {
  // 200 Pa step: S_p = 0.0564 * 200 = 11.3 < T_c at the step sample (which
  // therefore enters the window), over T_c from the next one, then decaying
  // with the high-pass pole 0.9935 (tau ~ 3 s): the paper's S_p > T_c flag
  // ends while the whisker is still pressed, the window learns pressed
  // samples, and after the release the frozen line keeps S_p over T_c (lock).
  Params p;  // paper defaults: no hold, no learn delay
  const HeldRun r = run_held(p, 300, 800);
  EXPECT_EQ(r.first, 301);
  EXPECT_TRUE(r.lost_while_pressed);
  EXPECT_TRUE(r.contact_after);
  EXPECT_EQ(r.held, 0);
}

TEST(TdorcWhisker, LearnDelayKeepsTheRisingEdgeOutOfTheWindow) {
  // The step sample (S_p = 11.3 < T_c) waits learn_delay samples; the onset
  // at the next sample discards it, so the frozen line is the exact drift:
  // S_c = 200 at the onset (instead of 192 with the step in the window).
  Params p;
  p.learn_delay = 10;
  const HeldRun r = run_held(p, 300, 800);
  EXPECT_EQ(r.first, 301);
  EXPECT_NEAR(r.sc_at_onset, 200.0, 1e-6);
  Params q;
  const HeldRun paper = run_held(q, 300, 800);
  // Without the delay the step sample tilts the 100-sample fit by
  // 200 * 49.5 / 83325 = 0.119 Pa/sample: S_c at the onset is ~192.
  EXPECT_LT(paper.sc_at_onset, 195.0);
}

TEST(TdorcWhisker, ContactHoldKeepsAPressedWhiskerInContactUntilRelease) {
  Params p = holding();
  const HeldRun r = run_held(p, 300, 800);
  EXPECT_EQ(r.first, 301);
  // Held (S_c = 200 > T_c against the exactly extrapolated drift) through the
  // last pressed sample, released at the first free one, no lock after.
  EXPECT_FALSE(r.lost_while_pressed);
  EXPECT_EQ(r.last, 799);
  EXPECT_EQ(r.samples, 499);
  EXPECT_EQ(r.held, 800 - 668);  // S_p alone holds it until sample 668 (see ContactHoldIsLimited)
  EXPECT_FALSE(r.contact_after);
  EXPECT_LT(r.max_abs_sc_after, 1e-6);
}

TEST(TdorcWhisker, ContactHoldIsLimited) {
  Params p = holding();
  p.max_contact_hold = 200;
  // Pressed for 1200 samples: S_p alone (decaying) keeps the contact until it
  // falls under T_c (sample 668, later than the 200-sample hold limit), then
  // the expired hold lets it go while the push goes on.
  const HeldRun r = run_held(p, 300, 1500);
  EXPECT_TRUE(r.lost_while_pressed);
  EXPECT_EQ(r.held, 0);
  p.max_contact_hold = 1000;
  const HeldRun longer = run_held(p, 300, 1500);
  EXPECT_TRUE(longer.lost_while_pressed);  // 1000 < 1199 pressed samples
  // The last held sample: onset + max_contact_hold - 1.
  const auto outs = run_pushed(p, 1500, [](int k) { return k >= 300 ? 200.0 : 0.0; });
  int last_held = -1;
  for (int k = 0; k < 1500; ++k) {
    if (outs[static_cast<size_t>(k)].contact_held) last_held = k;
  }
  EXPECT_EQ(longer.first + 999, last_held);
}

TEST(TdorcWhisker, HoldReleaseFractionEndsAHoldWhoseSignalCollapsed) {
  // Pressed with +200 Pa, then at sample 800 eased to +40 (still over T_c): a
  // partial retreat to 20 % of the peak. Fraction 0 keeps holding (S_c = 40 >
  // T_c); fraction 0.25 releases at once (40 < 50); fraction 0.1 keeps it.
  auto last_with = [](double fraction) {
    Params p = holding();
    p.hold_release_fraction = fraction;
    return last_contact(run_pushed(p, 1200, [](int k) { return k < 300 ? 0.0 : (k < 800 ? 200.0 : 40.0); }));
  };
  EXPECT_EQ(last_with(0.0), 1199);
  EXPECT_EQ(last_with(0.1), 1199);
  EXPECT_EQ(last_with(0.25), 799);
  Params bad;
  bad.hold_release_fraction = 1.0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
}

TEST(TdorcWhisker, HoldReleaseDropEndsAHoldOverAHysteresisOffset) {
  // Pressed with +200 Pa from sample 300 to 1099; after the release the gel
  // keeps +40 Pa (000 eq. 1, N_h), over T_c and over 0.1 of the peak, so the
  // hold of the previous rules lasts until max_contact_hold (onset 301 + 999).
  // With hold_release_drop 0.25 the whisker's S_c (here channel 1 alone, the
  // other two are exact lines) falls from its level 200 to 40 < 0.25 * level:
  // by hand the level is 196.8 after sample 1100 and 193.66 after 1101, still
  // over 160, so samples 1100, 1101 are held (hold_release_samples 3) and
  // 1102 is free.
  auto last_with = [](double drop, int level_samples) {
    Params p = holding();
    p.hold_release_fraction = 0.1;
    p.hold_release_samples = 3;
    p.hold_release_drop = drop;
    p.hold_level_samples = level_samples;
    return last_contact(run_pushed(p, 1600, [](int k) { return k < 300 ? 0.0 : (k < 1100 ? 200.0 : 40.0); }));
  };
  EXPECT_EQ(last_with(0.0, 50), 1300);
  EXPECT_EQ(last_with(0.25, 50), 1101);
  // A level that follows every sample (1) forgets the fall at once: only
  // sample 1100 is below, 1101 is over again (40 > 0.25 * 40), held to the limit.
  EXPECT_EQ(last_with(0.25, 1), 1300);
  EXPECT_EQ(last_with(0.15, 50), 1300);  // 40 > 0.15 * level: an offset of 20 % is not a release at 0.15
}

TEST(TdorcWhisker, HoldReleaseDropFollowsAGradualEaseOff) {
  // The level is a recent average, not the peak: a whisker eased off from
  // +200 to +40 Pa over 400 samples (the drone backing away) stays in
  // contact with hold_release_drop 0.25, and a quick fall from +200 to +40
  // within 5 samples is a release.
  auto last_with = [](int ramp) {
    Params p = holding();
    p.hold_release_samples = 3;
    p.hold_release_drop = 0.25;
    p.hold_level_samples = 50;
    return last_contact(run_pushed(p, 1600, [ramp](int k) {
      if (k < 300) return 0.0;
      if (k < 800) return 200.0;
      if (k < 800 + ramp) return 200.0 - 160.0 * (k - 800) / ramp;
      return k < 1250 ? 40.0 : 0.0;
    }));
  };
  EXPECT_EQ(last_with(400), 1251);  // held through the ease-off; released 2 samples after the push ends
  // By hand: level 193.73 after sample 804 (72 > 48.4 still over), 805 and
  // 806 below (40 < 48.4, < 47.7) and held, 807 free.
  EXPECT_EQ(last_with(5), 806);
  Params bad;
  bad.hold_release_drop = 1.0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
  bad.hold_release_drop = -0.1;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
  bad.hold_release_drop = 0.25;
  bad.hold_level_samples = 0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
}

TEST(TdorcWhisker, HoldQuietRmsEndsAHoldOverAQuietOffset) {
  // Issue 17: a whisker pressed by a moving drone (+200 Pa with +-30 Pa
  // alternating: changes of 60 Pa per sample) from sample 300 to 1099; after
  // the release the gel keeps an offset of +150 Pa decaying by 0.1 Pa per
  // sample (000 eq. 1, N_h). 150 is over T_c, over 0.1 of the peak and over
  // 0.25 of the level, so the previous rules hold the whisker to the limit
  // (onset 301 + 999 = 1300). The band-pass has zero gain at the alternation
  // (Nyquist), so S_p, the onset and the hold's start are those of a plain
  // push. By hand, with hold_quiet_rms 8 over 25 samples: the last change of
  // the pressed phase (60 Pa, sample 1099) leaves the window of 25 changes
  // after sample 1123; at 1124 the window holds the fall 170 -> 150 (20 Pa)
  // and 24 changes of 0.1 Pa, RMS sqrt((400 + 0.24) / 25) = 4.0 < 8: 1124 and
  // 1125 are held (hold_release_samples 3), 1126 is free.
  auto last_with = [](double rms) {
    Params p = holding();
    p.hold_release_fraction = 0.1;
    p.hold_release_samples = 3;
    p.hold_release_drop = 0.25;
    p.hold_level_samples = 50;
    p.hold_quiet_rms = rms;
    p.hold_quiet_samples = 25;
    return last_contact(run_pushed(p, 1600, [](int k) {
      if (k < 300) return 0.0;
      if (k < 1100) return 200.0 + (k % 2 == 0 ? 30.0 : -30.0);
      return 150.0 - 0.1 * (k - 1100);
    }));
  };
  EXPECT_EQ(last_with(0.0), 1300);
  EXPECT_EQ(last_with(8.0), 1125);
  // With 0.2 Pa the fall (RMS 4.0) is not quiet; from 1125 the window holds
  // only the 0.1 Pa changes: 1125, 1126 held, 1127 free. Below 0.1, never.
  EXPECT_EQ(last_with(0.2), 1126);
  EXPECT_EQ(last_with(0.09), 1300);
}

TEST(TdorcWhisker, HoldQuietRmsKeepsAMovingPressedWhisker) {
  // Pressed from sample 300 to the end with +-a Pa alternating on +200 Pa:
  // the changes are 2a per sample, their RMS 2a. With hold_quiet_rms 8 a
  // whisker moved by 10 Pa per sample (a = 5) stays in contact to the hold
  // limit (1300), one moved by 6 Pa (a = 3) is released as soon as the hold
  // begins: held at its first two samples, free at the third.
  auto outs_with = [](double a) {
    Params p = holding();
    p.hold_release_samples = 3;
    p.hold_quiet_rms = 8.0;
    p.hold_quiet_samples = 25;
    return run_pushed(p, 1600, [a](int k) { return k < 300 ? 0.0 : 200.0 + (k % 2 == 0 ? a : -a); });
  };
  EXPECT_EQ(last_contact(outs_with(5.0)), 1300);
  const auto quiet = outs_with(3.0);
  int first_held = -1;
  for (int k = 0; k < 1600 && first_held < 0; ++k) {
    if (quiet[static_cast<size_t>(k)].contact_held) first_held = k;
  }
  ASSERT_GT(first_held, 600);  // after S_p of the push decayed under T_c (~668)
  EXPECT_EQ(last_contact(quiet), first_held + 1);
  Params bad;
  bad.hold_quiet_rms = -1.0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
  bad.hold_quiet_rms = 8.0;
  bad.hold_quiet_samples = 1;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
}

TEST(TdorcWhisker, MaxDriftSlopeKeepsAStepFromLockingTheWhisker) {
  // eq. 8 as written on a 10 s push (+200 Pa, samples 300-799): the band-pass
  // loses the contact after ~7 s, the window learns pressed samples, and after
  // the release the least-squares line through the step is steep; its ramp
  // holds S_p over T_c (a ramp of c Pa/sample settles at ~161 c), the fit
  // freezes and the whisker stays "in contact" to the end (the lock). With
  // max_drift_slope the steep fits are not used and the lock never forms.
  auto run = [](double max_slope) {
    Params p;
    p.max_drift_slope = max_slope;
    return run_pushed(p, 3000, [](int k) { return k >= 300 && k < 800 ? 200.0 : 0.0; });
  };
  const auto paper = run(0.0);
  EXPECT_TRUE(paper[2999].contact) << "eq. 8 as written locks on this push";
  const auto bounded = run(0.5);
  EXPECT_FALSE(bounded[2999].contact);
  EXPECT_LT(last_contact(bounded), 1100);  // measured 1054, then free to the end
  // Free flight of the drifting whisker (+-0.03 Pa/sample) is never bounded.
  TdorcWhisker w = [] {
    Params p;
    p.max_drift_slope = 0.5;
    return TdorcWhisker(p);
  }();
  for (int k = 0; k < 1000; ++k) w.update({{100000.0 + 0.03 * k, 99000.0 - 0.03 * k, 101000.0}});
  for (int i = 0; i < 3; ++i) EXPECT_EQ(w.channel(i).implausible_fits(), 0u);
  Params bad;
  bad.max_drift_slope = -1.0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
}

TEST(TdorcWhisker, HoldReleaseSamplesBridgesStickSlipSamples) {
  // Pressed with +200 Pa from sample 300 to 1099, with a slip sample every
  // 50th pressed sample whose load drops to 0 (a whisker sliding along a
  // wall). Once S_p has decayed (sample 668), release after one sample loses
  // the contact at the first slip and learns pressed samples; two samples
  // bridge every slip and end one sample after the push.
  auto run = [](int release_samples) {
    Params p = holding();
    p.hold_release_samples = release_samples;
    const auto pressed = [](int k) { return k >= 300 && k < 1100; };
    const auto outs = run_pushed(p, 2000, [&](int k) {
      const bool slip = pressed(k) && (k - 300) % 50 == 25;
      return pressed(k) && !slip ? 200.0 : 0.0;
    });
    int pressed_in_contact = 0;
    for (int k = 0; k < 2000; ++k) pressed_in_contact += pressed(k) && outs[static_cast<size_t>(k)].contact ? 1 : 0;
    return std::make_pair(pressed_in_contact, last_contact(outs));
  };
  const auto one = run(1);
  EXPECT_LT(one.first, 799);  // lost at the first slip after sample 668
  const auto two = run(2);
  EXPECT_EQ(two.first, 799);    // every pressed sample from the onset (301) to 1099
  EXPECT_EQ(two.second, 1100);  // the first free sample is still held, the second releases
  const auto ten = run(10);
  EXPECT_EQ(ten.first, 799);
  EXPECT_EQ(ten.second, 1108);  // held through the 9 free samples after the push
  Params bad;
  bad.hold_release_samples = 0;
  EXPECT_THROW(TdorcWhisker{bad}, std::invalid_argument);
}

TEST(TdorcWhisker, BandpassModeNeverHolds) {
  // No drift model: S_c is the raw pressure, which must not hold a contact.
  Params p;
  p.mode = Mode::kBandpass;
  p.contact_hold = true;
  const HeldRun r = run_held(p, 300, 800);
  EXPECT_EQ(r.held, 0);
  EXPECT_TRUE(r.lost_while_pressed);
}

TEST(TdorcWhisker, TdocNeverRefits) {
  Params p;
  p.mode = Mode::kTdoc;
  TdorcWhisker w(p);
  LineFit first{};
  for (int k = 0; k < 2000; ++k) {
    // Drift changes slope after the first fit: TDOC keeps the first line.
    const double v = k < 100 ? 100000.0 + 0.01 * k : 100000.0 + 0.01 * k + 1e-5 * (k - 100) * (k - 100);
    const auto o = w.update({{v, v, v}});
    if (k == 99) first = w.channel(0).line();
    if (k >= 99) {
      EXPECT_EQ(w.channel(0).fit_count(), 1u);
      EXPECT_FALSE(o.drift_frozen);
    }
  }
  EXPECT_EQ(w.channel(0).line().slope, first.slope);
  EXPECT_EQ(w.channel(0).line().intercept, first.intercept);
  EXPECT_NEAR(first.slope, 0.01, 1e-12);
}

TEST(TdorcWhisker, TdorcFollowsChangingDriftButTdocDoesNot) {
  // Extended Data Fig. 2b in miniature: a drift whose slope changes after
  // take-off. TDORC keeps S_p near 0; TDOC's S_c grows.
  Params pr, po;
  po.mode = Mode::kTdoc;
  TdorcWhisker r(pr), o(po);
  double max_r = 0.0, sc_o = 0.0;
  for (int k = 0; k < 3000; ++k) {
    const double v = 100000.0 + 0.5 * std::sin(k * 0.002) * 400.0;
    const auto a = r.update({{v, v, v}});
    const auto b = o.update({{v, v, v}});
    if (k > 200) max_r = std::max(max_r, std::fabs(a.channel[0].calibrated));
    sc_o = b.channel[0].calibrated;
  }
  EXPECT_LT(max_r, 1.0);
  EXPECT_GT(std::fabs(sc_o), 50.0);
}

TEST(TdorcWhisker, AbsoluteThresholdCountsNegativeExcursions) {
  Params p;
  p.mode = Mode::kBandpass;
  TdorcWhisker plain(p);
  p.absolute_threshold = true;
  TdorcWhisker abs(p);
  plain.update({{0.0, 0.0, 0.0}});
  abs.update({{0.0, 0.0, 0.0}});
  // A -400 Pa step: S_p = -22.56.
  EXPECT_FALSE(plain.update({{0.0, -400.0, 0.0}}).contact);
  EXPECT_TRUE(abs.update({{0.0, -400.0, 0.0}}).contact);
}

TEST(TdorcWhisker, ResetStartsOver) {
  Params p;
  p.window = 5;
  TdorcWhisker w(p);
  for (int k = 0; k < 20; ++k) w.update({{1.0 * k, 2.0, 3.0}});
  EXPECT_TRUE(w.update({{20.0, 2.0, 3.0}}).ready);
  w.reset();
  EXPECT_EQ(w.samples(), 0);
  EXPECT_FALSE(w.update({{1.0, 2.0, 3.0}}).ready);
  EXPECT_EQ(w.channel(0).fit_count(), 0u);
}

TEST(TdorcWhisker, StateSize) {
  TdorcWhisker w{Params{}};
  const std::size_t s = w.state_size_bytes();
  // Three windows of n = 100 (value + index, 16 B each) dominate.
  EXPECT_GE(s, 3u * 100u * 16u);
  EXPECT_LT(s, 3u * 100u * 16u + 2048u);
}

// ------------------------------------------------------------------ validation

TEST(Params, ValidateSustainedContactFields) {
  Params p;
  p.max_contact_hold = 0;
  EXPECT_EQ(error_of(p), "TdorcParams.max_contact_hold: must be >= 1, got 0");
  p = Params{};
  p.learn_delay = -1;
  EXPECT_EQ(error_of(p), "TdorcParams.learn_delay: must be in [0, 10000], got -1");
  p = Params{};
  p.hold_release_samples = 0;
  EXPECT_EQ(error_of(p), "TdorcParams.hold_release_samples: must be in [1, 10000], got 0");
  p = Params{};
  p.hold_release_drop = 1.0;
  EXPECT_EQ(error_of(p), "TdorcParams.hold_release_drop: must be in [0, 1), got 1");
  p = Params{};
  p.hold_level_samples = 0;
  EXPECT_EQ(error_of(p), "TdorcParams.hold_level_samples: must be in [1, 100000], got 0");
  p = Params{};
  p.max_drift_slope = -1.0;
  EXPECT_EQ(error_of(p), "TdorcParams.max_drift_slope: must be finite and >= 0, got -1");
  p = Params{};
  p.hold_quiet_rms = -1.0;
  EXPECT_EQ(error_of(p), "TdorcParams.hold_quiet_rms: must be finite and >= 0, got -1");
  p = Params{};
  p.hold_quiet_samples = 1;
  EXPECT_EQ(error_of(p), "TdorcParams.hold_quiet_samples: must be in [2, 10000], got 1");
}

TEST(Params, ValidateNamesTheField) {
  Params p;
  EXPECT_EQ(error_of(p), "");
  p.window = 1;
  EXPECT_EQ(error_of(p), "TdorcParams.window: must be >= 2, got 1");
  p = Params{};
  p.contact_threshold = std::nan("");
  EXPECT_NE(error_of(p).find("TdorcParams.contact_threshold"), std::string::npos);
  p = Params{};
  p.absolute_threshold = true;
  p.contact_threshold = -1.0;
  EXPECT_NE(error_of(p).find("TdorcParams.contact_threshold: must be >= 0"), std::string::npos);
  p = Params{};
  p.bandpass_a[0] = 2.0;
  EXPECT_NE(error_of(p).find("TdorcParams.bandpass_a[0]: must be 1"), std::string::npos);
  p = Params{};
  p.bandpass_a = {{1.0, -2.0, 1.0}};  // double pole at z = 1
  EXPECT_NE(error_of(p).find("TdorcParams.bandpass_a: poles"), std::string::npos);
  p = Params{};
  p.bandpass_b[2] = INFINITY;
  EXPECT_NE(error_of(p).find("TdorcParams.bandpass_b[2]: must be finite"), std::string::npos);
  p = Params{};
  p.window = 1;
  EXPECT_THROW(TdorcWhisker{p}, std::invalid_argument);
}

TEST(Params, ModeStrings) {
  EXPECT_EQ(tdorc_filter::mode_from_string("tdorc"), Mode::kTdorc);
  EXPECT_EQ(tdorc_filter::mode_from_string("tdoc"), Mode::kTdoc);
  EXPECT_EQ(tdorc_filter::mode_from_string("bandpass"), Mode::kBandpass);
  EXPECT_STREQ(tdorc_filter::to_string(Mode::kTdoc), "tdoc");
  try {
    tdorc_filter::mode_from_string("TDORC ");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("TdorcParams.mode"), std::string::npos);
  }
}
