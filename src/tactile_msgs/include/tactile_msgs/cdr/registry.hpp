// Registry of every message type known to tactile_msgs (generated table), for generic
// code such as bag metadata and replay that works with type names at run time.
#ifndef TACTILE_MSGS__CDR__REGISTRY_HPP_
#define TACTILE_MSGS__CDR__REGISTRY_HPP_

#include <string_view>
#include <vector>

namespace tactile_msgs
{
namespace cdr
{

struct TypeInfo
{
  /// "pkg/msg/Type", e.g. "tactile_msgs/msg/WhiskerPressure".
  std::string_view name;
  /// Full definition text as rosbag2 stores it with encoding "ros2msg".
  std::string_view definition;
};

/// Looks a type up by "pkg/msg/Type" (also accepts the ROS 1 style "pkg/Type").
/// Returns nullptr for unknown types. The pointer stays valid for the program's lifetime.
const TypeInfo * find_type(std::string_view type_name);

/// Every type, sorted by name.
const std::vector<TypeInfo> & all_types();

}  // namespace cdr
}  // namespace tactile_msgs

#endif  // TACTILE_MSGS__CDR__REGISTRY_HPP_
