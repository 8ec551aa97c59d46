#include "tactile_fsm/safety_runner.hpp"

#include <stdexcept>

namespace tactile_fsm {

const char* to_string(SafetyInput i) {
  switch (i) {
    case SafetyInput::kDepth: return "tactile depth";
    case SafetyInput::kOdometry: return "odometry";
    case SafetyInput::kForce: return "force";
    case SafetyInput::kWallEstimate: return "wall estimate";
  }
  return "unknown input";
}

const char* to_string(SafetyState s) {
  switch (s) {
    case SafetyState::kNominal: return "NOMINAL";
    case SafetyState::kFailsafeHover: return "FAILSAFE_HOVER";
    case SafetyState::kFailsafeLand: return "FAILSAFE_LAND";
    case SafetyState::kTimeLimitLand: return "TIME_LIMIT_LAND";
  }
  return "UNKNOWN";
}

namespace {

SafetyReason stale_reason(SafetyInput i) { return static_cast<SafetyReason>(1 + static_cast<uint8_t>(i)); }

const char* stale_text(SafetyInput i) {
  switch (i) {
    case SafetyInput::kDepth: return "tactile depth stale";
    case SafetyInput::kOdometry: return "odometry stale";
    case SafetyInput::kForce: return "force stale";
    case SafetyInput::kWallEstimate: return "wall estimate stale";
  }
  return "input stale";
}

// Tolerance of time comparisons: ticks are sums of 10-20 ms steps in floating point.
constexpr double kTimeEps = 1e-9;

}  // namespace

void SafetyParams::validate(const std::string& owner) const {
  auto fail = [&](const char* field, const char* reason, double v) {
    throw std::invalid_argument(owner + "." + field + ": " + reason + ", got " + std::to_string(v));
  };
  // Finite: an infinite age would never call an input stale (the fail-safe off).
  if (!(std::isfinite(max_input_age_s) && max_input_age_s > 0.0)) {
    fail("max_input_age_s", "must be finite and > 0", max_input_age_s);
  }
  if (!(std::isfinite(failsafe_land_after_s) && failsafe_land_after_s >= 0.0)) {
    fail("failsafe_land_after_s", "must be finite and >= 0", failsafe_land_after_s);
  }
  if (!(time_limit_s > 0.0)) fail("time_limit_s", "must be > 0 (infinity: no limit)", time_limit_s);
}

SafetyRunner::SafetyRunner(const SafetyParams& params, std::vector<SafetyInput> inputs)
    : p_(params), inputs_(std::move(inputs)) {
  p_.validate();
  if (inputs_.empty()) throw std::invalid_argument("SafetyRunner: at least one input to guard");
}

void SafetyRunner::reset() {
  state_ = SafetyState::kNominal;
  reason_ = SafetyReason::kNone;
  text_ = "";
  stale_input_ = SafetyInput::kDepth;
  started_ = false;
  start_ = entered_ = held_s_ = 0.0;
  failsafe_hovers_ = 0;
}

int SafetyRunner::first_stale(double t, const double* stamps) const {
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    if (!input_is_fresh(t, stamps[i], p_.max_input_age_s)) return static_cast<int>(i);
  }
  return -1;
}

bool SafetyRunner::hover_expired(double t) const {
  return state_ == SafetyState::kFailsafeHover && t - entered_ >= p_.failsafe_land_after_s - kTimeEps;
}

bool SafetyRunner::time_limit_passed(double t) const {
  return started_ && std::isfinite(p_.time_limit_s) && t - start_ >= p_.time_limit_s - kTimeEps;
}

void SafetyRunner::enter(SafetyState s, SafetyReason r, const char* text, double t) {
  if (state_ == SafetyState::kFailsafeHover) held_s_ += t - entered_;
  state_ = s;
  reason_ = r;
  text_ = text;
  entered_ = t;
}

SafetyVerdict SafetyRunner::verdict(bool entered, bool resumed) const {
  SafetyVerdict v;
  v.state = state_;
  v.entered = entered;
  v.resumed = resumed;
  v.reason = reason_;
  v.text = text_;
  return v;
}

SafetyVerdict SafetyRunner::step(double t, std::initializer_list<double> stamps, bool guarded) {
  return step_impl(t, stamps.begin(), stamps.size(), guarded);
}

SafetyVerdict SafetyRunner::step(double t, const std::vector<double>& stamps, bool guarded) {
  return step_impl(t, stamps.data(), stamps.size(), guarded);
}

SafetyVerdict SafetyRunner::step_impl(double t, const double* stamps, std::size_t n, bool guarded) {
  if (n != inputs_.size()) {
    throw std::invalid_argument("SafetyRunner.step: " + std::to_string(n) + " stamps for " +
                                std::to_string(inputs_.size()) + " inputs");
  }
  if (!started_) {
    started_ = true;
    start_ = t;
  }
  switch (state_) {
    case SafetyState::kFailsafeLand:
    case SafetyState::kTimeLimitLand:
      return verdict(false, false);  // terminal: the landing goes on
    case SafetyState::kFailsafeHover: {
      if (first_stale(t, stamps) < 0) {
        enter(SafetyState::kNominal, SafetyReason::kInputsFresh, "inputs fresh again", t);
        return verdict(true, true);
      }
      if (hover_expired(t)) {
        enter(SafetyState::kFailsafeLand, SafetyReason::kStaleTooLong, "inputs stale for failsafe_land_after_s", t);
        return verdict(true, false);
      }
      return verdict(false, false);
    }
    case SafetyState::kNominal:
      break;
  }
  if (!guarded) return verdict(false, false);
  const int stale = first_stale(t, stamps);
  if (stale >= 0) {
    stale_input_ = inputs_[static_cast<std::size_t>(stale)];
    ++failsafe_hovers_;
    enter(SafetyState::kFailsafeHover, stale_reason(stale_input_), stale_text(stale_input_), t);
    return verdict(true, false);
  }
  if (time_limit_passed(t)) {
    enter(SafetyState::kTimeLimitLand, SafetyReason::kTimeLimit, "time limit", t);
    return verdict(true, false);
  }
  return verdict(false, false);
}

}  // namespace tactile_fsm
