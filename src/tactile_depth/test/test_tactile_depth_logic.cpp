// Node logic: parameters, pairing of the two whiskers, stale / NaN input, output fields.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "tactile_common/parameter_testing.hpp"
#include "tactile_common/time.hpp"
#include "tactile_depth/tactile_depth_logic.hpp"
#include "test_models.hpp"

using namespace tactile_depth;
using tactile_msgs::msg::TactileDepth;
using tactile_msgs::msg::WhiskerSignal;

namespace {

constexpr int64_t kMs = 1000000;

SensorModelFile linear_models() {
  SensorModelFile f;
  f.left = test_models::linear_mlp();
  f.right = test_models::linear_mlp();
  f.source = "test";
  return f;
}

TactileDepthLogic::Params params(EstimatorModel model = EstimatorModel::kKfFull) {
  TactileDepthLogic::Params p;
  p.estimator.model = model;
  return p;
}

WhiskerSignal signal(int side, int64_t ns, double sp0, bool contact = true) {
  WhiskerSignal s;
  tactile_common::to_stamp(ns, s.header.stamp);
  s.whisker_id = static_cast<uint8_t>(side);
  s.compensated = {{sp0, 1.0, 2.0}};
  s.contact = contact;
  s.calibrated_ready = true;
  return s;
}

nav_msgs::msg::Odometry odom(int64_t ns, double x, double y, double yaw) {
  nav_msgs::msg::Odometry o;
  tactile_common::to_stamp(ns, o.header.stamp);
  o.header.frame_id = "odom";
  o.child_frame_id = "body";
  o.pose.pose.position.x = x;
  o.pose.pose.position.y = y;
  o.pose.pose.orientation.z = std::sin(yaw / 2);
  o.pose.pose.orientation.w = std::cos(yaw / 2);
  return o;
}

}  // namespace

TEST(TactileDepthLogic, DefaultParameters) {
  const tactile_common::ParamMap m = TactileDepthLogic::default_parameters();
  EXPECT_EQ(m.get_string("model_file"), "default_model.json");
  EXPECT_EQ(m.get_string("estimator"), "kf_full");
  EXPECT_EQ(m.get_double("kf.q_mm2"), 0.01);
  EXPECT_EQ(m.get_double("kf.r_mm2"), 1.0);
  EXPECT_EQ(m.get_double("kf.p0_mm2"), 50.0);
  EXPECT_EQ(m.get_double("whisker_spacing"), 0.05);
  EXPECT_EQ(m.get_double("whisker_base_x"), 0.05);
  EXPECT_EQ(m.get_double("max_input_age_s"), 0.1);
  EXPECT_EQ(m.get_double("kf.slip_fraction"), 0.0);  // off: the shipped courses lose with it (README "Slip gate")
  EXPECT_EQ(m.get_int("kf.slip_window_samples", 1, 100), 25);
  EXPECT_EQ(m.get_double("kf.slip_r_mm2"), 1.0e4);
  EXPECT_EQ(m.get_int("kf.slip_max_samples", 0, 100), 0);               // no limit (README "Slip gate")
  EXPECT_EQ(m.get_double("kf.saturation_sum_pa"), 0.0);         // off (README "Saturated contact")
  EXPECT_EQ(m.get_double("kf.saturation_r_mm2"), 1.0e4);
  EXPECT_EQ(m.values().size(), 14u);
}

TEST(TactileDepthLogic, ParamsFromAndModelFileResolution) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tactile_depth_logic_" + std::to_string(::getpid()));
  fs::create_directories(dir / "share/tactile_depth/models");
  const fs::path model = dir / "share/tactile_depth/models/test_model.json";
  std::ofstream(model) << test_models::model_json(test_models::linear_mlp(), test_models::linear_mlp(2e-3));

  tactile_common::ParamMap m = TactileDepthLogic::default_parameters();
  m.set("model_file", model.string());  // absolute
  m.set("estimator", std::string("kf_simplified"));
  TactileDepthLogic::Params p = TactileDepthLogic::params_from(m);
  EXPECT_EQ(p.model_file, model.string());
  EXPECT_EQ(p.estimator.model, EstimatorModel::kKfSimplified);

  // Relative name through AMENT_PREFIX_PATH.
  const char* old = std::getenv("AMENT_PREFIX_PATH");
  const std::string saved = old ? old : "";
  ::setenv("AMENT_PREFIX_PATH", ("/nonexistent:" + dir.string()).c_str(), 1);
  EXPECT_EQ(TactileDepthLogic::resolve_model_file("test_model.json"), model.string());
  EXPECT_EQ(TactileDepthLogic::resolve_model_file("no_such_model.json"), "");
  m.set("model_file", std::string("test_model.json"));
  p = TactileDepthLogic::params_from(m);
  TactileDepthLogic logic(p);  // loads the file
  EXPECT_DOUBLE_EQ(logic.models().right.predict({{10, 0, 0}}), 0.02);
  if (old) ::setenv("AMENT_PREFIX_PATH", saved.c_str(), 1); else ::unsetenv("AMENT_PREFIX_PATH");

  auto expect_param_error = [&](const std::string& key, tactile_common::ParamValue v, const std::string& fragment) {
    tactile_common::ParamMap bad = TactileDepthLogic::default_parameters();
    bad.set("model_file", model.string());
    bad.set(key, v);
    try {
      TactileDepthLogic::params_from(bad);
      FAIL() << key;
    } catch (const tactile_common::ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_param_error("estimator", std::string("kalman"), "tactile_depth.ros__parameters.estimator: must be \"mlp\"");
  expect_param_error("kf.q_mm2", -1.0, "tactile_depth.ros__parameters.kf.q_mm2: must be finite and > 0");
  expect_param_error("kf.p0_mm2", 0.0, "kf.p0_mm2: must be finite and > 0");
  expect_param_error("kf.slip_fraction", 1.5, "tactile_depth.ros__parameters.kf.slip_fraction: must be in [0, 1)");
  expect_param_error("kf.slip_window_samples", int64_t{0}, "tactile_depth.ros__parameters.kf.slip_window_samples: must be in [1, 100], got 0");
  expect_param_error("kf.slip_window_samples", int64_t{1} << 40, "kf.slip_window_samples: must be in [1, 100]");
  // 2^32 + 25 is 25 as an int: rejected as given, before it is narrowed.
  expect_param_error("kf.slip_window_samples", (int64_t{1} << 32) + 25, "kf.slip_window_samples: must be in [1, 100], got 4294967321");
  expect_param_error("kf.slip_r_mm2", -1.0, "kf.slip_r_mm2: must be finite and > 0");
  expect_param_error("kf.slip_max_samples", int64_t{-1}, "tactile_depth.ros__parameters.kf.slip_max_samples: must be in [0, 100], got -1");
  expect_param_error("kf.slip_max_samples", int64_t{1} << 40, "kf.slip_max_samples: must be in [0, 100]");
  expect_param_error("kf.saturation_sum_pa", -1.0, "kf.saturation_sum_pa: must be finite and >= 0");
  expect_param_error("kf.saturation_r_mm2", 0.0, "kf.saturation_r_mm2: must be finite and > 0");
  expect_param_error("whisker_spacing", 0.0, "whisker_spacing: must be finite and > 0");
  expect_param_error("max_input_age_s", -0.1, "max_input_age_s: must be finite and > 0");
  expect_param_error("model_file", std::string("nothing_here.json"), "model_file: file \"nothing_here.json\" not found");
  fs::remove_all(dir);
}

TEST(TactileDepthLogic, PairsEqualStampsAndFillsEveryField) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_odometry(odom(0, 1.0, 2.0, 0.5));
  EXPECT_FALSE(logic.on_left_signal(signal(0, 20 * kMs, 80)));
  auto out = logic.on_right_signal(signal(1, 20 * kMs, 90));
  ASSERT_TRUE(out);
  EXPECT_EQ(tactile_common::from_stamp(out->header.stamp), 20 * kMs);
  EXPECT_EQ(out->header.frame_id, "body");
  EXPECT_EQ(out->model, TactileDepth::MODEL_MLP_KF_FULL);
  EXPECT_TRUE(out->contact_left);
  EXPECT_TRUE(out->contact_right);
  EXPECT_TRUE(out->filter_initialized);
  EXPECT_DOUBLE_EQ(out->depth_left, 0.080);
  EXPECT_DOUBLE_EQ(out->depth_right, 0.090);
  EXPECT_DOUBLE_EQ(out->variance_left, 50e-6);
  EXPECT_DOUBLE_EQ(out->variance_right, 50e-6);
  EXPECT_NEAR(out->wall_angle, std::atan(-0.01 / 0.05), 1e-12);
  const double g = 0.05 / (0.05 * 0.05 + 0.01 * 0.01);
  EXPECT_NEAR(out->wall_angle_variance, g * g * 100e-6, 1e-15);
  // Contact point: base (0.05 + d, +-0.025) in the body, rotated by 0.5, plus (1, 2).
  const double c = std::cos(0.5), s = std::sin(0.5);
  EXPECT_NEAR(out->contact_point_left.x, 1.0 + c * 0.13 - s * 0.025, 1e-12);
  EXPECT_NEAR(out->contact_point_left.y, 2.0 + s * 0.13 + c * 0.025, 1e-12);
  EXPECT_NEAR(out->contact_point_right.x, 1.0 + c * 0.14 + s * 0.025, 1e-12);
  EXPECT_NEAR(out->contact_point_right.y, 2.0 + s * 0.14 - c * 0.025, 1e-12);
  EXPECT_EQ(out->contact_point_left.z, 0.0);
  // The contact points are in the odometry's frame, not in the header's body frame.
  EXPECT_EQ(out->contact_frame_id, "odom");
  // Right first, then left, works the same.
  EXPECT_FALSE(logic.on_right_signal(signal(1, 40 * kMs, 90)));
  out = logic.on_left_signal(signal(0, 40 * kMs, 80));
  ASSERT_TRUE(out);
  EXPECT_EQ(logic.stats().published, 2u);
  EXPECT_EQ(logic.stats().received_left, 2u);
  EXPECT_EQ(logic.stats().received_right, 2u);
}

TEST(TactileDepthLogic, EstimatorParameterSelectsModel) {
  const std::pair<EstimatorModel, uint8_t> cases[] = {
      {EstimatorModel::kMlp, TactileDepth::MODEL_MLP},
      {EstimatorModel::kKfSimplified, TactileDepth::MODEL_MLP_KF_SIMPLIFIED},
      {EstimatorModel::kKfFull, TactileDepth::MODEL_MLP_KF_FULL}};
  for (const auto& [model, constant] : cases) {
    TactileDepthLogic logic(params(model), linear_models());
    logic.on_odometry(odom(0, 0, 0, 0));
    logic.on_left_signal(signal(0, 0, 80));
    const auto out = logic.on_right_signal(signal(1, 0, 80));
    ASSERT_TRUE(out);
    EXPECT_EQ(out->model, constant);
    EXPECT_EQ(out->filter_initialized, model != EstimatorModel::kMlp);
  }
}

TEST(TactileDepthLogic, MissingPartnerAndStaleInput) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_odometry(odom(0, 0, 0, 0));
  // Left at 20 ms, its partner never comes; next left at 40 ms replaces it.
  EXPECT_FALSE(logic.on_left_signal(signal(0, 20 * kMs, 80)));
  EXPECT_FALSE(logic.on_left_signal(signal(0, 40 * kMs, 80)));
  EXPECT_EQ(logic.stats().dropped_unpaired, 1u);
  // Right at 60 ms: the pending left (40 ms) can never pair now.
  EXPECT_FALSE(logic.on_right_signal(signal(1, 60 * kMs, 80)));
  EXPECT_EQ(logic.stats().dropped_unpaired, 2u);
  // Left at 50 ms arrives after the right moved on to 60 ms: unpaired.
  EXPECT_FALSE(logic.on_left_signal(signal(0, 50 * kMs, 80)));
  EXPECT_EQ(logic.stats().dropped_unpaired, 3u);
  EXPECT_TRUE(logic.on_left_signal(signal(0, 60 * kMs, 80)));
  // A pending right superseded 0.5 s later is stale.
  EXPECT_FALSE(logic.on_right_signal(signal(1, 80 * kMs, 80)));
  EXPECT_FALSE(logic.on_left_signal(signal(0, 580 * kMs, 80)));
  EXPECT_EQ(logic.stats().dropped_stale, 1u);
  EXPECT_EQ(logic.stats().published, 1u);
  // Out of order after a published pair.
  EXPECT_FALSE(logic.on_right_signal(signal(1, 60 * kMs, 80)));
  EXPECT_EQ(logic.stats().dropped_out_of_order, 1u);
}

TEST(TactileDepthLogic, NonFiniteAndWrongWhiskerDropped) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_odometry(odom(0, 0, 0, 0));
  WhiskerSignal bad = signal(0, 0, 80);
  bad.compensated[2] = std::nan("");
  EXPECT_FALSE(logic.on_left_signal(bad));
  bad.compensated[2] = INFINITY;
  EXPECT_FALSE(logic.on_left_signal(bad));
  EXPECT_EQ(logic.stats().dropped_nonfinite, 2u);
  EXPECT_FALSE(logic.on_right_signal(signal(0, 0, 80)));  // left id on the right topic
  EXPECT_EQ(logic.stats().dropped_wrong_whisker, 1u);
  // The NaN sample never paired: the right partner at the same stamp waits alone.
  EXPECT_FALSE(logic.on_right_signal(signal(1, 0, 80)));
  EXPECT_EQ(logic.stats().published, 0u);
  // NaN odometry is dropped; the last good pose stays.
  nav_msgs::msg::Odometry o = odom(0, 5, 5, 0);
  o.pose.pose.position.x = std::nan("");
  logic.on_odometry(o);
  EXPECT_EQ(logic.stats().dropped_nonfinite, 3u);
  const auto out = logic.on_left_signal(signal(0, 0, 80));
  ASSERT_TRUE(out);
  EXPECT_NEAR(out->contact_point_left.x, 0.13, 1e-12);
}

TEST(TactileDepthLogic, NoOrStaleOdometryKeepsFilterOff) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_left_signal(signal(0, 0, 80));
  auto out = logic.on_right_signal(signal(1, 0, 80));
  ASSERT_TRUE(out);
  EXPECT_FALSE(out->filter_initialized);  // no odometry yet
  EXPECT_EQ(logic.stats().ticks_without_odometry, 1u);
  logic.on_odometry(odom(20 * kMs, 0, 0, 0));
  logic.on_left_signal(signal(0, 20 * kMs, 80));
  out = logic.on_right_signal(signal(1, 20 * kMs, 80));
  EXPECT_TRUE(out->filter_initialized);
  // Odometry 0.2 s old (> max_input_age_s = 0.1): stale, the filter resets.
  logic.on_left_signal(signal(0, 220 * kMs, 80));
  out = logic.on_right_signal(signal(1, 220 * kMs, 80));
  EXPECT_FALSE(out->filter_initialized);
  EXPECT_EQ(logic.stats().ticks_without_odometry, 2u);
}

TEST(TactileDepthLogic, NotReadyOrNoContactResetsFilter) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_odometry(odom(0, 0, 0, 0));
  logic.on_left_signal(signal(0, 0, 80));
  EXPECT_TRUE(logic.on_right_signal(signal(1, 0, 80))->filter_initialized);
  WhiskerSignal l = signal(0, 20 * kMs, 80);
  l.calibrated_ready = false;  // TDORC window refilling: no contact
  logic.on_left_signal(l);
  auto out = logic.on_right_signal(signal(1, 20 * kMs, 80));
  EXPECT_FALSE(out->contact_left);
  EXPECT_FALSE(out->filter_initialized);
  logic.on_left_signal(signal(0, 40 * kMs, 80, false));
  out = logic.on_right_signal(signal(1, 40 * kMs, 80));
  EXPECT_FALSE(out->contact_left);
  EXPECT_TRUE(out->contact_right);
  EXPECT_FALSE(out->filter_initialized);
}

TEST(TactileDepthLogic, RepoConfigMatchesDefaults) {
  // The tests run in the package source dir; the config lives in the repo root.
  const tactile_common::ParamMap d = TactileDepthLogic::default_parameters();
  const tactile_common::ParamMap m =
      tactile_common::load_node_parameters("../../config/tactile_depth.yaml", "/tactile_depth", d);
  for (const auto& [key, value] : d.values()) {
    EXPECT_TRUE(m.values().at(key) == value) << key << " differs from default_parameters()";
  }
}

TEST(TactileDepthLogic, ModelFileChoosesTheInputField) {
  // The same signals with different S_p and S_c: the file's input_signal picks the field.
  auto sig = [](int side, int64_t ns, double sp0, double sc0) {
    WhiskerSignal s = signal(side, ns, sp0);
    s.calibrated = {{sc0, 1.0, 2.0}};
    return s;
  };
  SensorModelFile f = linear_models();
  TactileDepthLogic on_sp(params(EstimatorModel::kMlp), f);
  on_sp.on_left_signal(sig(0, 20 * kMs, 80, 60));
  auto a = on_sp.on_right_signal(sig(1, 20 * kMs, 90, 70));
  ASSERT_TRUE(a);
  EXPECT_DOUBLE_EQ(a->depth_left, 0.080);
  f.input_signal = tactile_depth::InputSignal::kCalibrated;
  TactileDepthLogic on_sc(params(EstimatorModel::kMlp), f);
  on_sc.on_left_signal(sig(0, 20 * kMs, 80, 60));
  auto b = on_sc.on_right_signal(sig(1, 20 * kMs, 90, 70));
  ASSERT_TRUE(b);
  EXPECT_DOUBLE_EQ(b->depth_left, 0.060);
  EXPECT_DOUBLE_EQ(b->depth_right, 0.070);
  // NaN in the field the model reads is dropped; NaN in the other one is not.
  WhiskerSignal bad = sig(0, 40 * kMs, 80, 60);
  bad.calibrated[1] = std::nan("");
  EXPECT_FALSE(on_sc.on_left_signal(bad));
  EXPECT_EQ(on_sc.stats().dropped_nonfinite, 1u);
  EXPECT_FALSE(on_sp.on_left_signal(bad));
  EXPECT_EQ(on_sp.stats().dropped_nonfinite, 0u);
}

TEST(TactileDepthLogic, ShippedDefaultModelFollowsTheContract) {
  // Contract check with the training tool's output; the other tests never use it.
  if (!std::ifstream("models/default_model.json")) GTEST_SKIP() << "no models/default_model.json yet";
  const SensorModelFile f = SensorModelFile::load("models/default_model.json");
  EXPECT_EQ(f.left.layers().front().in, 3);
  EXPECT_EQ(f.left.layers().back().out, 1);
  EXPECT_TRUE(std::isfinite(f.right.predict({{30.0, 5.0, -3.0}})));
  EXPECT_EQ(f.input_signal, tactile_depth::InputSignal::kCalibrated);  // README "Input signal"
}

// The parameter spec: every key described, no described range wider than what
// params_from()/validate() accept, and max_input_age_s the only live key.
TEST(TactileDepthLogic, EveryParameterIsDescribedWithTheRangeValidateAccepts) {
  namespace fs = std::filesystem;
  const fs::path model = fs::temp_directory_path() / ("tactile_depth_spec_" + std::to_string(::getpid()) + ".json");
  std::ofstream(model) << test_models::model_json(test_models::linear_mlp(), test_models::linear_mlp());
  tactile_common::ParamMap d = TactileDepthLogic::default_parameters();
  EXPECT_TRUE(tactile_common::undescribed(d).empty());
  d.set("model_file", model.string());
  ASSERT_NO_THROW(TactileDepthLogic::params_from(d));  // else every probe below is refused for the file
  for (const auto& leak :
       tactile_common::range_leaks(d, [](const tactile_common::ParamMap& m) { TactileDepthLogic::params_from(m); })) {
    ADD_FAILURE() << leak.key << " = " << leak.value << " is outside its described range but accepted";
  }
  std::vector<std::string> live;
  for (const auto& [key, info] : d.infos()) {
    if (info.live) live.push_back(key);
  }
  EXPECT_EQ(live, std::vector<std::string>{"max_input_age_s"});
  fs::remove(model);
}

// max_input_age_s applies from the next message: odometry 0.2 s old is stale at 0.1 s,
// fresh at 0.5 s. Any other change is refused and nothing changes.
TEST(TactileDepthLogic, LiveMaxInputAgeAppliesFromTheNextMessage) {
  TactileDepthLogic logic(params(), linear_models());
  logic.on_odometry(odom(0, 0, 0, 0));
  auto p = logic.params();
  p.max_input_age_s = 0.5;
  logic.set_params(p);
  EXPECT_EQ(logic.params().max_input_age_s, 0.5);
  logic.on_left_signal(signal(0, 200 * kMs, 80));
  auto out = logic.on_right_signal(signal(1, 200 * kMs, 80));
  ASSERT_TRUE(out);
  EXPECT_TRUE(out->filter_initialized);
  EXPECT_EQ(logic.stats().ticks_without_odometry, 0u);

  auto q = logic.params();
  q.max_input_age_s = 0.2;
  q.estimator.r_mm2 = 2.0;  // the Kalman filters were set up at start
  EXPECT_THROW(logic.set_params(q), std::invalid_argument);
  q = logic.params();
  q.max_input_age_s = -1.0;
  EXPECT_THROW(logic.set_params(q), std::invalid_argument);
  EXPECT_EQ(logic.params().max_input_age_s, 0.5);
}
