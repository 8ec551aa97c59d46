// The checks a Params::validate() repeats, with one wording for every package:
// "<Type>.<field>: <reason>" (params_from turns it into a ParamError naming the file
// and the parameter).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

namespace tactile_common {

/// Throws std::invalid_argument "<type>.<field>: must be finite and > 0, got <v>".
inline void require_finite_positive(const char* type, const char* field, double v) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw std::invalid_argument(std::string(type) + "." + field + ": must be finite and > 0, got " +
                                std::to_string(v));
  }
}

/// Throws std::invalid_argument "<type>.<low_field> (<low>) must be below <high_field> (<high>)"
/// unless low < high (a warning threshold below its error threshold, ...).
inline void require_below(const char* type, const char* low_field, double low, const char* high_field,
                          double high) {
  if (!(low < high)) {
    throw std::invalid_argument(std::string(type) + "." + low_field + " (" + std::to_string(low) +
                                ") must be below " + high_field + " (" + std::to_string(high) + ")");
  }
}

}  // namespace tactile_common
