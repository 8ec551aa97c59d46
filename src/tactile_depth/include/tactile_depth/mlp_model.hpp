// Whisker sensor model of paper 000 (Methods, "Whisker sensor model", eq. 12-14):
// a multilayer perceptron from the three drift-compensated barometer signals
// S_p^1..3 of one whisker to its tactile depth m [m].
//
//   S_n^i = (S_p^i - mu^i) / sigma^i,  i = 1, 2, 3            (000 eq. 12)
//   h^k   = ReLU(W^k h^(k-1) + b^k),   k = 1..L, h^0 = S_n     (000 eq. 13)
//   m     = W^(L+1) h^L + b^(L+1)                              (000 eq. 14)
//   depth = output_scale * m + output_offset                   (model file)
//
// Core layer: no ROS, no messages. Inference allocates nothing: the two
// activation buffers are sized once, when the model is built.
//
// Model file (JSON, the contract with the training tool in tools/; one file
// for both whiskers), see README.md "Model file":
//   {"format": "tactile_depth_mlp", "version": 1,
//    "whiskers": {"left": W, "right": W},
//    "units": {"input": "...", "output": "m"},
//    "input_signal": "compensated" | "calibrated",   (optional, default compensated)
//    "provenance": {...}}
//   W = {"input_mean": [3], "input_std": [3],
//        "layers": [{"weights": out x in, "bias": [out], "activation": "relu"|"identity"}, ...],
//        "output_scale": s, "output_offset": o}
#pragma once

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace tactile_depth {

/// Error in a model file: the message names the file (or source), the JSON
/// path (e.g. "whiskers.left.layers[2].weights[5]") and the reason.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Activation { kRelu, kIdentity };

/// One dense layer: y = act(W x + b), W is out x in, row-major (row = output neuron).
struct DenseLayer {
  int in = 0;
  int out = 0;
  std::vector<double> weights;  ///< out * in, row-major
  std::vector<double> bias;     ///< out
  Activation activation = Activation::kRelu;
};

/// The MLP of one whisker (000 eq. 12-14), with its input standardisation and
/// output scaling. Build with the constructor (validates shapes) or from a
/// model file through SensorModelFile.
class MlpModel {
 public:
  static constexpr int kInputs = 3;  ///< three barometers per whisker (000 eq. 12)

  MlpModel() = default;
  /// Validates: finite numbers, std > 0, shapes chain from 3 inputs to 1
  /// output, last layer identity (eq. 14). Throws std::invalid_argument naming
  /// the field. Allocates the activation buffers.
  MlpModel(const std::array<double, 3>& input_mean, const std::array<double, 3>& input_std,
           std::vector<DenseLayer> layers, double output_scale = 1.0, double output_offset = 0.0);

  /// Depth [m] for the compensated signals S_p [Pa] (000 eq. 12-14). No
  /// allocation. Requires a built model (valid()).
  double predict(const std::array<double, 3>& sp) const;

  bool valid() const { return !layers_.empty(); }
  const std::vector<DenseLayer>& layers() const { return layers_; }
  const std::array<double, 3>& input_mean() const { return mean_; }
  const std::array<double, 3>& input_std() const { return std_; }
  double output_scale() const { return scale_; }
  double output_offset() const { return offset_; }
  /// Number of parameters (weights + biases + 3 means + 3 stds + scale + offset).
  std::size_t parameter_count() const;
  /// Bytes of the parameters stored as float32, as on the microcontroller.
  std::size_t parameter_bytes_float32() const { return parameter_count() * 4; }
  /// Bytes this object holds (object, parameters as double, activation buffers).
  std::size_t memory_bytes() const;

 private:
  std::array<double, 3> mean_{};
  std::array<double, 3> std_{{1.0, 1.0, 1.0}};
  std::vector<DenseLayer> layers_;
  /// Each layer's weights transposed (in * out: the weights of input i to every output are
  /// contiguous), so predict() runs its inner loop over outputs, which vectorises.
  std::vector<std::vector<double>> weights_t_;
  double scale_ = 1.0;
  double offset_ = 0.0;
  // Activation buffers (ping-pong), sized to the widest layer at construction.
  mutable std::vector<double> buf_a_;
  mutable std::vector<double> buf_b_;
};

/// Which WhiskerSignal field feeds the MLP: the paper's band-passed S_p
/// (000 eq. 12, `compensated`) or the drift-corrected S_c before the band-pass
/// (000 eq. 5, `calibrated`), which keeps a held contact's level instead of
/// decaying it with the 0.05 Hz high-pass (see README "Input signal").
enum class InputSignal { kCompensated, kCalibrated };
const char* to_string(InputSignal s);

/// Both whiskers' models read from one model file.
struct SensorModelFile {
  static constexpr const char* kFormat = "tactile_depth_mlp";
  static constexpr int kVersion = 1;
  /// Largest accepted file (guards against a wrong path to a huge file).
  static constexpr std::size_t kMaxFileBytes = 64u * 1024u * 1024u;
  /// Largest accepted layer width and depth.
  static constexpr int kMaxWidth = 4096;
  static constexpr int kMaxLayers = 64;

  MlpModel left;
  MlpModel right;
  std::string input_units;
  InputSignal input_signal = InputSignal::kCompensated;  ///< "input_signal" (optional; default: the paper's S_p)
  std::string provenance_json;  ///< the provenance object, serialised (free-form)
  std::string source;           ///< file path or source name

  /// Reads and validates a model file. Throws ModelError
  /// "model file '<path>': <json.path>: <reason>".
  static SensorModelFile load(const std::string& path);
  /// Same from JSON text; `source` names it in errors.
  static SensorModelFile parse(const std::string& json_text, const std::string& source);
};

}  // namespace tactile_depth
