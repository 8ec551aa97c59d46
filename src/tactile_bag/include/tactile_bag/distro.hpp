// What differs between the ROS 2 distros' bags: message layouts of the standard types, the
// metadata version and the RIHS01 type description hashes (REP-2011) rosbag2 stores.
//
// The ROS-free standard types (tactile_msgs/ros_free_std) follow Kilted; Jazzy has the same
// layouts for every type the workspace uses. Humble (and Iron) differ in one:
// sensor_msgs/msg/Range has no trailing `float32 variance` (added in Jazzy).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tactile_bag {

/// Distros a bag can be written for.
inline const std::vector<std::string>& known_distros() {
  static const std::vector<std::string> d = {"humble", "iron", "jazzy", "kilted"};
  return d;
}
/// Throws BagError for a name not in known_distros().
void check_distro(const std::string& distro, const std::string& context);
/// rosbag2 metadata version the distro's recorder writes: humble 5, iron 8, jazzy/kilted 9.
int metadata_version_for_distro(const std::string& distro);
/// True where the distro has RIHS01 type hashes (iron and later).
bool distro_has_type_hashes(const std::string& distro);
/// True where sensor_msgs/msg/Range has no `variance` (humble, iron).
bool distro_range_without_variance(const std::string& distro);

/// Type description of `type_name` ("pkg/msg/Type") in rosidl's hashable JSON form (REP-2011:
/// the TypeDescription message without default values, referenced types sorted by name,
/// json.dumps separators ", " and ": "), built from a full ros2msg definition text as
/// rosbag2 stores it (own text, then "====...\nMSG: pkg/Type\n<text>" for every dependency).
/// Errors (unknown nested type, bad field line) are BagError naming the type and line.
std::string type_description_json(const std::string& type_name, const std::string& definition);
/// "RIHS01_" + hex sha256 of type_description_json().
std::string rihs01_hash(const std::string& type_name, const std::string& definition);

/// Full definition of `top_type` with the field `field` of `of_type` removed (in the top
/// section if of_type == top_type, else in its "MSG:" section). Humble's Range definition.
std::string remove_field_from_definition(const std::string& definition, const std::string& top_type,
                                         const std::string& of_type, const std::string& field);
/// True if the definition's section of `of_type` declares `field`. `found_type` is set to
/// whether the definition has a section for `of_type` at all.
bool definition_has_field(const std::string& definition, const std::string& top_type,
                          const std::string& of_type, const std::string& field,
                          bool* found_type = nullptr);

/// Byte length of a CDR sensor_msgs/Range payload (incl. the 4-byte encapsulation header) in
/// Humble's layout, i.e. up to and including `range`; 0 if the payload is too short to tell.
size_t range_payload_size_without_variance(const uint8_t* data, size_t size);

}  // namespace tactile_bag
