#include "tactile_common/sample_clock.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace tactile_common {

void SampleClockParams::validate() const {
  auto bad = [](const char* field, const std::string& reason) {
    throw std::invalid_argument(std::string("SampleClockParams.") + field + ": " + reason);
  };
  if (!std::isfinite(nominal_period_s) || nominal_period_s <= 0.0)
    bad("nominal_period_s", "must be finite and > 0, got " + std::to_string(nominal_period_s));
  if (!std::isfinite(tolerance_s) || tolerance_s <= 0.0)
    bad("tolerance_s", "must be finite and > 0, got " + std::to_string(tolerance_s));
  if (max_late_samples < 1) bad("max_late_samples", "must be >= 1, got " + std::to_string(max_late_samples));
  if (step_samples < 2) bad("step_samples", "must be >= 2, got " + std::to_string(step_samples));
}

const char* to_string(SampleKind kind) {
  switch (kind) {
    case SampleKind::kFirst: return "first";
    case SampleKind::kInOrder: return "in_order";
    case SampleKind::kRepairedAhead: return "repaired_ahead";
    case SampleKind::kRepairedBehind: return "repaired_behind";
    case SampleKind::kClockStep: return "clock_step";
    case SampleKind::kDuplicate: return "duplicate";
    case SampleKind::kLate: return "late";
  }
  return "?";
}

SampleClock::SampleClock(const SampleClockParams& params) : params_(params) {
  params_.validate();
  reset();
}

void SampleClock::reset() {
  have_last_ = false;
  have_receive_ = false;
  period_ns_ = params_.nominal_period_s * 1e9;
  repair_run_ = 0;
  repair_offset_ = 0;
}

SampleDecision SampleClock::classify(uint32_t sequence, int64_t stamp_ns, std::optional<int64_t> receive_ns) {
  SampleDecision out;
  if (!have_last_) {
    have_last_ = true;
    last_seq_ = sequence;
    last_stamp_ = last_raw_ = stamp_ns;
    have_receive_ = receive_ns.has_value();
    last_receive_ = receive_ns.value_or(0);
    ++stats_.in_order;
    out.stamp_ns = stamp_ns;
    return out;
  }
  const auto tol = static_cast<int64_t>(std::llround(params_.tolerance_s * 1e9));
  const int64_t d = static_cast<int32_t>(sequence - last_seq_);  // signed, modulo 2^32
  const int64_t dt = stamp_ns - last_stamp_;
  const bool have_rx = receive_ns.has_value() && have_receive_;
  const int64_t dr = have_rx ? *receive_ns - last_receive_ : 0;

  bool seq_usable = d > 0;
  if (d == 0 && (stamp_ns == last_raw_ || dt <= 0)) {  // rule 1
    out.kind = SampleKind::kDuplicate;
    out.accept = false;
    ++stats_.duplicates;
    return out;
  }
  if (d < 0 && -d <= params_.max_late_samples && dt <= tol) {  // rule 2
    out.kind = SampleKind::kLate;
    out.accept = false;
    ++stats_.late;
    return out;
  }
  if (d <= 0) {
    out.restart = true;
    ++stats_.restarts;
  }

  // Rule 3: does the stamp agree with another clock?
  const double period = period_ns_;
  const int64_t e_seq = seq_usable ? static_cast<int64_t>(std::llround(static_cast<double>(d) * period)) : 0;
  const bool ok_seq = seq_usable && dt > 0 && std::llabs(dt - e_seq) <= tol;
  const bool ok_rx = have_rx && dt > 0 && std::llabs(dt - dr) <= tol;
  const bool no_witness = !seq_usable && !have_rx;
  if (ok_seq || ok_rx || (no_witness && dt > 0)) {
    out.kind = SampleKind::kInOrder;
    out.stamp_ns = stamp_ns;
    out.elapsed_ns = dt;
    repair_run_ = 0;
    ++stats_.in_order;
    // Period estimate from consecutive samples whose stamp the sequence confirms.
    if (d == 1 && ok_seq) period_ns_ += (static_cast<double>(dt) - period_ns_) / 20.0;
  } else {
    // Rule 4: the stamp alone disagrees; the other clocks give the time.
    const auto p = static_cast<int64_t>(std::llround(period));
    const int64_t elapsed = seq_usable ? e_seq : (have_rx ? std::max(dr, p) : p);
    const int64_t offset = stamp_ns - (last_stamp_ + elapsed);
    if (repair_run_ > 0 && std::llabs(offset - repair_offset_) <= tol) {
      ++repair_run_;
    } else {
      repair_run_ = 1;
      repair_offset_ = offset;
    }
    out.elapsed_ns = elapsed;
    if (repair_run_ >= params_.step_samples && dt > 0) {
      // Rule 5: a step of the stamp clock, not a glitch (a backward step is
      // not taken: the stamps would go back).
      out.kind = SampleKind::kClockStep;
      out.stamp_ns = stamp_ns;
      repair_run_ = 0;
      ++stats_.clock_steps;
    } else {
      out.kind = offset > 0 ? SampleKind::kRepairedAhead : SampleKind::kRepairedBehind;
      out.stamp_ns = last_stamp_ + elapsed;
      ++(offset > 0 ? stats_.repaired_ahead : stats_.repaired_behind);
    }
  }
  out.missing = std::max<int64_t>(0, std::llround(static_cast<double>(out.elapsed_ns) / period) - 1);
  if (out.missing > 0) {
    ++stats_.gaps;
    stats_.missing += static_cast<uint64_t>(out.missing);
  }
  last_seq_ = sequence;
  last_stamp_ = out.stamp_ns;
  last_raw_ = stamp_ns;
  if (receive_ns) {
    have_receive_ = true;
    last_receive_ = *receive_ns;
  }
  return out;
}

}  // namespace tactile_common
