#include "test_models.hpp"

#include <random>
#include <sstream>

namespace tactile_depth::test_models {

MlpModel random_mlp(uint32_t seed, const std::vector<int>& widths, double output_scale, double output_offset) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<DenseLayer> layers;
  for (std::size_t k = 1; k < widths.size(); ++k) {
    DenseLayer l;
    l.in = widths[k - 1];
    l.out = widths[k];
    for (int i = 0; i < l.in * l.out; ++i) l.weights.push_back(u(rng));
    for (int i = 0; i < l.out; ++i) l.bias.push_back(u(rng));
    l.activation = k + 1 == widths.size() ? Activation::kIdentity : Activation::kRelu;
    layers.push_back(l);
  }
  return MlpModel({{10.0, -5.0, 3.0}}, {{20.0, 15.0, 30.0}}, layers, output_scale, output_offset);
}

MlpModel onboard_shape_mlp(uint32_t seed) { return random_mlp(seed, {3, 32, 32, 32, 1}, 0.01, 0.08); }

MlpModel linear_mlp(double scale, double offset) {
  DenseLayer l;
  l.in = 3;
  l.out = 1;
  l.weights = {1.0, 0.0, 0.0};
  l.bias = {0.0};
  l.activation = Activation::kIdentity;
  return MlpModel({{0.0, 0.0, 0.0}}, {{1.0, 1.0, 1.0}}, {l}, scale, offset);
}

namespace {

void whisker_json(std::ostringstream& os, const MlpModel& m) {
  os << "{\"input_mean\": [" << m.input_mean()[0] << ", " << m.input_mean()[1] << ", " << m.input_mean()[2] << "],"
     << " \"input_std\": [" << m.input_std()[0] << ", " << m.input_std()[1] << ", " << m.input_std()[2] << "],"
     << " \"layers\": [";
  for (std::size_t k = 0; k < m.layers().size(); ++k) {
    const DenseLayer& l = m.layers()[k];
    os << (k ? ", " : "") << "{\"weights\": [";
    for (int o = 0; o < l.out; ++o) {
      os << (o ? ", " : "") << "[";
      for (int i = 0; i < l.in; ++i) os << (i ? ", " : "") << l.weights[static_cast<std::size_t>(o * l.in + i)];
      os << "]";
    }
    os << "], \"bias\": [";
    for (int o = 0; o < l.out; ++o) os << (o ? ", " : "") << l.bias[static_cast<std::size_t>(o)];
    os << "], \"activation\": \"" << (l.activation == Activation::kRelu ? "relu" : "identity") << "\"}";
  }
  os << "], \"output_scale\": " << m.output_scale() << ", \"output_offset\": " << m.output_offset() << "}";
}

}  // namespace

std::string model_json(const MlpModel& left, const MlpModel& right) {
  std::ostringstream os;
  os.precision(17);
  os << "{\"format\": \"tactile_depth_mlp\", \"version\": 1, \"whiskers\": {\"left\": ";
  whisker_json(os, left);
  os << ", \"right\": ";
  whisker_json(os, right);
  os << "}, \"units\": {\"input\": \"Pa (TDORC compensated S_p)\", \"output\": \"m\"},"
     << " \"provenance\": {\"tool\": \"test_models.cpp\", \"seed\": 0}}";
  return os.str();
}

}  // namespace tactile_depth::test_models
