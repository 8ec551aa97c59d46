#include "whisker_driver/driver_health.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "tactile_common/validation.hpp"

namespace whisker_driver {

using tactile_common::ParamMap;

namespace {

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

constexpr const char* kType = "DriverHealth";  // names the fields in validation errors

}  // namespace

void DriverHealth::Params::validate() const {
  tactile_common::require_finite_positive(kType, "diagnostics_period_s", diagnostics_period_s);
  tactile_common::require_finite_positive(kType, "stall_warn_s", stall_warn_s);
  tactile_common::require_finite_positive(kType, "stall_error_s", stall_error_s);
  tactile_common::require_below(kType, "stall_warn_s", stall_warn_s, "stall_error_s", stall_error_s);
  tactile_common::require_finite_positive(kType, "frame_error_warn", frame_error_warn);
  tactile_common::require_finite_positive(kType, "frame_error_error", frame_error_error);
  tactile_common::require_below(kType, "frame_error_warn", frame_error_warn, "frame_error_error", frame_error_error);
  if (frame_error_error > 1.0) {
    throw std::invalid_argument("DriverHealth.frame_error_error: a fraction, must be <= 1, got " +
                                std::to_string(frame_error_error));
  }
}

ParamMap DriverHealth::default_parameters() {
  const Params d;
  ParamMap m(kNodeName, "defaults");
  using tactile_common::choice;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  // The health thresholds' spec (README): read at start like the driver's keys.
  m.set("diagnostics_period_s", d.diagnostics_period_s,
        {"/diagnostics period (diagnostic_updater's default 1 s)", "s", positive(), false,
         choice("diagnostic_updater's default")});
  m.set("stall_warn_s", d.stall_warn_s,
        {"stream WARN when no sample came for this long (5 frames at 50 Hz, 000 Methods); below stall_error_s", "s", positive(), false,
         choice("5 frames at 50 Hz (000 Methods)")});
  m.set("stall_error_s", d.stall_error_s,
        {"stream ERROR after this long (the serial source's reopen interval)", "s", positive(), false, choice()});
  m.set("frame_error_warn", d.frame_error_warn,
        {"WARN above this fraction of dropped lines in a period (choice); below frame_error_error", "", positive(), false,
         choice()});
  m.set("frame_error_error", d.frame_error_error,
        {"ERROR above this fraction (choice)", "", ParamRange{0.0, 1.0, true, false}, false, choice()});
  return m;
}

DriverHealth::Params DriverHealth::params_from(const ParamMap& m) {
  Params p;
  p.diagnostics_period_s = m.get_double("diagnostics_period_s");
  p.stall_warn_s = m.get_double("stall_warn_s");
  p.stall_error_s = m.get_double("stall_error_s");
  p.frame_error_warn = m.get_double("frame_error_warn");
  p.frame_error_error = m.get_double("frame_error_error");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw tactile_common::ParamError(m.source() + ": " + kNodeName + ": " + e.what());
  }
  return p;
}

DriverHealth::DriverHealth(const Params& params) : params_(params) { params_.validate(); }

DriverHealth::Check DriverHealth::update(const WhiskerDriverLogic::Stats& s, double sample_age_s) {
  const uint64_t lines = s.parse.lines - last_.parse.lines;
  const uint64_t dropped = (s.parse.dropped_lines() - last_.parse.dropped_lines()) +
                           (s.parse.dropped_frames() - last_.parse.dropped_frames());
  const uint64_t device_errors = s.source_errors - last_.source_errors;
  const uint64_t published = s.published - last_.published;
  last_ = s;
  const double dropped_fraction = lines > 0 ? static_cast<double>(dropped) / static_cast<double>(lines) : 0.0;

  Check c;
  c.values = {{"samples_in_period", std::to_string(published)},
              {"sample_age_s", fmt("%.3f", sample_age_s)},
              {"lines_in_period", std::to_string(lines)},
              {"dropped_in_period", std::to_string(dropped)},
              {"device_errors_in_period", std::to_string(device_errors)},
              {"device_errors", std::to_string(s.source_errors)},
              {"dropped_lines", std::to_string(s.parse.dropped_lines())},
              {"dropped_frames", std::to_string(s.parse.dropped_frames())},
              {"samples_missing", std::to_string(s.samples_missing)}};
  const bool stalled_error = !(sample_age_s <= params_.stall_error_s);  // NaN: never a sample
  if (device_errors > 0 && stalled_error) {
    c.level = Level::kError;
    c.message = "device gone: " + std::to_string(device_errors) + " device error(s) and no sample for " +
                fmt("%.1f", sample_age_s) + " s";
  } else if (stalled_error) {
    c.level = Level::kError;
    c.message = "stalled: no sample for " + fmt("%.2f", sample_age_s) + " s > stall_error_s " +
                fmt("%.2f", params_.stall_error_s) + " s";
  } else if (dropped_fraction > params_.frame_error_error) {
    c.level = Level::kError;
    c.message = "frame errors: " + std::to_string(dropped) + " of " + std::to_string(lines) +
                " lines dropped > frame_error_error " + fmt("%.2f", params_.frame_error_error);
  } else if (sample_age_s > params_.stall_warn_s) {
    c.level = Level::kWarn;
    c.message = "late: no sample for " + fmt("%.2f", sample_age_s) + " s > stall_warn_s " +
                fmt("%.2f", params_.stall_warn_s) + " s";
  } else if (dropped_fraction > params_.frame_error_warn) {
    c.level = Level::kWarn;
    c.message = "frame errors: " + std::to_string(dropped) + " of " + std::to_string(lines) +
                " lines dropped > frame_error_warn " + fmt("%.2f", params_.frame_error_warn);
  } else {
    c.message = std::to_string(published) + " samples";
  }
  return c;
}

}  // namespace whisker_driver
