// libFuzzer harness of the CDR decoder: arbitrary bytes decoded as one of
// several message types (chosen by the first byte). Decoding must either
// succeed or throw DecodeError: no crash, no sanitizer report, no huge
// allocation. Build: cmake -DTACTILE_MSGS_FUZZ=ON with CXX=clang++.
#include <cstddef>
#include <cstdint>

#include "tactile_msgs/cdr/serialization.hpp"
#include "geometry_msgs/msg/pose_array.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/point_cloud2.hpp"
#include "tactile_msgs/msg/gpis_map.hpp"
#include "tactile_msgs/msg/localization_result.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "tactile_msgs/msg/whisker_signal.hpp"

namespace {
template <class T>
void decode(const uint8_t* data, size_t size) {
  T msg;
  try {
    tactile_msgs::cdr::deserialize(data, size, msg);
    // A decoded message re-encodes and decodes to itself.
    const auto again = tactile_msgs::cdr::serialize(msg);
    T back;
    tactile_msgs::cdr::deserialize(again.data(), again.size(), back);
  } catch (const tactile_msgs::cdr::DecodeError&) {
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t which = data[0] % 7;
  ++data;
  --size;
  switch (which) {
    case 0: decode<tactile_msgs::msg::WhiskerPressure>(data, size); break;
    case 1: decode<tactile_msgs::msg::WhiskerSignal>(data, size); break;
    case 2: decode<tactile_msgs::msg::GpisMap>(data, size); break;
    case 3: decode<tactile_msgs::msg::LocalizationResult>(data, size); break;
    case 4: decode<sensor_msgs::msg::PointCloud2>(data, size); break;
    case 5: decode<nav_msgs::msg::Odometry>(data, size); break;
    default: decode<geometry_msgs::msg::PoseArray>(data, size); break;
  }
  return 0;
}
