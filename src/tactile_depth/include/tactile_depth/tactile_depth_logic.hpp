// Node logic of tactile_depth: the two whiskers' WhiskerSignal (TDORC output)
// and the odometry in, TactileDepth out (paper 000 eq. 12-30). No rclcpp:
// the rclcpp component and the standalone host both use this class.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_depth/depth_estimator.hpp"
#include "tactile_msgs/msg/tactile_depth.hpp"
#include "tactile_msgs/msg/whisker_signal.hpp"

namespace tactile_depth {

class TactileDepthLogic {
 public:
  static constexpr const char* kNodeName = "tactile_depth";
  static constexpr const char* kLeftSignalTopic = "whisker/left/signal";    // tactile_msgs/msg/WhiskerSignal
  static constexpr const char* kRightSignalTopic = "whisker/right/signal";  // tactile_msgs/msg/WhiskerSignal
  static constexpr const char* kOdometryTopic = "odom";                     // nav_msgs/msg/Odometry
  static constexpr const char* kOutputTopic = "whisker/depth";              // tactile_msgs/msg/TactileDepth
  /// frame_id of the output when the odometry names no child frame.
  static constexpr const char* kDefaultBodyFrame = "base_link";

  struct Params {
    tactile_depth::Params estimator;
    /// Resolved path of the model file (params_from resolves `model_file`).
    std::string model_file;
    /// A whisker sample waits at most this long (stamp difference) for its
    /// partner; odometry older than this (relative to the sample stamp) is
    /// stale. Our choice: 0.1 s = 5 samples at 50 Hz.
    double max_input_age_s = 0.1;
    void validate() const;
  };

  struct Stats {
    uint64_t received_left = 0;
    uint64_t received_right = 0;
    uint64_t received_odometry = 0;
    uint64_t published = 0;
    uint64_t dropped_nonfinite = 0;       ///< NaN/inf in S_p (signal) or in the pose (odometry)
    uint64_t dropped_wrong_whisker = 0;   ///< whisker_id does not match the topic
    uint64_t dropped_out_of_order = 0;    ///< stamp not after the last published pair
    uint64_t dropped_unpaired = 0;        ///< a sample whose partner never came (or came with another stamp)
    uint64_t dropped_stale = 0;           ///< a pending sample older than max_input_age_s dropped
    uint64_t ticks_without_odometry = 0;  ///< published with no or stale odometry (filters reset)
    uint64_t prediction_skipped = 0;      ///< process model could not predict (whisker parallel to the wall)
  };

  /// Every parameter the node reads, with defaults.
  static tactile_common::ParamMap default_parameters();
  /// Reads and validates; resolves `model_file` (see resolve_model_file).
  /// Throws tactile_common::ParamError naming the source, the key and the reason.
  static Params params_from(const tactile_common::ParamMap& map);
  /// Resolves a model file name: absolute paths as given; a relative path is
  /// looked up in <prefix>/share/tactile_depth/models/ for each prefix of
  /// AMENT_PREFIX_PATH, then in this package's own install share dir (fixed at
  /// build time), then relative to the working directory. Returns the first
  /// existing file, or "" if none exists.
  static std::string resolve_model_file(const std::string& name);

  /// Loads the model file (throws ModelError) and builds the estimator.
  explicit TactileDepthLogic(const Params& params);
  /// With models already in memory (tests, benchmarks).
  TactileDepthLogic(const Params& params, const SensorModelFile& models);

  std::optional<tactile_msgs::msg::TactileDepth> on_left_signal(const tactile_msgs::msg::WhiskerSignal& msg);
  std::optional<tactile_msgs::msg::TactileDepth> on_right_signal(const tactile_msgs::msg::WhiskerSignal& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: both whiskers' signals and the odometry in (sensor data), the depth
  /// out after each signal that completes a pair.
  template <class Ports>
  static void wire(Ports& p, TactileDepthLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    using tactile_msgs::msg::WhiskerSignal;
    auto depth = p.template publisher<tactile_msgs::msg::TactileDepth>(kOutputTopic, Pub::kData);
    p.template subscribe<WhiskerSignal>(kLeftSignalTopic, Sub::kSensorData, [&l, depth](const WhiskerSignal& msg) {
      if (auto out = l.on_left_signal(msg)) depth(std::move(*out));
    });
    p.template subscribe<WhiskerSignal>(kRightSignalTopic, Sub::kSensorData, [&l, depth](const WhiskerSignal& msg) {
      if (auto out = l.on_right_signal(msg)) depth(std::move(*out));
    });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdometryTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& msg) { l.on_odometry(msg); });
  }

  const Stats& stats() const { return stats_; }
  /// New parameters while running (`ros2 param set`): only the live keys of
  /// default_parameters() may differ (max_input_age_s, from the next message on).
  /// Throws std::invalid_argument if they do not validate or another field differs.
  void set_params(const Params& params);
  const Params& params() const { return params_; }
  const TactileDepthEstimator& estimator() const { return estimator_; }
  const SensorModelFile& models() const { return models_; }

 private:
  struct Pending {
    bool valid = false;
    int64_t stamp_ns = 0;
    tactile_msgs::msg::WhiskerSignal msg;
  };
  std::optional<tactile_msgs::msg::TactileDepth> on_signal(int side, const tactile_msgs::msg::WhiskerSignal& msg);
  tactile_msgs::msg::TactileDepth tick(const tactile_msgs::msg::WhiskerSignal& left,
                                       const tactile_msgs::msg::WhiskerSignal& right, int64_t stamp_ns);

  /// The MLP input of the model file: S_p (compensated) or S_c (calibrated).
  const std::array<double, 3>& input_of(const tactile_msgs::msg::WhiskerSignal& msg) const {
    return models_.input_signal == InputSignal::kCalibrated ? msg.calibrated : msg.compensated;
  }

  Params params_;
  SensorModelFile models_;
  TactileDepthEstimator estimator_;
  Stats stats_;
  Pending pending_[2];
  bool have_published_ = false;
  int64_t last_pair_ns_ = 0;
  bool have_odom_ = false;
  int64_t odom_ns_ = 0;
  Pose2 odom_pose_;
  std::string odom_frame_;
  std::string body_frame_ = kDefaultBodyFrame;
};

}  // namespace tactile_depth
