// Test helper for the independent PLY check (test/python/test_ply_peer.py):
//   mapping_ply_tool box OUT_PREFIX   writes OUT_PREFIX_ascii.ply and
//                                     OUT_PREFIX_binary.ply of one known box
//   mapping_ply_tool read FILE        loads FILE with PCL's own PLY reader and
//                                     prints "count minx miny minz maxx maxy maxz"
// Not installed.
#include <cstdio>
#include <iostream>
#include <string>

#include <pcl/common/common.h>
#include <pcl/io/ply_io.h>

#include "mapping_pcl/point_map.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: mapping_ply_tool box OUT_PREFIX | read FILE\n";
    return 2;
  }
  const std::string mode = argv[1];
  if (mode == "box") {
    mapping_pcl::PointMap m;
    mapping_pcl::Box b;  // must match test_ply_peer.py
    b.center = mapping_pcl::Vec3(1.5, -0.5, 0.7);
    b.size = mapping_pcl::Vec3(1.22, 0.08, 0.5);
    b.yaw = 0.0;
    m.insert_box(b, 0.02);
    mapping_pcl::write_ply(std::string(argv[2]) + "_ascii.ply", m.cloud(), mapping_pcl::PlyFormat::kAscii);
    mapping_pcl::write_ply(std::string(argv[2]) + "_binary.ply", m.cloud(), mapping_pcl::PlyFormat::kBinaryLittleEndian);
    return 0;
  }
  if (mode == "read") {
    pcl::PointCloud<pcl::PointXYZ> c;
    if (pcl::io::loadPLYFile(argv[2], c) < 0) {
      std::cerr << argv[2] << ": PCL could not read the file\n";
      return 1;
    }
    pcl::PointXYZ lo, hi;
    pcl::getMinMax3D(c, lo, hi);
    std::printf("%zu %.6f %.6f %.6f %.6f %.6f %.6f\n", c.size(), lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
    return 0;
  }
  std::cerr << "unknown mode " << mode << "\n";
  return 2;
}
