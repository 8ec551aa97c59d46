// Generic point-cloud map (PCL): insert points and oriented boxes of points,
// voxel-grid filtering, statistical outlier removal, footprint measurement
// (minimum-area oriented bounding rectangle, dimensions, areas) and PLY
// export. Used by the XPLORER contact mapper (xplorer_stamping.hpp, paper
// 001 Sec. IV-B) and usable by any other contact source (e.g. whisker
// contacts). Core layer: no ROS, no messages, metres.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace mapping_pcl {

using Vec3 = Eigen::Vector3d;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

struct MapParams {
  double voxel_leaf = 0.01;        ///< voxel-grid leaf [m] (001 uses Open3D point clouds; 1 cm is the issue's choice)
  int outlier_mean_k = 20;         ///< neighbours of the statistical outlier removal (choice)
  double outlier_stddev = 2.0;     ///< std-dev multiplier (choice)
  /// Outlier density at the slabs' resolution (issue 17, mapping_pcl README
  /// "Outlier removal at the slab spacing", rule 17): > 0: the statistical
  /// outlier removal judges the centroids of a copy of the map voxelised at
  /// this leaf, and a point is removed when its voxel's centroid is an
  /// outlier. The XPLORER slabs are point grids of slab_spacing = 2 cm, twice
  /// the 1 cm voxel leaf: where a single slab lies (a face's first and last
  /// slabs, next to the corners) the 1 cm map holds one point per 2 x 2 x 2
  /// cm, where dozens overlap (mid-face) one per 1 cm voxel, so at 1 cm the
  /// face ends have twice the mean neighbour distance of the map's bulk and
  /// fell beyond mean + 2 sigma (held-out polygons 13347, 13363, 13599: the
  /// map's hull 0.99 of the true area before the removal, 0.96-0.97 after).
  /// 0: the removal on the map's own points (PCL's filter, before issue 17's
  /// rule 17). Choice; tried at 0.02 m (the XPLORER slab_spacing) and off:
  /// it kept the polygons' face ends, and also the stray slabs of boxes and the
  /// fans of polygons that the removal at 1 cm had taken (tuning block
  /// 13300-13599: won 3 polygons, lost 5 boxes and 2 polygons).
  double outlier_leaf = 0.0;  ///< [m]
  /// Face ends kept by the faces' lines (issue 17, mapping_pcl README, rule
  /// 18): > 0: after the statistical outlier removal, the faces are the edges
  /// of the kept points' x-y convex hull at least this long whose length is
  /// supported (a kept point within outlier_face_tolerance inside the edge in
  /// at least outlier_face_support of its 2 x outlier_face_tolerance bins; a
  /// hull edge cutting a corner across a gap is supported at its two ends
  /// only). A removed point is put back if it lies at most
  /// outlier_face_outside outside every face's line and within
  /// outlier_face_depth inside one face's line, at most outlier_face_reach
  /// beyond that face's ends: a face end stamped by one slab is sparse (the
  /// removal takes it: held-out polygons 13347, 13363, 13599, tuning polygon
  /// 13263), not off the face; the remnants of clipped slabs and the tilted
  /// slab ends past a corner lie outside a face and stay removed (what rule
  /// 17 kept and lost boxes with). Supported hull edges shorter than
  /// outlier_face_length but at least outlier_face_bound_length long bound
  /// (a removed point must lie inside them too) without extending: a fan's
  /// bump past a corner can hide the next face from the hull but for a short
  /// edge at its end. A removed point is put back only within the kept
  /// points' height range (+- outlier_face_tolerance): the removal works in
  /// 3-D, the faces in x-y. Limits: an edge of at most 4 bins (8 x
  /// outlier_face_tolerance) counts as supported whatever lies between its
  /// end vertices (they are kept points); the faces come from the hull of all
  /// kept points, so a stray cluster the removal keeps replaces that side's
  /// faces by unsupported edges, which then bound nothing. 0: off (choice).
  double outlier_face_length = 0.0;   ///< [m]
  double outlier_face_tolerance = 0.01;  ///< [m], >= 1e-4 (one byte per bin per face)
  double outlier_face_outside = 0.0;     ///< [m]
  double outlier_face_bound_length = 0.05;  ///< [m]
  double outlier_face_depth = 0.1;    ///< [m] (the slab depth 0.08 m and a margin)
  double outlier_face_reach = 0.5;    ///< [m]
  double outlier_face_support = 0.5;  ///< fraction of the face's length, (0, 1]
  /// Re-run the voxel filter when the raw cloud has grown by this factor since
  /// the last filtering (bounds memory at high insert rates); 0 = never
  /// automatically (choice).
  double auto_filter_growth = 2.0;
  std::size_t auto_filter_min_points = 20000;  ///< ... and has at least this many points
  void validate() const;  ///< throws std::invalid_argument "MapParams.<field>: <reason>"
};

/// A solid box of points: centre, full extents along its own axes, yaw about
/// world z (boxes stay upright: contact slabs of 001 are vertical).
struct Box {
  Vec3 center = Vec3::Zero();
  Vec3 size = Vec3::Ones();  ///< full extents along the box x, y, z [m]
  double yaw = 0.0;          ///< [rad]
};

/// Footprint measurement of a map (x-y plane).
struct MapMeasurement {
  std::size_t points = 0;
  double length = 0.0;        ///< longer side of the minimum-area bounding rectangle [m]
  double width = 0.0;         ///< shorter side [m]
  double height = 0.0;        ///< z extent [m]
  double obb_area = 0.0;      ///< length x width [m^2]
  double hull_area = 0.0;     ///< area of the 2D convex hull of the footprint [m^2]
  double yaw = 0.0;           ///< direction of the length axis [rad], in (-pi/2, pi/2]
  Vec3 center = Vec3::Zero(); ///< centre of the rectangle (z: middle of the z extent)
  Vec3 min = Vec3::Zero(), max = Vec3::Zero();  ///< axis-aligned bounds
};

class PointMap {
 public:
  explicit PointMap(const MapParams& params = MapParams{});

  void insert(const Vec3& p);
  void insert(const std::vector<Vec3>& points);
  /// Fills `box` with a grid of points `spacing` apart (at least 2 per axis,
  /// faces included). Returns the number of points added.
  std::size_t insert_box(const Box& box, double spacing);
  /// The points insert_box would add (the same grid).
  static std::vector<Vec3> box_points(const Box& box, double spacing);
  /// Removes the points for which `drop` is true; returns how many.
  std::size_t remove_if(const std::function<bool(const Vec3&)>& drop);

  /// pcl::VoxelGrid with the given leaf (centroid per occupied voxel).
  void voxel_filter(double leaf);
  void voxel_filter() { voxel_filter(params_.voxel_leaf); }
  /// pcl::StatisticalOutlierRemoval; returns the number of points removed.
  std::size_t remove_outliers(int mean_k, double stddev);
  std::size_t remove_outliers() { return remove_outliers(params_.outlier_mean_k, params_.outlier_stddev); }

  MapMeasurement measure() const;

  const Cloud& cloud() const { return *cloud_; }
  Cloud::ConstPtr cloud_ptr() const { return cloud_; }
  std::size_t size() const { return cloud_->size(); }
  void clear();
  const MapParams& params() const { return params_; }
  uint64_t auto_filters() const { return auto_filters_; }

 private:
  void maybe_auto_filter();
  std::vector<bool> outliers_at_leaf(int mean_k, double stddev, double leaf) const;  ///< outlier_leaf > 0: the mask of the points kept
  /// outlier_face_length > 0: the removed points of `removed` that lie on a
  /// face of `kept` (rule 18) appended to `kept`; returns how many.
  std::size_t keep_face_ends(Cloud& kept, const Cloud& removed) const;
  void reserve_for(std::size_t extra);

  MapParams params_;
  Cloud::Ptr cloud_;
  std::size_t size_after_filter_ = 0;
  uint64_t auto_filters_ = 0;
};

/// Minimum-area enclosing rectangle of 2D points (convex hull + rotating the
/// rectangle onto each hull edge). Returns {length, width, yaw, cx, cy, hull_area}.
struct Rect2 {
  double length = 0, width = 0, yaw = 0, cx = 0, cy = 0, hull_area = 0;
};
Rect2 min_area_rectangle(const std::vector<Eigen::Vector2d>& points);
/// Convex hull of 2D points, counter-clockwise, no collinear vertices.
std::vector<Eigen::Vector2d> convex_hull(const std::vector<Eigen::Vector2d>& points);

// --- PLY ---------------------------------------------------------------------------

enum class PlyFormat { kAscii, kBinaryLittleEndian };

/// Map metadata written as PLY comments ("comment frame map", "comment units m").
struct PlyInfo {
  std::string frame = "map";
  std::string units = "m";
  std::string comment;  ///< optional free text (one line)
};

/// PLY text/bytes of a cloud: one `vertex` element with float x, y, z
/// (ASCII with 9 significant digits, or binary little endian regardless of
/// the host's byte order).
std::string ply_bytes(const Cloud& cloud, PlyFormat format, const PlyInfo& info = PlyInfo{});
/// Writes the PLY file; throws std::runtime_error naming the path on I/O failure.
void write_ply(const std::string& path, const Cloud& cloud, PlyFormat format, const PlyInfo& info = PlyInfo{});

}  // namespace mapping_pcl
