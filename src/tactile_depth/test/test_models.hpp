// Models for the tests and the benchmark, generated here (the tests never
// depend on the trained default model).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tactile_depth/mlp_model.hpp"

namespace tactile_depth::test_models {

/// A seeded random MLP with the given widths (first must be 3, last 1), ReLU
/// hidden layers, identity output, weights ~ U(-0.5, 0.5).
MlpModel random_mlp(uint32_t seed, const std::vector<int>& widths, double output_scale = 1.0,
                    double output_offset = 0.0);
/// The onboard shape 3 -> 32 -> 32 -> 32 -> 1.
MlpModel onboard_shape_mlp(uint32_t seed);
/// depth = scale * S_p[0] + offset (3 -> 1 identity, mean 0, std 1): lets a
/// test choose the measurement m exactly.
MlpModel linear_mlp(double scale = 1e-3, double offset = 0.0);
/// Serialises a model pair to the model file format (README "Model file").
std::string model_json(const MlpModel& left, const MlpModel& right);

}  // namespace tactile_depth::test_models
