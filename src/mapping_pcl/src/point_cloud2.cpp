#include "mapping_pcl/point_cloud2.hpp"

#include <cstring>

#include "tactile_common/time.hpp"

namespace mapping_pcl {

sensor_msgs::msg::PointCloud2 to_point_cloud2(const Cloud& cloud, const std::string& frame_id, int64_t stamp_ns) {
  sensor_msgs::msg::PointCloud2 m;
  tactile_common::to_stamp(stamp_ns, m.header.stamp);
  m.header.frame_id = frame_id;
  m.height = 1;
  m.width = static_cast<uint32_t>(cloud.size());
  const char* names[3] = {"x", "y", "z"};
  for (uint32_t i = 0; i < 3; ++i) {
    sensor_msgs::msg::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::msg::PointField::FLOAT32;
    f.count = 1;
    m.fields.push_back(f);
  }
  m.is_bigendian = false;
  m.point_step = 12;
  m.row_step = 12 * m.width;
  m.is_dense = true;
  m.data.resize(static_cast<size_t>(m.row_step));
  uint8_t* d = m.data.data();
  for (const auto& p : cloud) {
    for (float v : {p.x, p.y, p.z}) {
      uint32_t u;
      std::memcpy(&u, &v, 4);
      for (int b = 0; b < 4; ++b) *d++ = static_cast<uint8_t>((u >> (8 * b)) & 0xFFu);
    }
  }
  return m;
}

}  // namespace mapping_pcl
