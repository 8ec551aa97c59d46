// PCL cloud -> sensor_msgs/PointCloud2 (x, y, z float32, little endian,
// unorganised: height 1), the layout pcl_conversions produces for PointXYZ
// minus its padding. Node-logic layer (messages).
#pragma once

#include <cstdint>
#include <string>

#include "mapping_pcl/point_map.hpp"
#include "sensor_msgs/msg/point_cloud2.hpp"

namespace mapping_pcl {

sensor_msgs::msg::PointCloud2 to_point_cloud2(const Cloud& cloud, const std::string& frame_id, int64_t stamp_ns);

}  // namespace mapping_pcl
