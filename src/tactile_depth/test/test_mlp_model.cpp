// MLP sensor model (000 eq. 12-14) and the model file reader.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>
#include <unistd.h>

#include "tactile_depth/mlp_model.hpp"

using tactile_depth::Activation;
using tactile_depth::DenseLayer;
using tactile_depth::MlpModel;
using tactile_depth::ModelError;
using tactile_depth::SensorModelFile;

namespace {

// Hand network 3 -> 2 -> 1:
//   mean = [1, 2, 3], std = [2, 4, 0.5]
//   W1 = [[1, -1, 0.5], [-2, 1, 1]], b1 = [0.5, -1.5], ReLU
//   W2 = [[2, 3]], b2 = [0.1], identity; depth = 0.01 * m + 0.02
const char* kHandWhisker = R"({"input_mean": [1, 2, 3], "input_std": [2, 4, 0.5],
  "layers": [{"weights": [[1, -1, 0.5], [-2, 1, 1]], "bias": [0.5, -1.5], "activation": "relu"},
             {"weights": [[2, 3]], "bias": [0.1], "activation": "identity"}],
  "output_scale": 0.01, "output_offset": 0.02})";

std::string hand_file(const std::string& left = kHandWhisker, const std::string& right = kHandWhisker,
                      const std::string& extra = "") {
  return std::string(R"({"format": "tactile_depth_mlp", "version": 1, "whiskers": {"left": )") + left +
         R"(, "right": )" + right + R"(}, "units": {"input": "Pa, TDORC compensated S_p", "output": "m"},)" +
         R"( "provenance": {"tool": "hand"})" + extra + "}";
}

MlpModel hand_model() {
  DenseLayer l1{3, 2, {1, -1, 0.5, -2, 1, 1}, {0.5, -1.5}, Activation::kRelu};
  DenseLayer l2{2, 1, {2, 3}, {0.1}, Activation::kIdentity};
  return MlpModel({{1, 2, 3}}, {{2, 4, 0.5}}, {l1, l2}, 0.01, 0.02);
}

// A whisker object of shape 3 -> 32 -> 32 -> 32 -> 1 with row `bad_row` of
// layer `bad_layer` shortened by one (bad_layer < 0: all fine).
std::string onboard_whisker(int bad_layer = -1, int bad_row = -1) {
  const int widths[] = {3, 32, 32, 32, 1};
  std::string s = R"({"input_mean": [0, 0, 0], "input_std": [1, 1, 1], "layers": [)";
  for (int k = 0; k < 4; ++k) {
    s += k ? ", " : "";
    s += R"({"weights": [)";
    for (int o = 0; o < widths[k + 1]; ++o) {
      s += o ? ", [" : "[";
      const int n = widths[k] - ((k == bad_layer && o == bad_row) ? 1 : 0);
      for (int i = 0; i < n; ++i) s += i ? ", 0.01" : "0.01";
      s += "]";
    }
    s += R"(], "bias": [)";
    for (int o = 0; o < widths[k + 1]; ++o) s += o ? ", 0" : "0";
    s += std::string(R"(], "activation": ")") + (k == 3 ? "identity" : "relu") + "\"}";
  }
  return s + R"(], "output_scale": 1.0, "output_offset": 0.0})";
}

void expect_error(const std::string& json, const std::string& fragment) {
  try {
    SensorModelFile::parse(json, "test.json");
    FAIL() << "no error, expected: " << fragment;
  } catch (const ModelError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("model file 'test.json': ", 0), 0u) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << "got: " << what << "\nexpected to contain: " << fragment;
  }
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

}  // namespace

TEST(MlpModel, HandComputedNetwork) {
  const MlpModel m = hand_model();
  // S_n = [1, 0, 2]: h = [1 + 0 + 1 + 0.5, relu(-2 + 0 + 2 - 1.5)] = [2.5, 0]; m = 5.1
  EXPECT_NEAR(m.predict({{3, 2, 4}}), 0.01 * 5.1 + 0.02, 1e-15);
  // S_n = [0, 0, 0]: h = [0.5, 0]; m = 1.1
  EXPECT_NEAR(m.predict({{1, 2, 3}}), 0.01 * 1.1 + 0.02, 1e-15);
  // S_n = [0, 1, 1]: h = [relu(-1 + 0.5 + 0.5), 1 + 1 - 1.5] = [0, 0.5]; m = 1.6
  EXPECT_NEAR(m.predict({{1, 6, 3.5}}), 0.01 * 1.6 + 0.02, 1e-15);
  // S_n = [-1, 0, 0]: h = [relu(-1 + 0.5), relu(2 - 1.5)] = [0, 0.5]; m = 1.6
  EXPECT_NEAR(m.predict({{-1, 2, 3}}), 0.036, 1e-15);
  // S_n = [-2, 0, 0]: h = [relu(-2 + 0.5), -2*-2 - 1.5] = [0, 2.5]; m = 7.6
  EXPECT_NEAR(m.predict({{-3, 2, 3}}), 0.01 * 7.6 + 0.02, 1e-15);
}

TEST(MlpModel, BothHiddenUnitsOff) {
  const MlpModel m = hand_model();
  // S_n = [0, 2, 0] (S_p = [1, 10, 3]): h1 = -2 + 0.5 = -1.5 -> 0, h2 = 2 - 1.5 = 0.5 -> m = 1.6
  EXPECT_NEAR(m.predict({{1, 10, 3}}), 0.036, 1e-15);
  // S_n = [0, 0, -1] (S_p = [1, 2, 2.5]): h1 = -0.5 + 0.5 = 0, h2 = -1 - 1.5 -> 0; m = 0.1
  EXPECT_NEAR(m.predict({{1, 2, 2.5}}), 0.021, 1e-15);
}

TEST(MlpModel, FileGivesSameNetwork) {
  const SensorModelFile f = SensorModelFile::parse(hand_file(), "hand.json");
  const MlpModel ref = hand_model();
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 5.0);
  for (int i = 0; i < 100; ++i) {
    const std::array<double, 3> x{{n(rng), n(rng), n(rng)}};
    EXPECT_EQ(f.left.predict(x), ref.predict(x));
    EXPECT_EQ(f.right.predict(x), ref.predict(x));
  }
  EXPECT_EQ(f.input_units, "Pa, TDORC compensated S_p");
  EXPECT_NE(f.provenance_json.find("hand"), std::string::npos);
  EXPECT_EQ(f.left.parameter_count(), 3u * 2 + 2 + 2 + 1 + 8);
}

TEST(MlpModel, OnboardShapeParses) {
  const SensorModelFile f = SensorModelFile::parse(hand_file(onboard_whisker(), onboard_whisker()), "x");
  ASSERT_EQ(f.left.layers().size(), 4u);
  EXPECT_EQ(f.left.layers()[1].in, 32);
  EXPECT_EQ(f.left.layers()[1].out, 32);
  // 3*32+32 + 2*(32*32+32) + 32+1 + 3 + 3 + 2
  EXPECT_EQ(f.left.parameter_count(), 2281u);
  EXPECT_EQ(f.left.parameter_bytes_float32(), 9124u);
}

// predict() runs its loops over outputs (vectorised); each output must still sum
// bias + w_0 x_0 + w_1 x_1 + ... in input order, so the result equals, bit for bit, the
// dot product per output row written out here (000 eq. 12-14) on random networks of
// the onboard shape (3-32-32-32-1) and odd widths, with negative pre-activations.
TEST(MlpModel, BitIdenticalToRowMajorDotProducts) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const std::vector<int>& widths : {std::vector<int>{3, 32, 32, 32, 1}, std::vector<int>{3, 7, 5, 1},
                                         std::vector<int>{3, 1}}) {
    std::vector<DenseLayer> layers;
    for (size_t k = 0; k + 1 < widths.size(); ++k) {
      DenseLayer l;
      l.in = widths[k];
      l.out = widths[k + 1];
      for (int j = 0; j < l.in * l.out; ++j) l.weights.push_back(n(rng));
      for (int j = 0; j < l.out; ++j) l.bias.push_back(0.3 * n(rng));
      l.activation = k + 2 < widths.size() ? Activation::kRelu : Activation::kIdentity;
      layers.push_back(l);
    }
    const std::array<double, 3> mean{{1.0, -2.0, 0.5}}, sd{{3.0, 0.7, 2.0}};
    const MlpModel m(mean, sd, layers, 0.01, 0.02);
    for (int t = 0; t < 200; ++t) {
      const std::array<double, 3> sp{{20 * n(rng), 20 * n(rng), 20 * n(rng)}};
      std::vector<double> x(3);
      for (int i = 0; i < 3; ++i) x[i] = (sp[i] - mean[i]) / sd[i];
      for (const DenseLayer& l : layers) {
        std::vector<double> y(l.out);
        for (int o = 0; o < l.out; ++o) {
          double acc = l.bias[o];
          for (int i = 0; i < l.in; ++i) acc += l.weights[o * l.in + i] * x[i];
          y[o] = (l.activation == Activation::kRelu && acc < 0.0) ? 0.0 : acc;
        }
        x = y;
      }
      const double expected = 0.01 * x[0] + 0.02;
      EXPECT_EQ(m.predict(sp), expected) << "widths " << widths.size() << " trial " << t;
    }
  }
}

TEST(MlpModel, ConstructorValidates) {
  DenseLayer l1{3, 2, {1, -1, 0.5, -2, 1, 1}, {0.5, -1.5}, Activation::kRelu};
  DenseLayer l2{2, 1, {2, 3}, {0.1}, Activation::kIdentity};
  EXPECT_THROW(MlpModel({{1, 2, 3}}, {{2, 0, 0.5}}, {l1, l2}), std::invalid_argument);
  EXPECT_THROW(MlpModel({{1, 2, NAN}}, {{2, 1, 0.5}}, {l1, l2}), std::invalid_argument);
  EXPECT_THROW(MlpModel({{1, 2, 3}}, {{2, 1, 0.5}}, {l2, l1}), std::invalid_argument);
  EXPECT_THROW(MlpModel({{1, 2, 3}}, {{2, 1, 0.5}}, {l1}), std::invalid_argument);  // 2 outputs
  DenseLayer relu_out = l2;
  relu_out.activation = Activation::kRelu;
  EXPECT_THROW(MlpModel({{1, 2, 3}}, {{2, 1, 0.5}}, {l1, relu_out}), std::invalid_argument);
  EXPECT_THROW(MlpModel({{1, 2, 3}}, {{2, 1, 0.5}}, {}), std::invalid_argument);
  try {
    MlpModel({{1, 2, 3}}, {{2, -1, 0.5}}, {l1, l2});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MlpModel.input_std[1]: must be finite and > 0"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, ErrorsNamePathAndReason) {
  const std::string ok = hand_file();
  expect_error("", "(root): not valid JSON");
  expect_error(ok.substr(0, ok.size() / 2), "(root): not valid JSON");
  expect_error("\x01\x02\xff garbage", "(root): not valid JSON");
  expect_error("[1, 2]", "(root): must be an object, got array");
  expect_error(replace(ok, R"("format": "tactile_depth_mlp", )", ""), "format: missing");
  expect_error(replace(ok, "tactile_depth_mlp", "onnx"), "format: must be \"tactile_depth_mlp\", got \"onnx\"");
  expect_error(replace(ok, R"("version": 1)", R"("version": 2)"), "version: unsupported version 2");
  expect_error(replace(ok, R"("version": 1)", R"("version": "1")"), "version: must be an integer, got string");
  expect_error(hand_file(kHandWhisker, kHandWhisker, R"(, "extra": 1)"), "extra: unknown key");
  expect_error(replace(ok, R"("output": "m")", R"("output": "mm")"), "units.output: must be \"m\"");
  expect_error(replace(ok, R"("provenance": {"tool": "hand"})", R"("provenance": "hand")"), "provenance: must be an object, got string");
  expect_error(replace(ok, R"(, "right": )", R"(, "rihgt": )"), "whiskers.rihgt: unknown key");
  const std::string w = kHandWhisker;
  auto left = [&](const std::string& from, const std::string& to) { return hand_file(replace(w, from, to)); };
  expect_error(left("[1, 2, 3]", "[1, 2]"), "whiskers.left.input_mean: must have 3 numbers, got 2");
  expect_error(left("[2, 4, 0.5]", "[2, 0, 0.5]"), "whiskers.left.input_std[1]: must be > 0");
  expect_error(left("[2, 4, 0.5]", "[2, -4, 0.5]"), "whiskers.left.input_std[1]: must be > 0");
  expect_error(left("[2, 4, 0.5]", "[2, 4, 1e999]"), "(root): not valid JSON: [json.exception.out_of_range.406] number overflow");
  expect_error(left("[[1, -1, 0.5], [-2, 1, 1]]", "[[1, -1, 0.5], [-2, 1, \"x\"]]"),
               "whiskers.left.layers[0].weights[1][2]: must be a number, got string");
  expect_error(left("[[1, -1, 0.5], [-2, 1, 1]]", "[[1, -1, 0.5], [-2, 1, null]]"),
               "whiskers.left.layers[0].weights[1][2]: must be a number, got null");
  expect_error(left("[[1, -1, 0.5], [-2, 1, 1]]", "[[1, -1, 0.5], 7]"),
               "whiskers.left.layers[0].weights[1]: must be an array");
  expect_error(left("[[1, -1, 0.5], [-2, 1, 1]]", "[[1, -1, 0.5], [-2, 1]]"),
               "whiskers.left.layers[0].weights[1]: must have 3 numbers (the 3 inputs), got 2");
  expect_error(left("[[2, 3]]", "[[2, 3, 4]]"),
               "whiskers.left.layers[1].weights[0]: must have 2 numbers (outputs of layers[0]), got 3");
  expect_error(left("[0.5, -1.5]", "[0.5, -1.5, 2]"), "whiskers.left.layers[0].bias: must have 2 numbers, got 3");
  expect_error(left("\"relu\"", "\"tanh\""), "whiskers.left.layers[0].activation: unknown activation \"tanh\"");
  expect_error(left("\"identity\"", "\"relu\""), "whiskers.left.layers[1].activation: output layer must be \"identity\"");
  expect_error(left("[[2, 3]], \"bias\": [0.1]", "[[2, 3], [1, 1]], \"bias\": [0.1, 0]"),
               "whiskers.left.layers[1].weights: output layer must have 1 row");
  expect_error(left("\"weights\": [[2, 3]]", "\"weihgts\": [[2, 3]]"), "whiskers.left.layers[1].weihgts: unknown key");
  expect_error(left(", \"activation\": \"identity\"", ""), "whiskers.left.layers[1].activation: missing");
  expect_error(hand_file(R"({"input_mean": [0, 0, 0], "input_std": [1, 1, 1], "layers": [], "output_scale": 1, "output_offset": 0})"),
               "whiskers.left.layers: must have at least one layer");
  expect_error(left("\"output_scale\": 0.01", "\"output_scale\": 0"), "whiskers.left.output_scale: must be != 0");
  expect_error(left("\"output_offset\": 0.02", "\"output_offset\": true"), "whiskers.left.output_offset: must be a number, got boolean");
  expect_error(left(", \"output_offset\": 0.02", ""), "whiskers.left.output_offset: missing");
  expect_error(hand_file(kHandWhisker, onboard_whisker(2, 5)),
               "whiskers.right.layers[2].weights[5]: must have 32 numbers (outputs of layers[1]), got 31");
}

TEST(ModelFile, InputSignal) {
  // Absent: the paper's S_p (000 eq. 12); "calibrated": S_c (eq. 5); anything else is an error.
  EXPECT_EQ(SensorModelFile::parse(hand_file(), "x").input_signal, tactile_depth::InputSignal::kCompensated);
  const std::string cal = hand_file(kHandWhisker, kHandWhisker, R"(, "input_signal": "calibrated")");
  EXPECT_EQ(SensorModelFile::parse(cal, "x").input_signal, tactile_depth::InputSignal::kCalibrated);
  const std::string cmp = hand_file(kHandWhisker, kHandWhisker, R"(, "input_signal": "compensated")");
  EXPECT_EQ(SensorModelFile::parse(cmp, "x").input_signal, tactile_depth::InputSignal::kCompensated);
  expect_error(hand_file(kHandWhisker, kHandWhisker, R"(, "input_signal": "raw")"),
               "input_signal: must be \"compensated\" (S_p, 000 eq. 12) or \"calibrated\" (S_c, eq. 5), got \"raw\"");
  expect_error(hand_file(kHandWhisker, kHandWhisker, R"(, "input_signal": 3)"), "input_signal:");
}

TEST(ModelFile, LoadFromDisk) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tactile_depth_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path good = dir / "good.json";
  std::ofstream(good) << hand_file();
  const SensorModelFile f = SensorModelFile::load(good.string());
  EXPECT_EQ(f.source, good.string());
  EXPECT_NEAR(f.left.predict({{3, 2, 4}}), 0.071, 1e-15);

  try {
    SensorModelFile::load((dir / "missing.json").string());
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json': cannot open"), std::string::npos) << e.what();
  }
  // Oversized (sparse file, 1 byte over the limit).
  const fs::path big = dir / "big.json";
  {
    std::ofstream out(big, std::ios::binary);
    out.seekp(static_cast<std::streamoff>(SensorModelFile::kMaxFileBytes));
    out.put(' ');
  }
  try {
    SensorModelFile::load(big.string());
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << e.what();
  }
  // Loaded again after an edit: the new text is parsed (the kept models are keyed by the text),
  // and an edit that breaks the file throws although the good version was loaded before.
  {
    std::ofstream(good) << replace(hand_file(), "\"output_offset\": 0.02", "\"output_offset\": 0.52");
    const SensorModelFile edited = SensorModelFile::load(good.string());
    EXPECT_NEAR(edited.left.predict({{3, 2, 4}}), 0.571, 1e-12);
    std::ofstream(good) << hand_file();
    EXPECT_EQ(SensorModelFile::load(good.string()).left.predict({{3, 2, 4}}), f.left.predict({{3, 2, 4}}));
    std::ofstream(good) << replace(hand_file(), "\"relu\"", "\"sigmoid\"");
    EXPECT_THROW(SensorModelFile::load(good.string()), ModelError);
  }
  // Errors from a file name the file.
  const fs::path bad = dir / "bad.json";
  std::ofstream(bad) << replace(hand_file(), "\"relu\"", "\"sigmoid\"");
  try {
    SensorModelFile::load(bad.string());
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("model file '" + bad.string() + "': whiskers.left.layers[0].activation"),
              std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}
