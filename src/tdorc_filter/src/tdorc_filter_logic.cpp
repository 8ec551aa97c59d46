#include "tdorc_filter/tdorc_filter_logic.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/time.hpp"

namespace tdorc_filter {

using tactile_common::ParamMap;
using tactile_common::ParamRange;

void TdorcFilterLogic::Params::validate() const {
  tdorc.validate();
  if (!std::isfinite(max_sample_gap_s) || max_sample_gap_s <= 0.0) {
    throw std::invalid_argument("TdorcFilterLogic.max_sample_gap_s: must be finite and > 0, got " +
                                std::to_string(max_sample_gap_s));
  }
  try {
    clock.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();  // "SampleClockParams.<field>: <reason>"
    throw std::invalid_argument("TdorcFilterLogic.clock." + what.substr(what.find('.') + 1));
  }
}

ParamMap TdorcFilterLogic::default_parameters() {
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::positive;
  using tactile_common::tuned;
  const tdorc_filter::Params d;
  const Params n;
  ParamMap m(kNodeName, "defaults");
  // The node's parameter spec: value, description (from the Params comments), unit, the
  // range params_from()/validate() accept, and whether it is applied while running
  // (README "Parameters"). Only contact_threshold is live: a threshold on S_p, read per
  // sample; everything else shapes the drift window and the filter state.
  m.set("mode", std::string(to_string(d.mode)),
        {"compensation: tdorc (re-fit the drift on free-flight samples, 000 eq. 8), tdoc (fit once), "
         "bandpass (band-pass only)", "", {}, false,
         paper("000 eq. 4-11, Methods (TDORC: eq. 8 re-fit per free sample)")});
  m.set("window", static_cast<int64_t>(d.window),
        {"n, samples in the least-squares drift window (000 Methods, n = 100)", "samples", closed(2, 100000), false,
         paper("000 eq. 6-7, Methods: sliding window n = 100")});
  m.set("contact_threshold", d.contact_threshold,
        {"T_c, contact threshold on the band-passed S_p (000 Results: 20); >= 0 with absolute_threshold",
         "Pa", {}, true, paper("000 Results: a threshold of 20")});
  m.set("absolute_threshold", d.absolute_threshold,
        {"false: contact when S_p > T_c (the paper's rule); true: when |S_p| > T_c", "", {}, false,
         paper("000 Methods: contact when S_p > T")});
  m.set("learn_delay", static_cast<int64_t>(d.learn_delay),
        {"a free sample enters the drift window only after this many further free samples "
         "(workspace extension, README); 0: eq. 8 as written", "samples", closed(0, 10000), false,
         choice("shipped 10 = 0.2 s keeps a contact's rising edge out of the window (README \"Sustained contact\")")});
  m.set("contact_hold", d.contact_hold,
        {"hold a contact while any channel's S_c exceeds T_c (workspace extension, README)", "", {}, false,
         choice("README \"Sustained contact\": the band-pass forgets a held push after ~7 s")});
  m.set("max_contact_hold", static_cast<int64_t>(d.max_contact_hold),
        {"limit of a held contact (1000 = 20 s at 50 Hz)", "samples", closed(1, 100000000), false,
         choice("a bound, so a frozen line never holds a contact for ever")});
  m.set("hold_release_fraction", d.hold_release_fraction,
        {"a held contact ends when no channel's S_c is above this fraction of its peak in the contact; 0: off",
         "", ParamRange{0.0, 1.0, false, true}, false,
         tuned("README \"Sustained contact\": 8 wall-following scenarios, seeds 1-10, (0.1, 3) 39/40")});
  m.set("hold_release_samples", static_cast<int64_t>(d.hold_release_samples),
        {"consecutive samples below the hold condition that end a held contact", "samples", closed(1, 10000), false,
         tuned("README \"Sustained contact\": 8 wall-following scenarios, seeds 1-10, (0.1, 3) 39/40")});
  m.set("hold_release_drop", d.hold_release_drop,
        {"a held contact ends when the whisker's S_c falls below this fraction of its recent level; 0: off",
         "", ParamRange{0.0, 1.0, false, true}, false,
         tuned("README \"Sustained contact\": 6 baffle layouts, seeds 1-10, (0.25, 50) 58/60, seeds 11-20 59/60")});
  m.set("hold_level_samples", static_cast<int64_t>(d.hold_level_samples),
        {"time constant of that recent level (25 = 0.5 s at 50 Hz)", "samples", closed(1, 100000), false,
         tuned("README \"Sustained contact\": 6 baffle layouts, seeds 1-10, (0.25, 50) 58/60")});
  m.set("max_drift_slope", d.max_drift_slope,
        {"largest drift slope a re-fit may have (workspace extension, README); 0: off", "Pa/sample",
         ParamRange{0.0, std::numeric_limits<double>::infinity(), false, true}, false,
         tuned("README \"Sustained contact\": 2x the SITL free-flight drift; 6 layouts 59/60, seeds 11-30 117/120")});
  m.set("hold_quiet_rms", d.hold_quiet_rms,
        {"a held contact ends when the RMS of S_c's sample-to-sample changes is below this (issue 17); 0: off",
         "Pa", ParamRange{0.0, std::numeric_limits<double>::infinity(), false, true}, false,
         tuned("README \"Sustained contact\": off; 8 Pa ends phantom holds (mocap block 2000-2049) but loses sweeps")});
  m.set("hold_quiet_samples", static_cast<int64_t>(d.hold_quiet_samples),
        {"samples over which that RMS is taken (25 = 0.5 s at 50 Hz)", "samples", closed(2, 10000), false,
         choice("25 = 0.5 s at 50 Hz")});
  m.set("bandpass_b", std::vector<double>(d.bandpass_b.begin(), d.bandpass_b.end()),
        {"band-pass numerator b0, b1, b2 (000 eq. 9-11: first-order Butterworth 0.05-1 Hz at 50 Hz)", "", {}, false,
         paper("000 eq. 9-11")});
  m.set("bandpass_a", std::vector<double>(d.bandpass_a.begin(), d.bandpass_a.end()),
        {"band-pass denominator a0 = 1, a1, a2 (000 eq. 9-11); poles inside the unit circle", "", {}, false,
         paper("000 eq. 9-11")});
  m.set("max_sample_gap_s", n.max_sample_gap_s,
        {"a gap up to this is bridged (drift extrapolated), a longer one resets the filter (README \"Time\")", "s",
         positive(), false, choice()});
  m.set("sample_period_s", n.clock.nominal_period_s,
        {"nominal sample period of the whisker deck (000: 50 Hz)", "s", ParamRange{0.0, 10.0, true, false}, false,
         paper("000 Methods: whisker deck sampled at 50 Hz")});
  m.set("stamp_tolerance_s", n.clock.tolerance_s,
        {"how far a stamp may disagree with sequence and receive time before it is repaired (README \"Time\")",
         "s", ParamRange{0.0, 60.0, true, false}, false, choice()});
  m.set("max_late_samples", n.clock.max_late_samples,
        {"a sequence further back than this is a restart, not a late sample (README \"Time\")", "samples",
         closed(1, 1000000), false, choice()});
  m.set("clock_step_samples", n.clock.step_samples,
        {"consecutive samples with one stamp offset taken as a new time base (README \"Time\")", "samples",
         closed(2, 1000000), false, choice()});
  return m;
}

namespace {

std::array<double, 3> three(const ParamMap& m, const std::string& key) {
  const std::vector<double> v = m.get_double_array(key);
  if (v.size() != 3) throw m.error(key, "must have 3 elements (b0, b1, b2 / a0, a1, a2), got " + std::to_string(v.size()));
  return {{v[0], v[1], v[2]}};
}

}  // namespace

TdorcFilterLogic::Params TdorcFilterLogic::params_from(const ParamMap& m) {
  Params p;
  const std::string mode = m.get_string("mode");
  try {
    p.tdorc.mode = mode_from_string(mode.c_str());
  } catch (const std::invalid_argument&) {
    throw m.error("mode", "must be \"tdorc\", \"tdoc\" or \"bandpass\", got \"" + mode + "\"");
  }
  p.tdorc.window = m.get_int("window", 2, 100000);
  p.tdorc.contact_threshold = m.get_double("contact_threshold");
  p.tdorc.absolute_threshold = m.get_bool("absolute_threshold");
  p.tdorc.learn_delay = m.get_int("learn_delay", 0, 10000);
  p.tdorc.contact_hold = m.get_bool("contact_hold");
  p.tdorc.max_contact_hold = m.get_int("max_contact_hold", 1, 100000000);
  p.tdorc.hold_release_fraction = m.get_double("hold_release_fraction");
  p.tdorc.hold_release_samples = m.get_int("hold_release_samples", 1, 10000);
  p.tdorc.hold_release_drop = m.get_double("hold_release_drop");
  p.tdorc.hold_level_samples = m.get_int("hold_level_samples", 1, 100000);
  p.tdorc.max_drift_slope = m.get_double("max_drift_slope");
  p.tdorc.hold_quiet_rms = m.get_double("hold_quiet_rms");
  p.tdorc.hold_quiet_samples = m.get_int("hold_quiet_samples", 2, 10000);
  p.tdorc.bandpass_b = three(m, "bandpass_b");
  p.tdorc.bandpass_a = three(m, "bandpass_a");
  p.max_sample_gap_s = m.get_double("max_sample_gap_s");
  p.clock.nominal_period_s = m.get_double("sample_period_s");
  if (!std::isfinite(p.clock.nominal_period_s) || p.clock.nominal_period_s <= 0.0 || p.clock.nominal_period_s > 10.0) {
    throw m.error("sample_period_s", "must be in (0, 10], got " + std::to_string(p.clock.nominal_period_s));
  }
  p.clock.tolerance_s = m.get_double("stamp_tolerance_s");
  if (!std::isfinite(p.clock.tolerance_s) || p.clock.tolerance_s <= 0.0 || p.clock.tolerance_s > 60.0) {
    throw m.error("stamp_tolerance_s", "must be in (0, 60], got " + std::to_string(p.clock.tolerance_s));
  }
  p.clock.max_late_samples = m.get_int64("max_late_samples", 1, 1000000);
  p.clock.step_samples = m.get_int64("clock_step_samples", 2, 1000000);
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw m.error_from(e);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

TdorcFilterLogic::TdorcFilterLogic(const Params& params)
    : params_(params), whisker_(params.tdorc), clock_(params.clock) {
  params_.validate();
}

void TdorcFilterLogic::set_params(const Params& params) {
  params.validate();
  // Only the live keys may differ (default_parameters(): contact_threshold); the node's
  // parameter callback never passes another change, and a caller that does is refused.
  tdorc_filter::Params expected = params_.tdorc;
  expected.contact_threshold = params.tdorc.contact_threshold;
  const auto& c = params.clock;
  const auto& o = params_.clock;
  if (expected != params.tdorc || params.max_sample_gap_s != params_.max_sample_gap_s ||
      c.nominal_period_s != o.nominal_period_s || c.tolerance_s != o.tolerance_s ||
      c.max_late_samples != o.max_late_samples || c.step_samples != o.step_samples) {
    throw std::invalid_argument("TdorcFilterLogic.set_params: only contact_threshold may change while running");
  }
  params_ = params;
  whisker_.set_contact_threshold(params.tdorc.contact_threshold);
}

std::optional<tactile_msgs::msg::WhiskerSignal> TdorcFilterLogic::on_pressure(
    const tactile_msgs::msg::WhiskerPressure& msg, std::optional<int64_t> receive_ns) {
  using tactile_common::SampleKind;
  using tactile_msgs::msg::WhiskerPressure;
  using tactile_msgs::msg::WhiskerSignal;
  ++stats_.received;
  if (msg.whisker_id != WhiskerPressure::WHISKER_LEFT && msg.whisker_id != WhiskerPressure::WHISKER_RIGHT) {
    ++stats_.dropped_wrong_whisker;
    return std::nullopt;
  }
  if (whisker_id_ >= 0 && msg.whisker_id != whisker_id_) {
    ++stats_.dropped_wrong_whisker;
    return std::nullopt;
  }
  for (double p : msg.pressure) {
    if (!std::isfinite(p)) {
      ++stats_.dropped_nonfinite;  // never enters the filter state
      return std::nullopt;
    }
  }
  // Which clock to trust (README "Time"): duplicates and late samples are
  // dropped, a stamp that disagrees with both the sequence and the receive
  // time is replaced, and the sample still enters the filter.
  const auto d = clock_.classify(msg.sequence, tactile_common::from_stamp(msg.header.stamp), receive_ns);
  switch (d.kind) {
    case SampleKind::kDuplicate: ++stats_.dropped_duplicate; break;
    case SampleKind::kLate: ++stats_.dropped_late; break;
    case SampleKind::kRepairedAhead: ++stats_.stamps_repaired_ahead; break;
    case SampleKind::kRepairedBehind: ++stats_.stamps_repaired_behind; break;
    case SampleKind::kClockStep: ++stats_.clock_steps; break;
    case SampleKind::kFirst:
    case SampleKind::kInOrder: break;
  }
  if (!d.accept) {
    ++stats_.dropped_out_of_order;
    return std::nullopt;
  }
  if (d.restart) ++stats_.sequence_restarts;
  if (have_last_) {
    if (tactile_common::to_seconds(d.elapsed_ns) > params_.max_sample_gap_s) {
      whisker_.reset();  // the window and the extrapolated drift are stale
      ++stats_.resets_on_gap;
    } else if (d.missing > 0) {
      // The window is in samples: the missing ones keep their index, so the
      // drift line (000 eq. 4) is extrapolated over them as across a contact.
      whisker_.skip(d.missing);
      ++stats_.gaps_bridged;
      stats_.samples_missing += static_cast<uint64_t>(d.missing);
    }
    if (msg.sequence != static_cast<uint32_t>(last_sequence_ + 1u)) ++stats_.sequence_gaps;
  }
  whisker_id_ = msg.whisker_id;
  have_last_ = true;
  last_sequence_ = msg.sequence;

  const WhiskerOutput o = whisker_.update(msg.pressure);
  WhiskerSignal s;
  s.header = msg.header;
  tactile_common::to_stamp(d.stamp_ns, s.header.stamp);
  s.whisker_id = msg.whisker_id;
  switch (params_.tdorc.mode) {
    case Mode::kTdorc: s.mode = WhiskerSignal::MODE_TDORC; break;
    case Mode::kTdoc: s.mode = WhiskerSignal::MODE_TDOC; break;
    case Mode::kBandpass: s.mode = WhiskerSignal::MODE_BANDPASS; break;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    s.raw[i] = o.channel[i].raw;
    s.calibrated[i] = o.channel[i].calibrated;
    s.compensated[i] = o.channel[i].compensated;
    s.channel_contact[i] = o.channel[i].contact;
    s.drift_slope[i] = o.channel[i].drift_slope;
    s.drift_intercept[i] = o.channel[i].drift_intercept;
  }
  s.contact = o.contact;
  s.calibrated_ready = o.ready;
  s.drift_frozen = o.drift_frozen;
  s.window_fill = static_cast<uint32_t>(o.window_fill);
  ++stats_.published;
  return s;
}

}  // namespace tdorc_filter
