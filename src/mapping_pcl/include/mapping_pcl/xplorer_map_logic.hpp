// Node logic of the XPLORER contact mapper (paper 001 Sec. IV-B): the body
// force estimate (xplorer_force_est) and the odometry in, the contact point
// cloud out (sensor_msgs/PointCloud2) and, on request, a PLY file. No rclcpp.
#pragma once

#include <algorithm>

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "mapping_pcl/point_cloud2.hpp"
#include "mapping_pcl/point_map.hpp"
#include "mapping_pcl/xplorer_stamping.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/point_cloud2.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_msgs/msg/arm_imu_array.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"

namespace mapping_pcl {

class XplorerMapLogic {
 public:
  static constexpr const char* kNodeName = "xplorer_mapping";
  static constexpr const char* kWrenchBodyTopic = "xplorer/wrench_body";  // geometry_msgs/msg/WrenchStamped
  static constexpr const char* kOdometryTopic = "odom";                   // nav_msgs/msg/Odometry
  static constexpr const char* kCloudTopic = "xplorer/map";               // sensor_msgs/msg/PointCloud2
  /// The shorter state gate after a turn is safe only with the recent-axis check, which needs
  /// the latest force samples: without them the 1 s average still pressing the face before the
  /// turn would be stamped on the new one (README "Recent axis"), so min_state_time_s applies.
  bool short_gate_after_turn() const { return params_.stamping.recent_axis && params_.force_now_samples > 0; }
  static constexpr const char* kDoneState = "done";  // tactile_fsm's loop closure (issue 17): ends the last face, the first contact's
  static constexpr const char* kTurningState = "tactile_turning";  // tactile_fsm's Tactile-turning (001 Gamma 2): ends a face at a convex corner
  static constexpr const char* kFsmStateTopic = "xplorer/fsm_state";      // tactile_msgs/msg/FsmState (optional)
  static constexpr const char* kArmImuTopic = "arm_imu";                  // tactile_msgs/msg/ArmImuArray (optional: edge_from_arms)

  /// MapParams with the XPLORER map's rules on (rule 18: outlier_face_length 0.2 m).
  static MapParams xplorer_map_params() {
    MapParams m;
    m.outlier_face_length = 0.2;
    return m;
  }

  struct Params {
    XplorerMapParams stamping;
    /// The map's filters (outlier_leaf: README "Outlier removal at the slab spacing",
    /// rule 17, tried at 0.02 m and off: 0, PCL's removal on the 1 cm points;
    /// outlier_face_length: README "Face ends kept by the faces' lines", rule 18,
    /// 0.2 m for the XPLORER map, off in the generic MapParams).
    MapParams map = xplorer_map_params();
    int force_average_samples = 50;  ///< moving average of the body force (001 Sec. V-C: 50 samples)
    double floor_z = 0.0;            ///< floor height for the flying check [m]
    double publish_rate_hz = 1.0;    ///< PointCloud2 rate (choice: the full map is large)
    double max_odometry_age_s = 0.1; ///< older odometry pauses the stamping (choice)
    std::string frame_id = "odom";  ///< of the cloud: the odometry poses' frame (REP 105; was map)
    std::string ply_file;            ///< written by save_ply() ("" = none)
    bool ply_binary = false;         ///< false: ASCII as 001; true: binary little endian
    /// Stamp only while the exploration FSM is in one of these states (once an
    /// FsmState has arrived; empty = always). Keeps slabs out of turns, where
    /// the body force points across the corner (choice; 001 gates on force only).
    std::vector<std::string> stamp_states = {"tactile_traversal"};
    double min_state_time_s = 1.0;   ///< ... and has been in it this long (choice: the 50-sample, 1 s force average still holds the turn)
    /// ... or this long in a traversal entered from Tactile-turning: the
    /// stamping's recent_axis check holds back the slabs while the average
    /// still reads the face just left; the 1 s gate left no slab on the
    /// 0.4-0.5 m faces of the polygons. After Exploration the 1 s stays (the
    /// first contact's rebound; contact now) (choice; README "Recent axis").
    double min_state_time_after_turn_s = 0.3;
    double max_arm_age_s = 0.1;      ///< older arm angles: the fixed slab_offset is used (choice; arm IMUs at 50 Hz)
    /// The "contact now" force (stamping.min_force_now) is the mean of this
    /// many latest wrench samples (choice: 10 = 0.2 s at 50 Hz); 0: not used.
    int force_now_samples = 10;
    /// The contact-now check applies only in a state entered from one of
    /// these FSM states (FsmState.previous_state; always before an FsmState is
    /// heard; empty = always): the rebound that the 1 s average hides follows
    /// a contact at the Exploration speed (0.3 m/s); on the 0.3-0.6 m faces of
    /// polygons, re-contacted after a turn at 0.15 m/s, the contact is
    /// intermittent but the vehicle stays at the face, and the check cut
    /// their coverage (choice; README "Contact now").
    std::vector<std::string> contact_now_after = {"exploration"};
    /// A Tactile-turning entered for one of these reasons (FsmState.reason_code, by the
    /// names of turning_reasons(): "contact_lost_turn", "yaw_rate_peak"; never the
    /// human-readable FsmState.reason) counts as a state of contact_now_after for the
    /// traversal that follows it: the first-contact rules of impact_turn_rules (default
    /// contact now and the steady first contact; min_state_time_s instead of the shorter
    /// gate after a turn only with "gate") apply to its re-contact. tactile_fsm's turn about
    /// a face's end after a contact lost (REASON_XPLORER_CONTACT_LOST_TURN) is no corner
    /// turn of a steady traversal: the vehicle comes back to the object from off its face,
    /// and the re-contact is an impact like the one after Exploration (choice; README
    /// "Re-contact after a contact-lost turn"). Empty: off.
    std::vector<std::string> impact_turn_reasons = {"contact_lost_turn"};
    /// Which first-contact rules the traversal after such a turn gets: "contact_now"
    /// (stamping.min_force_now), "steady" (the steady hold), "gate" (min_state_time_s
    /// instead of min_state_time_after_turn_s; not by default: on the polygons 3012
    /// and 3016 the 1 s gate undid what contact now gained, hull 0.994 -> 0.952
    /// and 0.984 -> 0.938) (choice; README
    /// "Re-contact after a contact-lost turn").
    std::vector<std::string> impact_turn_rules = {"contact_now", "steady"};
    /// Entering one of these FSM states releases the held-back slabs of the
    /// last corner_release_s (dated by the state's entry): Tactile-turning (a
    /// corner, 001 Sec. IV-A), the loop closed ("done": the vehicle stops at
    /// the first contact point, which may be next to a corner) and Exploration
    /// (the contact lost) (choice; README "Corner release" and "Release on
    /// every end of a traversal").
    std::vector<std::string> release_states = {"tactile_turning", "done", "exploration"};
    void validate() const;
  };

  struct Stats {
    uint64_t received_wrench = 0;
    uint64_t received_odometry = 0;
    uint64_t dropped_nonfinite = 0;   ///< NaN/inf force or pose
    uint64_t dropped_wrong_frame = 0; ///< wrench not in the body frame of the odometry / base_link
    uint64_t ticks_without_input = 0; ///< timer ticks with no or stale odometry/force
    uint64_t published = 0;
    uint64_t ticks_gated = 0;         ///< timer ticks skipped: FSM state not in stamp_states
    uint64_t received_arm_imu = 0;
    uint64_t dropped_arm_samples = 0; ///< arm samples with a bad arm_id or a non-finite / > 0.8 rad angle
  };

  /// The reasons of entering Tactile-turning that impact_turn_reasons may name, with their
  /// FsmState.reason_code (REASON_XPLORER_*; names as tactile_fsm's to_string(XplorerReason)).
  static const std::vector<std::pair<std::string, uint8_t>>& turning_reasons();

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit XplorerMapLogic(const Params& params);

  void on_wrench_body(const geometry_msgs::msg::WrenchStamped& msg);
  void on_odometry(const nav_msgs::msg::Odometry& msg);
  void on_fsm_state(const tactile_msgs::msg::FsmState& msg);
  /// Arm deflections for the CAD outline (stamping.edge_from_arms).
  void on_arm_imu(const tactile_msgs::msg::ArmImuArray& msg);
  /// Timer at stamping.rate_hz (30 Hz): stamps slabs; returns the cloud when
  /// a publication is due.
  std::optional<sensor_msgs::msg::PointCloud2> on_timer(int64_t now_ns);

  /// Voxel filter (1 cm) and statistical outlier removal of the map, then its measurement.
  MapMeasurement finalize();
  /// Writes params.ply_file (or `path` if given) in the configured format.
  void save_ply(const std::string& path = "") const;

  const PointMap& map() const { return map_; }
  const XplorerContactMapper& mapper() const { return mapper_; }
  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  int64_t period_ns() const;

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: body wrench, odometry and arm IMU in (sensor data), the FSM state in
  /// reliable (a state change is an event, not a stream); the contact cloud out latched (a
  /// late subscriber still gets the map) every period_ns() on the node's clock.
  template <class Ports>
  static void wire(Ports& p, XplorerMapLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto cloud = p.template publisher<sensor_msgs::msg::PointCloud2>(kCloudTopic, Pub::kLatched);
    p.template subscribe<geometry_msgs::msg::WrenchStamped>(
        kWrenchBodyTopic, Sub::kSensorData, [&l](const geometry_msgs::msg::WrenchStamped& m) { l.on_wrench_body(m); });
    p.template subscribe<nav_msgs::msg::Odometry>(kOdometryTopic, Sub::kSensorData,
                                                  [&l](const nav_msgs::msg::Odometry& m) { l.on_odometry(m); });
    p.template subscribe<tactile_msgs::msg::FsmState>(kFsmStateTopic, Sub::kReliable,
                                                      [&l](const tactile_msgs::msg::FsmState& m) { l.on_fsm_state(m); });
    p.template subscribe<tactile_msgs::msg::ArmImuArray>(
        kArmImuTopic, Sub::kSensorData, [&l](const tactile_msgs::msg::ArmImuArray& m) { l.on_arm_imu(m); });
    p.timer(l.period_ns(), [&l, cloud](int64_t now_ns) {
      if (auto out = l.on_timer(now_ns)) cloud(std::move(*out));
    });
  }

 private:
  Params params_;
  PointMap map_;
  XplorerContactMapper mapper_;
  Stats stats_;
  std::deque<Eigen::Vector2d> forces_;
  Eigen::Vector2d force_sum_ = Eigen::Vector2d::Zero();
  std::optional<nav_msgs::msg::Odometry> odom_;
  std::optional<std::string> fsm_state_;
  double fsm_state_since_s_ = 0.0;  ///< stamp time of entering the current state
  std::string fsm_previous_state_;  ///< FsmState.previous_state of the current state
  std::vector<uint8_t> impact_turn_codes_;  ///< FsmState.reason_code of impact_turn_reasons
  bool turn_after_impact_reason_ = false;  ///< the latest Tactile-turning was entered for one of impact_turn_reasons
  bool entered_after_impact_ = false;      ///< the current state was entered from contact_now_after or such a turn
  bool entered_after_impact_turn_ = false; ///< ... from such a turn (impact_turn_rules apply)
  bool impact_rule(const char* r) const {
    return !entered_after_impact_turn_ ||
           std::find(params_.impact_turn_rules.begin(), params_.impact_turn_rules.end(), r) != params_.impact_turn_rules.end();
  }
  int64_t last_publish_ns_ = -1;
  std::array<double, 4> arm_angles_{};
  std::array<int64_t, 4> arm_stamp_ns_{-1, -1, -1, -1};
};

}  // namespace mapping_pcl
