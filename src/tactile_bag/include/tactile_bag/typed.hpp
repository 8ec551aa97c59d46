// Typed layer over tactile_bag: messages of tactile_msgs (or rosidl types in a ROS
// build) written and decoded with tactile_msgs' CDR serialization.
//
//   #include "tactile_bag/typed.hpp"
//   writer.write("/whisker/left/pressure", stamp_ns, msg);   // creates the topic
//   auto msg = tactile_bag::decode<tactile_msgs::msg::WhiskerPressure>(serialized);
#pragma once

#include <string>

#include "tactile_bag/bag.hpp"
#include "tactile_msgs/cdr/serialization.hpp"

namespace tactile_bag {

/// TopicInfo for message type T: type name and full ros2msg definition from MessageTraits.
template <class T>
TopicInfo topic_info_for(const std::string& topic) {
  TopicInfo info;
  info.name = topic;
  info.type = tactile_msgs::cdr::MessageTraits<T>::type_name;
  info.type_definition = tactile_msgs::cdr::MessageTraits<T>::definition();
  info.definition_encoding = "ros2msg";
  return info;
}

template <class T>
void Writer::write(const std::string& topic, int64_t timestamp_ns, const T& msg) {
  const std::string existing = topic_type(topic);
  if (existing.empty()) {
    create_topic(topic_info_for<T>(topic));
  } else if (existing != tactile_msgs::cdr::MessageTraits<T>::type_name) {
    throw BagError(db_path() + ": topic '" + topic + "' has type '" + existing +
                   "', cannot write a " + tactile_msgs::cdr::MessageTraits<T>::type_name);
  }
  const std::vector<uint8_t> data = tactile_msgs::cdr::serialize(msg);
  write(topic, timestamp_ns, data.data(), data.size());
}

/// Deserialize a message read from a bag. Throws BagError naming the topic, the
/// timestamp and the decode error (type, field, byte offset) on malformed payloads.
template <class T>
T decode(const SerializedMessage& m) {
  T out{};
  try {
    tactile_msgs::cdr::deserialize(m.data.data(), m.data.size(), out);
  } catch (const std::exception& e) {
    throw BagError("message on '" + m.topic + "' at " + std::to_string(m.timestamp_ns) +
                   " ns: cannot decode as " + tactile_msgs::cdr::MessageTraits<T>::type_name +
                   ": " + e.what());
  }
  return out;
}

}  // namespace tactile_bag
