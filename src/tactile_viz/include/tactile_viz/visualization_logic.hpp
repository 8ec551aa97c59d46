// Node logic of the visualization node: the estimates and events of the other nodes in,
// visualization_msgs/MarkerArray (RViz markers) and the GPIS mean and variance as
// nav_msgs/OccupancyGrid out. No rclcpp: the component (src/ros/) and any host call the
// on_* handlers and publish what they return. README: what each namespace draws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "nav_msgs/msg/occupancy_grid.hpp"
#include "std_msgs/msg/color_rgba.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_msgs/msg/collision_event.hpp"
#include "tactile_msgs/msg/exploration_target.hpp"
#include "tactile_msgs/msg/gpis_map.hpp"
#include "tactile_msgs/msg/localization_result.hpp"
#include "tactile_msgs/msg/tactile_depth.hpp"
#include "tactile_msgs/msg/wall_estimate.hpp"
#include "visualization_msgs/msg/marker_array.hpp"

namespace tactile_viz {

struct VisualizationParams {
  /// Length of each contact history (whisker contacts per whisker, collision events): a
  /// ring buffer, the oldest point is dropped (bounds memory and the marker size).
  int64_t max_markers = 500;
  /// Markers of one source (whisker contacts, wall estimate, localization) are published
  /// at most once per this interval of their input's header stamps; a marker that
  /// disappears (contact lost, wall lost) is deleted at once. 0: every input.
  double min_interval_s = 0.1;
  double contact_diameter = 0.02;    ///< whisker contact spheres [m]
  double collision_diameter = 0.05;  ///< collision spheres [m]
  double normal_length = 0.1;        ///< collision normal lines [m]
  double wall_length = 1.0;          ///< drawn length of the estimated wall [m]
  double line_width = 0.01;          ///< LINE_STRIP / LINE_LIST width [m]
  double point_size = 0.015;         ///< GPIS training points and corners [m]
  double target_diameter = 0.08;     ///< exploration target sphere [m]
  /// OccupancyGrid scaling of the GPIS mean [m]: cell = round(50 + 50 * clamp(mean /
  /// mean_range, -1, 1)), so 50 is the surface (zero level set), 0 and 100 are
  /// -mean_range and +mean_range or beyond.
  double mean_range = 0.5;
  /// OccupancyGrid scaling of the GPIS variance [m^2]: cell = round(100 * clamp(variance /
  /// variance_max, 0, 1)). 1.0: the IMQ kernel's prior variance k(x, x) = 1 (000 eq. 33).
  double variance_max = 1.0;
  void validate() const;
};

/// Bad input message: names the message type, the field and the reason.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class VisualizationLogic {
 public:
  using Params = VisualizationParams;
  using MarkerArray = visualization_msgs::msg::MarkerArray;
  using Grid = nav_msgs::msg::OccupancyGrid;

  static constexpr const char* kNodeName = "visualization";
  // Inputs, relative as their publishers name them.
  static constexpr const char* kDepthTopic = "whisker/depth";                // tactile_msgs/msg/TactileDepth (tactile_depth)
  static constexpr const char* kWallTopic = "wall_effect/estimate";          // tactile_msgs/msg/WallEstimate (wall_effect_ekf)
  static constexpr const char* kGpisMapTopic = "gpis/map";                   // tactile_msgs/msg/GpisMap (gpis_explorer, latched)
  static constexpr const char* kGpisTargetTopic = "gpis/target";             // tactile_msgs/msg/ExplorationTarget (gpis_explorer, latched)
  static constexpr const char* kCollisionTopic = "collisions";               // tactile_msgs/msg/CollisionEvent (tactile_sim)
  static constexpr const char* kLocalizationTopic = "whisker/localization";  // tactile_msgs/msg/LocalizationResult (whisker_localization)
  // Outputs.
  static constexpr const char* kMarkersTopic = "visualization/markers";      // visualization_msgs/msg/MarkerArray, reliable
  static constexpr const char* kMeanGridTopic = "gpis/mean_grid";            // nav_msgs/msg/OccupancyGrid, latched
  static constexpr const char* kVarianceGridTopic = "gpis/variance_grid";    // nav_msgs/msg/OccupancyGrid, latched

  // Marker namespaces, one per source, and their ids.
  static constexpr const char* kNsWhiskerContacts = "whisker_contacts";  // SPHERE_LIST: id 0 left, 1 right
  static constexpr const char* kNsWallEstimate = "wall_estimate";        // LINE_STRIP id 0 (wall), ARROW id 1 (vehicle -> wall)
  static constexpr const char* kNsGpisContour = "gpis_contour";          // LINE_STRIP per contour, ids 0..n-1
  static constexpr const char* kNsGpisTraining = "gpis_training";        // POINTS id 0 (colours per label)
  static constexpr const char* kNsGpisCorners = "gpis_corners";          // SPHERE_LIST id 0
  static constexpr const char* kNsGpisTarget = "gpis_target";            // SPHERE id 0
  static constexpr const char* kNsCollisions = "collisions";             // SPHERE_LIST id 0, LINE_LIST id 1 (normals)
  static constexpr const char* kNsLocalization = "localization";         // SPHERE id 0 (contact), POINTS id 1 (pose set), ARROW id 2 (best)

  struct Stats {
    uint64_t contacts_without_frame = 0;  ///< whisker contact with contact_frame_id "" (no odometry yet): not drawn
    uint64_t nonfinite_dropped = 0;       ///< points with NaN/inf coordinates: not drawn
    uint64_t grid_cells_unknown = 0;      ///< NaN/inf GPIS mean or variance cells: -1 (unknown) in the grid
    uint64_t throttled = 0;               ///< inputs whose markers min_interval_s held back
  };

  static tactile_common::ParamMap default_parameters();
  static Params params_from(const tactile_common::ParamMap& map);

  explicit VisualizationLogic(const Params& params);

  /// Each handler returns the markers to publish (empty: nothing new). The first
  /// output of every namespace starts with a DELETEALL of that namespace: markers a
  /// previous run left in RViz disappear.
  MarkerArray on_tactile_depth(const tactile_msgs::msg::TactileDepth& msg);
  MarkerArray on_wall_estimate(const tactile_msgs::msg::WallEstimate& msg);
  /// Throws InputError if the grid sizes, contour_starts or training labels are inconsistent.
  MarkerArray on_gpis_map(const tactile_msgs::msg::GpisMap& msg);
  MarkerArray on_exploration_target(const tactile_msgs::msg::ExplorationTarget& msg);
  MarkerArray on_collision(const tactile_msgs::msg::CollisionEvent& msg);
  MarkerArray on_localization(const tactile_msgs::msg::LocalizationResult& msg);

  /// GPIS posterior mean / variance as grids (scaling: Params::mean_range, variance_max).
  /// Throws InputError like on_gpis_map.
  Grid mean_grid(const tactile_msgs::msg::GpisMap& msg);
  Grid variance_grid(const tactile_msgs::msg::GpisMap& msg);

  /// DELETEALL of every namespace (e.g. a new run): the histories are cleared too.
  MarkerArray reset();

  const Params& params() const { return params_; }
  const Stats& stats() const { return stats_; }

  /// Colours (RGBA in [0, 1]) of the sources, for tests and the README.
  static std_msgs::msg::ColorRGBA color(float r, float g, float b, float a = 1.0f);

 private:
  /// A ring buffer of points in one frame.
  struct History {
    std::string frame_id;
    std::vector<geometry_msgs::msg::Point> points;  ///< insertion order, oldest first
    std::vector<std_msgs::msg::ColorRGBA> colors;    ///< per point (collisions), or empty
    std::vector<geometry_msgs::msg::Point> lines;    ///< pairs (collision normals), or empty
  };
  struct Source {
    bool started = false;        ///< DELETEALL sent
    int64_t last_publish_ns = 0;
    bool published_once = false;
    int max_id = -1;             ///< highest id shown (DELETE of the rest)
  };

  void start(Source& s, const char* ns, MarkerArray& out);
  bool due(Source& s, int64_t stamp_ns, bool forced);
  void push(History& h, const geometry_msgs::msg::Point& p, std::size_t per_item);
  static void check_gpis(const tactile_msgs::msg::GpisMap& msg);

  Params params_;
  Stats stats_;
  History contacts_[2];
  History collisions_;
  Source depth_src_, wall_src_, contour_src_, training_src_, corners_src_, target_src_, collision_src_,
      localization_src_;
  bool wall_shown_ = false;
  bool localization_contact_shown_ = false;
};

}  // namespace tactile_viz
