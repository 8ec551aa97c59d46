#include "tactile_depth/mlp_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

namespace tactile_depth {

namespace {

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

[[noreturn]] void invalid(const std::string& field, const std::string& reason) {
  throw std::invalid_argument("MlpModel." + field + ": " + reason);
}

}  // namespace

MlpModel::MlpModel(const std::array<double, 3>& input_mean, const std::array<double, 3>& input_std,
                   std::vector<DenseLayer> layers, double output_scale, double output_offset)
    : mean_(input_mean), std_(input_std), layers_(std::move(layers)), scale_(output_scale),
      offset_(output_offset) {
  for (int i = 0; i < kInputs; ++i) {
    const std::string idx = "[" + std::to_string(i) + "]";
    if (!std::isfinite(mean_[i])) invalid("input_mean" + idx, "must be finite, got " + num(mean_[i]));
    if (!std::isfinite(std_[i]) || std_[i] <= 0.0) {
      invalid("input_std" + idx, "must be finite and > 0, got " + num(std_[i]));
    }
  }
  if (layers_.empty()) invalid("layers", "must have at least one layer");
  int width = kInputs;
  std::size_t widest = kInputs;
  for (std::size_t k = 0; k < layers_.size(); ++k) {
    const DenseLayer& l = layers_[k];
    const std::string f = "layers[" + std::to_string(k) + "]";
    if (l.in != width) invalid(f + ".in", "must be " + std::to_string(width) + " (previous layer's outputs), got " + std::to_string(l.in));
    if (l.out < 1) invalid(f + ".out", "must be >= 1, got " + std::to_string(l.out));
    if (l.weights.size() != static_cast<std::size_t>(l.out) * static_cast<std::size_t>(l.in)) {
      invalid(f + ".weights", "must have out*in = " + std::to_string(l.out * l.in) + " values, got " + std::to_string(l.weights.size()));
    }
    if (l.bias.size() != static_cast<std::size_t>(l.out)) {
      invalid(f + ".bias", "must have " + std::to_string(l.out) + " values, got " + std::to_string(l.bias.size()));
    }
    for (double w : l.weights) if (!std::isfinite(w)) invalid(f + ".weights", "must be finite, got " + num(w));
    for (double b : l.bias) if (!std::isfinite(b)) invalid(f + ".bias", "must be finite, got " + num(b));
    width = l.out;
    widest = std::max(widest, static_cast<std::size_t>(l.out));
  }
  if (width != 1) invalid("layers", "last layer must have 1 output (depth, 000 eq. 14), got " + std::to_string(width));
  if (layers_.back().activation != Activation::kIdentity) {
    invalid("layers[" + std::to_string(layers_.size() - 1) + "].activation", "output layer must be linear (identity, 000 eq. 14)");
  }
  if (!std::isfinite(scale_) || scale_ == 0.0) invalid("output_scale", "must be finite and != 0, got " + num(scale_));
  if (!std::isfinite(offset_)) invalid("output_offset", "must be finite, got " + num(offset_));
  buf_a_.assign(widest, 0.0);
  buf_b_.assign(widest, 0.0);
  for (const DenseLayer& l : layers_) {
    std::vector<double> t(l.weights.size());
    for (int o = 0; o < l.out; ++o) {
      for (int i = 0; i < l.in; ++i) {
        t[static_cast<std::size_t>(i) * l.out + o] = l.weights[static_cast<std::size_t>(o) * l.in + i];
      }
    }
    weights_t_.push_back(std::move(t));
  }
}

double MlpModel::predict(const std::array<double, 3>& sp) const {
  double* x = buf_a_.data();
  double* y = buf_b_.data();
  for (int i = 0; i < kInputs; ++i) x[i] = (sp[i] - mean_[i]) / std_[i];  // 000 eq. 12
  for (std::size_t k = 0; k < layers_.size(); ++k) {
    const DenseLayer& l = layers_[k];
    const double* wt = weights_t_[k].data();
    // W^k h^(k-1) + b^k (000 eq. 13, 14). Every output sums bias + w_0 x_0 + w_1 x_1 + ...
    // in this order, as a dot product per output row would: the loops are interchanged
    // so the compiler vectorises over outputs, and the results are bit-identical.
    for (int o = 0; o < l.out; ++o) y[o] = l.bias[static_cast<std::size_t>(o)];
    for (int i = 0; i < l.in; ++i) {
      const double xi = x[i];
      const double* col = wt + static_cast<std::size_t>(i) * static_cast<std::size_t>(l.out);
      for (int o = 0; o < l.out; ++o) y[o] += col[o] * xi;
    }
    if (l.activation == Activation::kRelu) {
      for (int o = 0; o < l.out; ++o) y[o] = y[o] < 0.0 ? 0.0 : y[o];  // ReLU (eq. 13); linear (eq. 14) otherwise
    }
    std::swap(x, y);
  }
  return scale_ * x[0] + offset_;
}

std::size_t MlpModel::parameter_count() const {
  std::size_t n = 2 * kInputs + 2;
  for (const DenseLayer& l : layers_) n += l.weights.size() + l.bias.size();
  return n;
}

std::size_t MlpModel::memory_bytes() const {
  std::size_t n = sizeof(*this);
  for (const DenseLayer& l : layers_) n += sizeof(DenseLayer) + (l.weights.capacity() + l.bias.capacity()) * sizeof(double);
  for (const auto& t : weights_t_) n += sizeof(t) + t.capacity() * sizeof(double);
  n += (buf_a_.capacity() + buf_b_.capacity()) * sizeof(double);
  return n;
}

// ---------------------------------------------------------------------------
// Model file

namespace {

using nlohmann::json;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& reason) const {
    throw ModelError("model file '" + source_ + "': " + (path.empty() ? std::string("(root)") : path) + ": " + reason);
  }

  static const char* kind(const json& j) {
    return j.type_name();
  }

  const json& member(const json& obj, const std::string& path, const char* key) const {
    auto it = obj.find(key);
    if (it == obj.end()) fail(path.empty() ? key : path + "." + key, "missing");
    return *it;
  }

  void object(const json& j, const std::string& path, const std::set<std::string>& allowed) const {
    if (!j.is_object()) fail(path, std::string("must be an object, got ") + kind(j));
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!allowed.count(it.key())) fail(path.empty() ? it.key() : path + "." + it.key(), "unknown key");
    }
  }

  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, std::string("must be a number, got ") + kind(j));
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(path, "must be finite, got " + num(v));
    return v;
  }

  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, std::string("must be a string, got ") + kind(j));
    return j.get<std::string>();
  }

  std::vector<double> numbers(const json& j, const std::string& path, std::size_t expected_size) const {
    if (!j.is_array()) fail(path, std::string("must be an array, got ") + kind(j));
    if (expected_size > 0 && j.size() != expected_size) {
      fail(path, "must have " + std::to_string(expected_size) + " numbers, got " + std::to_string(j.size()));
    }
    if (j.empty()) fail(path, "must not be empty");
    std::vector<double> out;
    out.reserve(j.size());
    for (std::size_t i = 0; i < j.size(); ++i) out.push_back(number(j[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }

  MlpModel whisker(const json& w, const std::string& path) const {
    object(w, path, {"input_mean", "input_std", "layers", "output_scale", "output_offset"});
    const std::vector<double> mean = numbers(member(w, path, "input_mean"), path + ".input_mean", 3);
    const std::vector<double> sd = numbers(member(w, path, "input_std"), path + ".input_std", 3);
    for (std::size_t i = 0; i < 3; ++i) {
      if (sd[i] <= 0.0) fail(path + ".input_std[" + std::to_string(i) + "]", "must be > 0 (000 eq. 12 divides by it), got " + num(sd[i]));
    }
    const json& layers = member(w, path, "layers");
    const std::string lpath = path + ".layers";
    if (!layers.is_array()) fail(lpath, std::string("must be an array, got ") + kind(layers));
    if (layers.empty()) fail(lpath, "must have at least one layer");
    if (layers.size() > static_cast<std::size_t>(SensorModelFile::kMaxLayers)) {
      fail(lpath, "too many layers (" + std::to_string(layers.size()) + " > " + std::to_string(SensorModelFile::kMaxLayers) + ")");
    }
    std::vector<DenseLayer> out;
    int width = MlpModel::kInputs;
    for (std::size_t k = 0; k < layers.size(); ++k) {
      const std::string p = lpath + "[" + std::to_string(k) + "]";
      const json& lj = layers[k];
      object(lj, p, {"weights", "bias", "activation"});
      const json& wj = member(lj, p, "weights");
      if (!wj.is_array()) fail(p + ".weights", std::string("must be an array of rows, got ") + kind(wj));
      if (wj.empty()) fail(p + ".weights", "must have at least one row");
      if (wj.size() > static_cast<std::size_t>(SensorModelFile::kMaxWidth)) {
        fail(p + ".weights", "too many rows (" + std::to_string(wj.size()) + " > " + std::to_string(SensorModelFile::kMaxWidth) + ")");
      }
      DenseLayer l;
      l.in = width;
      l.out = static_cast<int>(wj.size());
      l.weights.reserve(wj.size() * static_cast<std::size_t>(width));
      for (std::size_t r = 0; r < wj.size(); ++r) {
        const std::string rp = p + ".weights[" + std::to_string(r) + "]";
        const json& row = wj[r];
        if (!row.is_array()) fail(rp, std::string("must be an array (one row per output neuron), got ") + kind(row));
        if (row.size() != static_cast<std::size_t>(width)) {
          fail(rp, "must have " + std::to_string(width) + " numbers (" +
                       (k == 0 ? std::string("the 3 inputs") : "outputs of layers[" + std::to_string(k - 1) + "]") +
                       "), got " + std::to_string(row.size()));
        }
        for (std::size_t i = 0; i < row.size(); ++i) l.weights.push_back(number(row[i], rp + "[" + std::to_string(i) + "]"));
      }
      l.bias = numbers(member(lj, p, "bias"), p + ".bias", wj.size());
      const std::string act = string(member(lj, p, "activation"), p + ".activation");
      if (act == "relu") {
        l.activation = Activation::kRelu;
      } else if (act == "identity") {
        l.activation = Activation::kIdentity;
      } else {
        fail(p + ".activation", "unknown activation \"" + act + "\" (known: \"relu\", \"identity\")");
      }
      width = l.out;
      out.push_back(std::move(l));
    }
    const std::string last = lpath + "[" + std::to_string(layers.size() - 1) + "]";
    if (width != 1) fail(last + ".weights", "output layer must have 1 row (the depth, 000 eq. 14), got " + std::to_string(width));
    if (out.back().activation != Activation::kIdentity) fail(last + ".activation", "output layer must be \"identity\" (linear, 000 eq. 14)");
    const double scale = number(member(w, path, "output_scale"), path + ".output_scale");
    if (scale == 0.0) fail(path + ".output_scale", "must be != 0");
    const double offset = number(member(w, path, "output_offset"), path + ".output_offset");
    try {
      return MlpModel({{mean[0], mean[1], mean[2]}}, {{sd[0], sd[1], sd[2]}}, std::move(out), scale, offset);
    } catch (const std::invalid_argument& e) {
      fail(path, e.what());  // unreachable after the checks above; kept as a guard
    }
  }

  SensorModelFile file(const json& root) const {
    SensorModelFile f;
    f.source = source_;
    object(root, "", {"format", "version", "whiskers", "units", "input_signal", "provenance"});
    const std::string format = string(member(root, "", "format"), "format");
    if (format != SensorModelFile::kFormat) fail("format", "must be \"" + std::string(SensorModelFile::kFormat) + "\", got \"" + format + "\"");
    const json& version = member(root, "", "version");
    if (!version.is_number_integer()) fail("version", std::string("must be an integer, got ") + kind(version));
    if (version.get<int64_t>() != SensorModelFile::kVersion) {
      fail("version", "unsupported version " + std::to_string(version.get<int64_t>()) + " (this reader knows " + std::to_string(SensorModelFile::kVersion) + ")");
    }
    const json& units = member(root, "", "units");
    object(units, "units", {"input", "output"});
    f.input_units = string(member(units, "units", "input"), "units.input");
    const std::string out_units = string(member(units, "units", "output"), "units.output");
    if (out_units != "m") fail("units.output", "must be \"m\" (depth in metres), got \"" + out_units + "\"");
    if (root.contains("input_signal")) {
      const std::string in = string(root.at("input_signal"), "input_signal");
      if (in == "compensated") {
        f.input_signal = InputSignal::kCompensated;
      } else if (in == "calibrated") {
        f.input_signal = InputSignal::kCalibrated;
      } else {
        fail("input_signal", "must be \"compensated\" (S_p, 000 eq. 12) or \"calibrated\" (S_c, eq. 5), got \"" + in + "\"");
      }
    }
    const json& prov = member(root, "", "provenance");
    if (!prov.is_object()) fail("provenance", std::string("must be an object, got ") + kind(prov));
    f.provenance_json = prov.dump();
    const json& whiskers = member(root, "", "whiskers");
    object(whiskers, "whiskers", {"left", "right"});
    f.left = whisker(member(whiskers, "whiskers", "left"), "whiskers.left");
    f.right = whisker(member(whiskers, "whiskers", "right"), "whiskers.right");
    return f;
  }

 private:
  std::string source_;
};

}  // namespace

const char* to_string(InputSignal s) {
  return s == InputSignal::kCalibrated ? "calibrated" : "compensated";
}

SensorModelFile SensorModelFile::parse(const std::string& json_text, const std::string& source) {
  Reader reader(source);
  if (json_text.size() > kMaxFileBytes) {
    reader.fail("", "too large (" + std::to_string(json_text.size()) + " bytes > " + std::to_string(kMaxFileBytes) + ")");
  }
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {  // parse_error, out_of_range (number overflow)
    reader.fail("", std::string("not valid JSON: ") + e.what());
  }
  return reader.file(root);
}

SensorModelFile SensorModelFile::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError("model file '" + path + "': cannot open");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw ModelError("model file '" + path + "': cannot read");
  if (static_cast<std::size_t>(size) > kMaxFileBytes) {
    throw ModelError("model file '" + path + "': (root): too large (" + std::to_string(size) + " bytes > " + std::to_string(kMaxFileBytes) + ")");
  }
  in.seekg(0, std::ios::beg);
  std::string text(static_cast<std::size_t>(size), '\0');
  if (!in.read(&text[0], size)) throw ModelError("model file '" + path + "': cannot read");
  // Every flight of `tactile sim --trials N` and of a sweep builds its depth node anew from the
  // same file: the models parsed last are kept (keyed by path and the whole text, so an edited
  // file is parsed again) and copied out, instead of parsing the JSON per flight (1.6 % of a
  // recorded whisker flight's CPU, issue 18). Errors are never cached: a bad file throws each time.
  struct Cached {
    std::string path, text;
    SensorModelFile file;
  };
  static std::mutex mu;
  static std::vector<Cached> cache;  // a handful of model files at most
  {
    std::lock_guard<std::mutex> lk(mu);
    for (const auto& c : cache) {
      if (c.path == path && c.text == text) return c.file;
    }
  }
  SensorModelFile parsed = parse(text, path);
  std::lock_guard<std::mutex> lk(mu);
  if (cache.size() >= 4) cache.erase(cache.begin());
  cache.push_back({path, std::move(text), parsed});
  return parsed;
}

}  // namespace tactile_depth
