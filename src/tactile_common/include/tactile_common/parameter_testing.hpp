// Test helper for the integer parameters of a node logic (header-only, no
// test framework): each integer parameter set to a value an int would wrap.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <variant>

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

}  // namespace tactile_common
