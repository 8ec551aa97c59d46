// Coordinate frames of the workspace (REP 105, REP 103) and the robot model
// they are derived from. ROS-free: the node logics stamp headers with these
// names, the rclcpp components broadcast the transforms and publish the URDF.
//
// The frame tree of one vehicle (every name behind the node's frame_prefix,
// e.g. "cf1/" gives "cf1/base_link"):
//
//   map ──(static identity, unless a behaviour owns a world map)── odom
//     odom ──(dynamic: the vehicle's state estimate)── base_link
//       base_link ──(static, from the vehicle geometry)── whisker_left, whisker_right,
//                    imu_link, tof_down, flow, arm0..arm3 (+ arm0_imu..), rotor0..rotor3
//   map ──(static identity: the simulator's world)── ground_truth/odom
//     ground_truth/odom ──(dynamic: the simulator's truth)── ground_truth/base_link
//
// Ground truth has its own pair (not odom/base_link, which belong to the estimate):
// two publishers of one transform would make tf2 flip between them.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace tactile_common {

namespace frames {
inline constexpr const char* kMap = "map";
inline constexpr const char* kOdom = "odom";
inline constexpr const char* kBaseLink = "base_link";
inline constexpr const char* kWhiskerLeft = "whisker_left";
inline constexpr const char* kWhiskerRight = "whisker_right";
inline constexpr const char* kImu = "imu_link";
inline constexpr const char* kTofDown = "tof_down";
inline constexpr const char* kFlow = "flow";
inline constexpr const char* kGroundTruthOdom = "ground_truth/odom";
inline constexpr const char* kGroundTruthBaseLink = "ground_truth/base_link";
}  // namespace frames

/// Throws std::invalid_argument unless `prefix` is empty or a relative tf2 name
/// ending in '/' (letters, digits, '_', '/'; no leading '/', no "//"): "cf1/".
/// `where` names the parameter in the message.
void validate_frame_prefix(std::string_view prefix, std::string_view where = "frame_prefix");

/// `prefix` + `frame`.
std::string prefixed(std::string_view prefix, std::string_view frame);

/// A rigid transform parent -> child: translation [m] and rotation as a unit
/// quaternion (x, y, z, w), from roll/pitch/yaw [rad] (fixed axes X-Y-Z, as URDF's rpy).
struct RigidTransform {
  std::array<double, 3> xyz{0.0, 0.0, 0.0};
  std::array<double, 3> rpy{0.0, 0.0, 0.0};
  std::array<double, 4> quaternion() const;  ///< x, y, z, w of rpy
};

/// A link of a robot model fixed to its parent (fixed joint `<parent>_to_<name>`),
/// with a simple visual (a box, a cylinder along the link's z axis, or a sphere).
struct RobotLink {
  enum class Shape { kNone, kBox, kCylinder, kSphere };
  std::string name;
  std::string parent;
  RigidTransform origin;  ///< parent -> this link
  Shape shape = Shape::kNone;
  std::array<double, 3> size{0.0, 0.0, 0.0};  ///< box x, y, z; cylinder radius, length; sphere radius [m]
  RigidTransform visual_origin;               ///< of the visual in this link's frame
  std::string colour = "grey";                ///< a material of to_urdf(): grey, black, silver, orange
};

/// A robot: the root link (base_link) and its fixed links, in an order where a
/// parent comes before its children.
struct RobotModel {
  std::string name;
  RobotLink root;  ///< its name is base_link; origin unused
  std::vector<RobotLink> links;

  /// Throws std::invalid_argument naming the link and the reason: empty or
  /// duplicate names, a parent not defined before, non-finite numbers, negative sizes.
  void validate() const;
};

/// One static transform of the model: parent -> child (names prefixed).
struct StaticFrame {
  std::string parent;
  std::string child;
  RigidTransform transform;
};

/// The fixed joints of `model` as static transforms, every frame behind `prefix`.
std::vector<StaticFrame> static_frames(const RobotModel& model, std::string_view prefix);

/// The URDF (XML) of `model`, every link behind `prefix` (the links and
/// the joints of static_frames(), so both come from one list).
std::string to_urdf(const RobotModel& model, std::string_view prefix);

}  // namespace tactile_common
