// Generic PCL point-cloud map: insertion, filters, footprint measurement, PLY.
#include "mapping_pcl/point_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>

namespace mapping_pcl {

void MapParams::validate() const {
  auto bad = [](const char* f, const std::string& why) {
    throw std::invalid_argument(std::string("MapParams.") + f + ": " + why);
  };
  if (!(voxel_leaf > 0.0) || !std::isfinite(voxel_leaf)) bad("voxel_leaf", "must be finite and > 0, got " + std::to_string(voxel_leaf));
  if (outlier_mean_k < 1) bad("outlier_mean_k", "must be >= 1, got " + std::to_string(outlier_mean_k));
  if (!(outlier_stddev > 0.0) || !std::isfinite(outlier_stddev))
    bad("outlier_stddev", "must be finite and > 0, got " + std::to_string(outlier_stddev));
  if (!(outlier_leaf >= 0.0) || !std::isfinite(outlier_leaf))
    bad("outlier_leaf", "must be finite and >= 0 (0: the removal on the map's own points), got " + std::to_string(outlier_leaf));
  if (!(outlier_face_length >= 0.0) || !std::isfinite(outlier_face_length))
    bad("outlier_face_length", "must be finite and >= 0 (0: off), got " + std::to_string(outlier_face_length));
  if (!(outlier_face_tolerance >= 1e-4) || !std::isfinite(outlier_face_tolerance))
    bad("outlier_face_tolerance", "must be finite and >= 1e-4 m (the support test keeps one byte per 2 x tolerance of every face), got " +
                                      std::to_string(outlier_face_tolerance));
  if (!std::isfinite(outlier_face_outside)) bad("outlier_face_outside", "must be finite, got " + std::to_string(outlier_face_outside));
  if (!(outlier_face_bound_length > 0.0) || !std::isfinite(outlier_face_bound_length))
    bad("outlier_face_bound_length", "must be finite and > 0, got " + std::to_string(outlier_face_bound_length));
  if (!(outlier_face_depth >= 0.0) || !std::isfinite(outlier_face_depth))
    bad("outlier_face_depth", "must be finite and >= 0, got " + std::to_string(outlier_face_depth));
  if (!(outlier_face_reach >= 0.0) || !std::isfinite(outlier_face_reach))
    bad("outlier_face_reach", "must be finite and >= 0, got " + std::to_string(outlier_face_reach));
  if (!(outlier_face_support > 0.0 && outlier_face_support <= 1.0))
    bad("outlier_face_support", "must be in (0, 1], got " + std::to_string(outlier_face_support));
  if (!(auto_filter_growth == 0.0 || auto_filter_growth > 1.0) || !std::isfinite(auto_filter_growth))
    bad("auto_filter_growth", "must be 0 (off) or > 1, got " + std::to_string(auto_filter_growth));
}

PointMap::PointMap(const MapParams& params) : params_((params.validate(), params)), cloud_(new Cloud) {}

void PointMap::clear() {
  cloud_->clear();
  size_after_filter_ = 0;
}

void PointMap::reserve_for(std::size_t extra) {
  // Geometric growth: reserving the exact size on every insert would copy the
  // whole map each time.
  const std::size_t need = cloud_->size() + extra;
  if (need > cloud_->points.capacity()) cloud_->reserve(std::max(need, 2 * cloud_->points.capacity()));
}

void PointMap::insert(const Vec3& p) {
  if (!p.allFinite()) throw std::invalid_argument("PointMap::insert: non-finite point");
  cloud_->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  maybe_auto_filter();
}

void PointMap::insert(const std::vector<Vec3>& points) {
  for (const auto& p : points) {
    if (!p.allFinite()) throw std::invalid_argument("PointMap::insert: non-finite point");
  }
  reserve_for(points.size());
  for (const auto& p : points)
    cloud_->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  maybe_auto_filter();
}

std::vector<Vec3> PointMap::box_points(const Box& b, double spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) throw std::invalid_argument("PointMap::insert_box: spacing must be > 0");
  if (!b.center.allFinite() || !b.size.allFinite() || !std::isfinite(b.yaw) || (b.size.array() < 0.0).any())
    throw std::invalid_argument("PointMap::insert_box: non-finite or negative box");
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) n[a] = std::max(2, static_cast<int>(std::ceil(b.size[a] / spacing - 1e-9)) + 1);
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  std::vector<Vec3> pts;
  pts.reserve(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  for (int i = 0; i < n[0]; ++i) {
    const double u = -0.5 * b.size.x() + b.size.x() * i / (n[0] - 1);
    for (int j = 0; j < n[1]; ++j) {
      const double v = -0.5 * b.size.y() + b.size.y() * j / (n[1] - 1);
      const double x = b.center.x() + c * u - s * v, y = b.center.y() + s * u + c * v;
      for (int k = 0; k < n[2]; ++k) {
        const double w = -0.5 * b.size.z() + b.size.z() * k / (n[2] - 1);
        pts.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(b.center.z() + w));
      }
    }
  }
  return pts;
}

std::size_t PointMap::insert_box(const Box& b, double spacing) {
  const std::vector<Vec3> pts = box_points(b, spacing);
  reserve_for(pts.size());
  for (const auto& p : pts)
    cloud_->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  maybe_auto_filter();
  return pts.size();
}

std::size_t PointMap::remove_if(const std::function<bool(const Vec3&)>& drop) {
  const std::size_t before = cloud_->size();
  auto& v = cloud_->points;
  v.erase(std::remove_if(v.begin(), v.end(), [&](const pcl::PointXYZ& p) { return drop(Vec3(p.x, p.y, p.z)); }), v.end());
  cloud_->width = static_cast<uint32_t>(v.size());
  cloud_->height = 1;
  return before - cloud_->size();
}

void PointMap::maybe_auto_filter() {
  if (params_.auto_filter_growth <= 0.0 || cloud_->size() < params_.auto_filter_min_points) return;
  if (static_cast<double>(cloud_->size()) < params_.auto_filter_growth * static_cast<double>(size_after_filter_)) return;
  voxel_filter(params_.voxel_leaf);
  ++auto_filters_;
}

void PointMap::voxel_filter(double leaf) {
  if (!(leaf > 0.0)) throw std::invalid_argument("PointMap::voxel_filter: leaf must be > 0");
  if (!cloud_->empty()) {
    pcl::VoxelGrid<pcl::PointXYZ> vg;
    vg.setInputCloud(cloud_);
    const float l = static_cast<float>(leaf);
    vg.setLeafSize(l, l, l);
    Cloud::Ptr out(new Cloud);
    vg.filter(*out);
    cloud_ = out;
  }
  size_after_filter_ = cloud_->size();
}

std::size_t PointMap::remove_outliers(int mean_k, double stddev) {
  if (mean_k < 1 || !(stddev > 0.0)) throw std::invalid_argument("PointMap::remove_outliers: mean_k >= 1 and stddev > 0");
  if (cloud_->size() <= static_cast<std::size_t>(mean_k)) return 0;
  std::vector<bool> keep;
  if (params_.outlier_leaf > 0.0) {
    keep = outliers_at_leaf(mean_k, stddev, params_.outlier_leaf);
  } else {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
    sor.setInputCloud(cloud_);
    sor.setMeanK(mean_k);
    sor.setStddevMulThresh(stddev);
    pcl::Indices kept;
    sor.filter(kept);
    keep.assign(cloud_->size(), false);
    for (const auto k : kept) keep[static_cast<std::size_t>(k)] = true;
  }
  Cloud::Ptr out(new Cloud);
  Cloud removed;
  out->reserve(cloud_->size());
  for (std::size_t i = 0; i < cloud_->size(); ++i) (keep[i] ? *out : removed).push_back(cloud_->points[i]);
  if (params_.outlier_face_length > 0.0 && !removed.empty()) keep_face_ends(*out, removed);
  const std::size_t n_removed = cloud_->size() - out->size();
  cloud_ = out;
  size_after_filter_ = std::min(size_after_filter_, cloud_->size());
  return n_removed;
}

std::vector<bool> PointMap::outliers_at_leaf(int mean_k, double stddev, double leaf) const {
  // README "Outlier removal at the slab spacing" (rule 17): voxel centroids at `leaf`
  // (floor(p / leaf), as PCL's voxel grid), PCL's statistical outlier removal on them,
  // and every point of an outlier voxel removed.
  struct KeyHash {
    std::size_t operator()(const std::array<int64_t, 3>& k) const {
      return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<int64_t, 3>, std::size_t, KeyHash> index;
  std::vector<std::size_t> voxel_of(cloud_->size());
  std::vector<Eigen::Vector3d> sum;
  std::vector<std::size_t> count;
  for (std::size_t i = 0; i < cloud_->size(); ++i) {
    const auto& p = cloud_->points[i];
    const std::array<int64_t, 3> k{static_cast<int64_t>(std::floor(p.x / leaf)), static_cast<int64_t>(std::floor(p.y / leaf)),
                                   static_cast<int64_t>(std::floor(p.z / leaf))};
    const auto [it, fresh] = index.emplace(k, sum.size());
    if (fresh) {
      sum.emplace_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    sum[it->second] += Eigen::Vector3d(p.x, p.y, p.z);
    ++count[it->second];
    voxel_of[i] = it->second;
  }
  if (sum.size() <= static_cast<std::size_t>(mean_k)) return std::vector<bool>(cloud_->size(), true);
  Cloud::Ptr centroids(new Cloud);
  centroids->reserve(sum.size());
  for (std::size_t v = 0; v < sum.size(); ++v) {
    const Eigen::Vector3d c = sum[v] / static_cast<double>(count[v]);
    centroids->push_back(pcl::PointXYZ(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())));
  }
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(centroids);
  sor.setMeanK(mean_k);
  sor.setStddevMulThresh(stddev);
  pcl::Indices kept;
  sor.filter(kept);
  std::vector<bool> keep_voxel(sum.size(), false);
  for (const auto k : kept) keep_voxel[static_cast<std::size_t>(k)] = true;
  std::vector<bool> keep(cloud_->size());
  for (std::size_t i = 0; i < cloud_->size(); ++i) keep[i] = keep_voxel[voxel_of[i]];
  return keep;
}

std::size_t PointMap::keep_face_ends(Cloud& kept, const Cloud& removed) const {
  // README "Face ends kept by the faces' lines" (rule 18).
  const double tol = params_.outlier_face_tolerance, bin = 2.0 * tol;
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(kept.size());
  double z_lo = INFINITY, z_hi = -INFINITY;  // the removal works in 3-D, the faces in x-y
  for (const auto& p : kept) {
    xy.emplace_back(p.x, p.y);
    z_lo = std::fmin(z_lo, p.z);
    z_hi = std::fmax(z_hi, p.z);
  }
  if (xy.size() < 3) return 0;
  const std::vector<Eigen::Vector2d> hull = convex_hull(xy);
  struct Face {
    Eigen::Vector2d a, u, n;  // start, direction, outward normal (the hull is counter-clockwise)
    double length;
    bool extends;  // long enough to extend (outlier_face_length); shorter ones only bound
  };
  std::vector<Face> faces;
  for (std::size_t i = 0; hull.size() >= 3 && i < hull.size(); ++i) {
    const Eigen::Vector2d a = hull[i], b = hull[(i + 1) % hull.size()];
    const double length = (b - a).norm();
    if (length < std::min(params_.outlier_face_length, params_.outlier_face_bound_length)) continue;
    const Eigen::Vector2d u = (b - a) / length, n(u.y(), -u.x());
    const std::size_t bins = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(length / bin)));
    std::vector<char> hit(bins, 0);
    for (const auto& q : xy) {
      const Eigen::Vector2d d = q - a;
      const double t = d.dot(u);
      if (d.dot(n) < -tol || t < 0.0 || t > length) continue;
      hit[std::min(bins - 1, static_cast<std::size_t>(t / bin))] = 1;
    }
    const auto supported = static_cast<double>(std::count(hit.begin(), hit.end(), 1));
    if (supported >= params_.outlier_face_support * static_cast<double>(bins))
      faces.push_back({a, u, n, length, length >= params_.outlier_face_length});
  }
  if (faces.empty()) return 0;
  std::size_t put_back = 0;
  for (const auto& p : removed) {
    if (p.z < z_lo - tol || p.z > z_hi + tol) continue;  // off the kept points' height range
    const Eigen::Vector2d q(p.x, p.y);
    bool inside = true, on_face = false;
    for (const auto& f : faces) {
      const double out = (q - f.a).dot(f.n), t = (q - f.a).dot(f.u);
      if (out > params_.outlier_face_outside) {
        inside = false;
        break;
      }
      if (f.extends && out >= -params_.outlier_face_depth && t >= -params_.outlier_face_reach && t <= f.length + params_.outlier_face_reach)
        on_face = true;
    }
    if (inside && on_face) {
      kept.push_back(p);
      ++put_back;
    }
  }
  return put_back;
}

namespace {
double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}
}  // namespace

std::vector<Eigen::Vector2d> convex_hull(const std::vector<Eigen::Vector2d>& pts_in) {
  std::vector<Eigen::Vector2d> p = pts_in;
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  p.erase(std::unique(p.begin(), p.end(), [](const auto& a, const auto& b) { return a == b; }), p.end());
  if (p.size() <= 1) return p;
  // Andrew's monotone chain convex hull (counter-clockwise).
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

Rect2 min_area_rectangle(const std::vector<Eigen::Vector2d>& pts_in) {
  Rect2 r;
  if (pts_in.empty()) return r;
  const std::vector<Eigen::Vector2d> h = convex_hull(pts_in);
  if (h.size() == 1) {
    r.cx = h[0].x();
    r.cy = h[0].y();
    return r;
  }
  double area = 0.0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const auto& a = h[i];
    const auto& b = h[(i + 1) % h.size()];
    area += a.x() * b.y() - b.x() * a.y();
  }
  r.hull_area = 0.5 * std::abs(area);
  // The minimum-area rectangle has a side on a hull edge.
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Eigen::Vector2d e = h[(i + 1) % h.size()] - h[i];
    if (e.norm() < 1e-12) continue;
    const Eigen::Vector2d u = e.normalized(), v(-u.y(), u.x());
    double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
    for (const auto& q : h) {
      const double a = q.dot(u), b = q.dot(v);
      umin = std::min(umin, a);
      umax = std::max(umax, a);
      vmin = std::min(vmin, b);
      vmax = std::max(vmax, b);
    }
    const double A = (umax - umin) * (vmax - vmin);
    if (A < best - 1e-15) {
      best = A;
      const double lu = umax - umin, lv = vmax - vmin;
      const Eigen::Vector2d c = u * 0.5 * (umin + umax) + v * 0.5 * (vmin + vmax);
      r.cx = c.x();
      r.cy = c.y();
      const Eigen::Vector2d axis = lu >= lv ? u : v;
      r.length = std::max(lu, lv);
      r.width = std::min(lu, lv);
      double yaw = std::atan2(axis.y(), axis.x());
      if (yaw <= -M_PI / 2) yaw += M_PI;
      if (yaw > M_PI / 2) yaw -= M_PI;
      r.yaw = yaw;
    }
  }
  return r;
}

MapMeasurement PointMap::measure() const {
  MapMeasurement m;
  m.points = cloud_->size();
  if (cloud_->empty()) return m;
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(cloud_->size());
  m.min = Vec3::Constant(std::numeric_limits<double>::infinity());
  m.max = -m.min;
  for (const auto& p : *cloud_) {
    const Vec3 q(p.x, p.y, p.z);
    m.min = m.min.cwiseMin(q);
    m.max = m.max.cwiseMax(q);
    xy.emplace_back(q.x(), q.y());
  }
  const Rect2 r = min_area_rectangle(xy);
  m.length = r.length;
  m.width = r.width;
  m.height = m.max.z() - m.min.z();
  m.obb_area = r.length * r.width;
  m.hull_area = r.hull_area;
  m.yaw = r.yaw;
  m.center = Vec3(r.cx, r.cy, 0.5 * (m.min.z() + m.max.z()));
  return m;
}

// --- PLY -------------------------------------------------------------------------------

std::string ply_bytes(const Cloud& cloud, PlyFormat format, const PlyInfo& info) {
  auto one_line = [](const std::string& s) {
    std::string o = s;
    std::replace(o.begin(), o.end(), '\n', ' ');
    std::replace(o.begin(), o.end(), '\r', ' ');
    return o;
  };
  std::ostringstream h;
  h << "ply\n"
    << "format " << (format == PlyFormat::kAscii ? "ascii" : "binary_little_endian") << " 1.0\n"
    << "comment generator mapping_pcl\n"
    << "comment frame " << one_line(info.frame) << "\n"
    << "comment units " << one_line(info.units) << "\n";
  if (!info.comment.empty()) h << "comment " << one_line(info.comment) << "\n";
  h << "element vertex " << cloud.size() << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "end_header\n";
  std::string out = h.str();
  if (format == PlyFormat::kAscii) {
    std::ostringstream b;
    b.precision(9);  // float32 round-trips with 9 significant digits
    for (const auto& p : cloud) b << p.x << ' ' << p.y << ' ' << p.z << '\n';
    out += b.str();
  } else {
    const std::size_t off = out.size();
    out.resize(off + 12 * cloud.size());
    char* d = &out[off];
    for (const auto& p : cloud) {
      for (float f : {p.x, p.y, p.z}) {
        uint32_t u;
        std::memcpy(&u, &f, 4);
        for (int i = 0; i < 4; ++i) *d++ = static_cast<char>((u >> (8 * i)) & 0xFFu);  // little endian
      }
    }
  }
  return out;
}

void write_ply(const std::string& path, const Cloud& cloud, PlyFormat format, const PlyInfo& info) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  const std::string bytes = ply_bytes(cloud, format, info);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  f.close();
  if (!f) throw std::runtime_error(path + ": write failed");
}

}  // namespace mapping_pcl
