// Test utilities for the parameters of a node logic (header-only, no test framework):
// each integer parameter set to a value an int would wrap; each described range probed
// just outside its ends.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "tactile_common/parameters.hpp"

namespace tactile_common {

/// One integer parameter set to a value that wraps when narrowed to int.
struct WrappedInteger {
  std::string key;
  int64_t value = 0;  ///< the default + 2^32: static_cast<int>(value) is the default
  std::string error;  ///< what params_from threw (ParamError), "" if it accepted the value

  /// The error a range-checked read gives: names the key, a range and the value as given
  /// ("<key>: must be in [lo, hi], got <value>"), not the value narrowed.
  bool rejected_as_given() const {
    return error.find("ros__parameters." + key + ": must be in [") != std::string::npos &&
           error.find("], got " + std::to_string(value)) != std::string::npos;
  }
};

/// For every integer parameter of `defaults`, alone: sets it to its default +
/// 2^32 and calls `params_from(map)`. Returned by key.
template <typename ParamsFrom>
std::map<std::string, WrappedInteger> wrapped_integers(const ParamMap& defaults, ParamsFrom params_from) {
  std::map<std::string, WrappedInteger> out;
  for (const auto& [key, value] : defaults.values()) {
    const auto* v = std::get_if<int64_t>(&value);
    if (v == nullptr) continue;
    // Wrapping a default within 2^32 of INT64_MAX would overflow: such a key is read as a
    // 64-bit value anyway (nothing to narrow), so it goes the other way.
    const int64_t step = *v > INT64_MAX - (int64_t{1} << 32) ? -(int64_t{1} << 32) : (int64_t{1} << 32);
    WrappedInteger w{key, *v + step, ""};
    ParamMap m = defaults;
    m.set(key, w.value);
    try {
      params_from(m);
    } catch (const ParamError& e) {
      w.error = e.what();
    }
    out.emplace(key, std::move(w));
  }
  return out;
}

/// A value just outside a described range that params_from() accepted.
struct RangeLeak {
  std::string key;
  double value = 0.0;
};

/// For every key of `defaults` whose ParamInfo has a range, alone: sets it just outside
/// each finite end (an open end itself; a closed end minus/plus one for an integer, the
/// next double for a double) and calls `params_from(map)`. Returns the values it accepted:
/// none when the described range is no wider than what params_from()/validate() take
/// (a ROS tool then never shows a range the node refuses inside).
template <typename ParamsFrom>
std::vector<RangeLeak> range_leaks(const ParamMap& defaults, ParamsFrom params_from) {
  std::vector<RangeLeak> out;
  for (const auto& [key, info] : defaults.infos()) {
    if (!info.range) continue;
    const ParamValue& value = defaults.values().at(key);
    const bool integer = std::holds_alternative<int64_t>(value);
    if (!integer && !std::holds_alternative<double>(value)) continue;
    const ParamRange& r = *info.range;
    std::vector<double> probes;
    const double inf = std::numeric_limits<double>::infinity();
    if (std::isfinite(r.lo)) probes.push_back(r.open_lo ? r.lo : integer ? r.lo - 1 : std::nextafter(r.lo, -inf));
    if (std::isfinite(r.hi)) probes.push_back(r.open_hi ? r.hi : integer ? r.hi + 1 : std::nextafter(r.hi, inf));
    for (const double v : probes) {
      ParamMap m = defaults;
      if (integer) {
        m.set(key, static_cast<int64_t>(v));
      } else {
        m.set(key, v);
      }
      try {
        params_from(m);
        out.push_back({key, v});
      } catch (const ParamError&) {
      }
    }
  }
  return out;
}

/// For every double key of `defaults` whose described range has an infinite end, alone: sets
/// it to that infinity and calls `params_from(map)`. Returns the values it accepted: none when
/// an unbounded range ("(0, inf)") means every finite value, as ParamRange::contains() takes
/// it (range_leaks() probes finite ends only; an infinite max_input_age_s would switch a
/// stale-input failsafe off).
template <typename ParamsFrom>
std::vector<RangeLeak> infinities_accepted(const ParamMap& defaults, ParamsFrom params_from) {
  std::vector<RangeLeak> out;
  for (const auto& [key, info] : defaults.infos()) {
    if (!info.range || !std::holds_alternative<double>(defaults.values().at(key))) continue;
    for (const double v : {info.range->lo, info.range->hi}) {
      if (!std::isinf(v)) continue;
      ParamMap m = defaults;
      m.set(key, v);
      try {
        params_from(m);
        out.push_back({key, v});
      } catch (const ParamError&) {
      }
    }
  }
  return out;
}

/// The keys of `defaults` without a ParamInfo (or with an empty description).
inline std::vector<std::string> undescribed(const ParamMap& defaults) {
  std::vector<std::string> out;
  for (const auto& [key, value] : defaults.values()) {
    const ParamInfo* info = defaults.info(key);
    if (info == nullptr || info->description.empty()) out.push_back(key);
  }
  return out;
}

}  // namespace tactile_common
