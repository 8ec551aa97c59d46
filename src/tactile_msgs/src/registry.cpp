#include "tactile_msgs/cdr/registry.hpp"

#include <string>

namespace tactile_msgs
{
namespace cdr
{

const TypeInfo * find_type(std::string_view type_name)
{
  std::string normalized;
  const auto slash = type_name.find('/');
  if (slash != std::string_view::npos && type_name.find('/', slash + 1) == std::string_view::npos) {
    // "pkg/Type" -> "pkg/msg/Type"
    normalized.append(type_name.substr(0, slash)).append("/msg").append(type_name.substr(slash));
    type_name = normalized;
  }
  for (const auto & info : all_types()) {
    if (info.name == type_name) {
      return &info;
    }
  }
  return nullptr;
}

}  // namespace cdr
}  // namespace tactile_msgs
