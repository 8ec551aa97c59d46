// Node logic of whisker_localization (paper 002): the whisker's base moment
// (WrenchStamped, torque.z = M(0) in the whisker base frame) and the base's
// odometry in; the preimage localization result (contact point, pose set,
// best estimate, spread) out. No rclcpp: the rclcpp component and the
// standalone host use this class.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geometry_msgs/msg/pose_array.hpp"
#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/localization_result.hpp"
#include "whisker_localization/contact_estimation.hpp"
#include "whisker_localization/elastica.hpp"
#include "whisker_localization/preimage.hpp"

namespace whisker_localization {

class WhiskerLocalizationLogic {
 public:
  static constexpr const char* kNodeName = "whisker_localization";
  static constexpr const char* kMomentTopic = "whisker/base_wrench";     // geometry_msgs/msg/WrenchStamped (torque.z = M(0))
  static constexpr const char* kOdomTopic = "odom";                      // nav_msgs/msg/Odometry (the whisker base)
  static constexpr const char* kResultTopic = "whisker/localization";    // tactile_msgs/msg/LocalizationResult
  static constexpr const char* kPoseSetTopic = "whisker/pose_set";       // geometry_msgs/msg/PoseArray
  static constexpr const char* kMapFrame = "map";

  struct Params {
    BeamParams beam;
    LocalizerParams localizer;
    /// Known map: a YAML file with `polylines: [[[x, y], ...], ...]` (metres,
    /// free space on the left of each polyline). Empty: the Table II concave
    /// corner (fillet_radius, leg).
    std::string map_file;
    double map_spacing = 0.001;     ///< boundary discretisation [m], 002 Sec. VII-B (1 mm)
    double fillet_radius = 0.05;    ///< default map: see stage_sim.hpp (choice)
    double leg = 0.15;
    /// Known start (002 Sec. VII-D); used when use_prior.
    bool use_prior = false;
    double prior_x = 0.0, prior_y = 0.0, prior_yaw = 0.0;
    /// What torque.z of the input carries: "moment" (calibrated M(0) [N m]) or
    /// "flux" (the Hall sensor's flux density B [mT], converted with
    /// hall_coefficients, 002 Sec. V-B).
    std::string input = "moment";
    /// M(0) = c0 + c1 B + c2 B^2 + ... (HallCalibration::coefficients()).
    std::vector<double> hall_coefficients{0.0, 1.0};
    /// |M(0)| below this is no contact [N m]. Choice: 5x a 0.2 uN m noise floor.
    double contact_threshold = 1e-6;
    /// Odometry older than this at a moment sample is stale [s]. Choice: 0.1 s.
    double max_odom_age_s = 0.1;
    /// A contact sample is localized only once the base has moved at least
    /// this far since the previous localized sample [m] (002 Sec. VII-D:
    /// steps below 1 mm, e.g. 0.5 mm on a continuously moving stage); 0:
    /// every sample. Choice.
    double min_step = 0.0;
    void validate() const;
  };

  struct Stats {
    uint64_t moments_received = 0;
    uint64_t odom_received = 0;
    uint64_t published = 0;
    uint64_t dropped_nonfinite = 0;     ///< NaN/inf moment or odometry
    uint64_t dropped_out_of_order = 0;  ///< stamp not after the previous accepted one
    uint64_t dropped_no_odom = 0;       ///< no odometry yet, or older than max_odom_age_s
    uint64_t no_contact = 0;            ///< |M(0)| below contact_threshold
    uint64_t resets = 0;                ///< empty intersections (localizer restarted)
    uint64_t skipped_small_motion = 0;  ///< contact samples within min_step of the previous localized one
  };

  struct Outputs {
    std::optional<tactile_msgs::msg::LocalizationResult> result;
    std::optional<geometry_msgs::msg::PoseArray> pose_set;
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit WhiskerLocalizationLogic(const Params& params);

  void on_odometry(const nav_msgs::msg::Odometry& msg);
  /// One base-moment sample: forward-projects the pose set by the odometry
  /// motion since the previous sample and intersects it with the preimage.
  Outputs on_moment(const geometry_msgs::msg::WrenchStamped& msg);

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: odometry and base moment in (sensor data), the result and the pose
  /// set out after each moment sample.
  template <class Ports>
  static void wire(Ports& p, WhiskerLocalizationLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto result = p.template publisher<tactile_msgs::msg::LocalizationResult>(kResultTopic, Pub::kData);
    auto pose_set = p.template publisher<geometry_msgs::msg::PoseArray>(kPoseSetTopic, Pub::kData);
    p.template subscribe<nav_msgs::msg::Odometry>(kOdomTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.template subscribe<geometry_msgs::msg::WrenchStamped>(
        kMomentTopic, Sub::kSensorData, [&l, result, pose_set](const geometry_msgs::msg::WrenchStamped& m) {
          auto out = l.on_moment(m);
          if (out.result) result(std::move(*out.result));
          if (out.pose_set) pose_set(std::move(*out.pose_set));
        });
  }

  /// Starts over (a new sweep): empties the pose set and the contact
  /// history; with `prior`, the new known start (002 Sec. VII-D).
  void restart(const Pose2* prior);

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const PreimageLocalizer& localizer() const { return *localizer_; }
  const BoundaryMap& map() const { return *map_; }

 private:
  Params params_;
  std::unique_ptr<BoundaryMap> map_;
  std::unique_ptr<ElasticaSolver> solver_;
  std::unique_ptr<PreimageLocalizer> localizer_;
  Stats stats_;
  bool have_odom_ = false;
  int64_t odom_stamp_ = 0;
  Pose2 odom_;
  bool have_last_ = false;
  int64_t last_stamp_ = 0;
  Pose2 last_odom_;
};

/// Reads a map file (`polylines: [[[x, y], ...], ...]`); throws
/// std::runtime_error naming the file, the key path and the reason.
std::vector<std::vector<std::array<double, 2>>> load_map_file(const std::string& path);

}  // namespace whisker_localization
