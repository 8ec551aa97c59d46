// XPLORER contact map stamping rules (001 Sec. IV-B, V-D).
#include "mapping_pcl/xplorer_stamping.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mapping_pcl {

void XplorerMapParams::validate() const {
  auto bad = [](const std::string& f, const std::string& why, double v) {
    throw std::invalid_argument("XplorerMapParams." + f + ": " + why + ", got " + std::to_string(v));
  };
  if (!(delta_map > 0.0) || !std::isfinite(delta_map)) bad("delta_map", "must be finite and > 0", delta_map);
  if (!(delta_map_hold > 0.0) || !(delta_map_hold <= delta_map)) bad("delta_map_hold", "must be > 0 and <= delta_map", delta_map_hold);
  for (int i = 0; i < 3; ++i) {
    if (!(slab_size[i] > 0.0) || !std::isfinite(slab_size[i])) bad("slab_size[" + std::to_string(i) + "]", "must be finite and > 0", slab_size[i]);
  }
  if (!(slab_offset >= 0.0) || !std::isfinite(slab_offset)) bad("slab_offset", "must be finite and >= 0", slab_offset);
  if (!(corner_offset >= 0.0) || !std::isfinite(corner_offset)) bad("corner_offset", "must be finite and >= 0", corner_offset);
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) bad("rate_hz", "must be finite and > 0", rate_hz);
  if (!(corner_release_s >= 0.0) || !std::isfinite(corner_release_s)) bad("corner_release_s", "must be finite and >= 0", corner_release_s);
  if (!(slab_spacing > 0.0) || !std::isfinite(slab_spacing)) bad("slab_spacing", "must be finite and > 0", slab_spacing);
  if (!std::isfinite(min_flight_height)) bad("min_flight_height", "must be finite", min_flight_height);
  if (!(arm_hinge_offset >= 0.0) || !std::isfinite(arm_hinge_offset)) bad("arm_hinge_offset", "must be finite and >= 0", arm_hinge_offset);
  if (!(arm_length > 0.0) || !std::isfinite(arm_length)) bad("arm_length", "must be finite and > 0", arm_length);
  if (!(min_arm_deflection >= 0.0) || !std::isfinite(min_arm_deflection)) bad("min_arm_deflection", "must be finite and >= 0", min_arm_deflection);
  if (!(min_force_now >= 0.0) || !std::isfinite(min_force_now)) bad("min_force_now", "must be finite and >= 0", min_force_now);
  if (!(corner_angle_tolerance >= 0.0) || !(corner_angle_tolerance <= M_PI))
    bad("corner_angle_tolerance", "must be in [0, pi] (>= pi/2: every change of lambda)", corner_angle_tolerance);
  if (!(guard_radius >= 0.0) || !std::isfinite(guard_radius)) bad("guard_radius", "must be finite and >= 0", guard_radius);
  if (!(corner_fill_max_gap >= 0.0) || !std::isfinite(corner_fill_max_gap))
    bad("corner_fill_max_gap", "must be finite and >= 0 (0: no corner fill)", corner_fill_max_gap);
  if (!(corner_fill_min_turn >= 0.0) || !(corner_fill_min_turn <= 0.75 * M_PI))
    bad("corner_fill_min_turn", "must be in [0, 3 pi / 4]", corner_fill_min_turn);
  if (!(corner_fill_fit_length > 0.0) || !std::isfinite(corner_fill_fit_length))
    bad("corner_fill_fit_length", "must be finite and > 0", corner_fill_fit_length);
  if (!(steady_distance >= 0.0) || !std::isfinite(steady_distance))
    bad("steady_distance", "must be finite and >= 0 (0: no steady first contact)", steady_distance);
  if (!(steady_angle > 0.0) || !(steady_angle <= M_PI / 2)) bad("steady_angle", "must be in (0, pi/2]", steady_angle);
  if (!(steady_offset > 0.0) || !std::isfinite(steady_offset)) bad("steady_offset", "must be finite and > 0", steady_offset);
  if (!(touching_half_ratio >= 0.0) || !(touching_half_ratio <= 1.0))
    bad("touching_half_ratio", "must be in [0, 1] (0: off)", touching_half_ratio);
  if (!(face_clip_min_length >= 0.0) || !std::isfinite(face_clip_min_length))
    bad("face_clip_min_length", "must be finite and >= 0 (0: no face clip)", face_clip_min_length);
  if (!(face_clip_max_residual > 0.0) || !std::isfinite(face_clip_max_residual))
    bad("face_clip_max_residual", "must be finite and > 0", face_clip_max_residual);
  if (!(face_clip_tolerance >= 0.0) || !std::isfinite(face_clip_tolerance))
    bad("face_clip_tolerance", "must be finite and >= 0", face_clip_tolerance);
  if (!(face_clip_angle_tolerance >= 0.0) || !(face_clip_angle_tolerance <= M_PI))
    bad("face_clip_angle_tolerance", "must be in [0, pi]", face_clip_angle_tolerance);
  if (!(face_clip_margin >= 0.0) || !std::isfinite(face_clip_margin)) bad("face_clip_margin", "must be finite and >= 0", face_clip_margin);
  if (!(face_clip_tilted_reach >= 0.0) || !std::isfinite(face_clip_tilted_reach))
    bad("face_clip_tilted_reach", "must be finite and >= 0", face_clip_tilted_reach);
  if (!(face_clip_corner_reach >= 0.0) || !std::isfinite(face_clip_corner_reach))
    bad("face_clip_corner_reach", "must be finite and >= 0 (0: the clip span is not extended to the corners)", face_clip_corner_reach);
  if (!(touching_half_s >= 0.0) || !std::isfinite(touching_half_s)) bad("touching_half_s", "must be finite and >= 0", touching_half_s);
}

namespace {
constexpr double kArmDir[4] = {-M_PI / 4, M_PI / 4, 3 * M_PI / 4, -3 * M_PI / 4};  // tactile_msgs/ArmImu.arm_id
}  // namespace

bool is_right_angle_corner(BodyDirection previous_body, const Eigen::Vector2d& previous_world,
                           BodyDirection body, const Eigen::Vector2d& world, double tolerance) {
  if (tolerance >= M_PI / 2) return true;  // 001: every change of lambda
  if (previous_body != body) return false;  // also before the first slab (kNone)
  const double turned = std::acos(std::clamp(previous_world.normalized().dot(world.normalized()), -1.0, 1.0));
  return std::abs(turned - M_PI / 2) <= tolerance;
}

bool both_arms_touch(const Eigen::Vector2d& d, const std::array<double, 4>& theta, double min_deflection) {
  for (int i = 0; i < 4; ++i) {
    if (Eigen::Vector2d(std::cos(kArmDir[i]), std::sin(kArmDir[i])).dot(d) > 1e-9 && !(std::abs(theta[i]) >= min_deflection))
      return false;
  }
  return true;
}

// README "Touching-guard half": +1 (-1) if only the facing arm left (right) of the body
// direction d touches by the ratio rule, 0 otherwise.
int touching_side(const Eigen::Vector2d& d, const std::array<double, 4>& theta, double ratio) {
  double left = -1.0, right = -1.0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d a(std::cos(kArmDir[i]), std::sin(kArmDir[i]));
    if (a.dot(d) <= 1e-9) continue;
    const double cross = d.x() * a.y() - d.y() * a.x();
    (cross > 0.0 ? left : right) = std::abs(theta[i]);
  }
  if (left < 0.0 || right < 0.0) return 0;  // C_n not between two arms
  if (right < ratio * left) return 1;
  if (left < ratio * right) return -1;
  return 0;
}

double outline_reach(const XplorerMapParams& p, const Eigen::Vector2d& d, const std::array<double, 4>& theta) {
  double reach = -1e300;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d tip =
        p.arm_hinge_offset * Eigen::Vector2d(std::cos(kArmDir[i]), std::sin(kArmDir[i])) +
        p.arm_length * Eigen::Vector2d(std::cos(kArmDir[i] + theta[i]), std::sin(kArmDir[i] + theta[i]));
    reach = std::max(reach, tip.dot(d));
  }
  return reach + p.guard_radius;
}

XplorerContactMapper::XplorerContactMapper(const XplorerMapParams& params, PointMap& map)
    : p_((params.validate(), params)), map_(&map) {}

Box XplorerContactMapper::face_slab(const ContactSample& s, BodyDirection contact) const {
  return face_slab_world(s, Eigen::Rotation2Dd(s.yaw) * unit(contact));  // C_n in the world
}

Box XplorerContactMapper::face_slab_world(const ContactSample& s, const Eigen::Vector2d& d, double offset) const {
  Box b;
  const double reach = (offset >= 0.0 ? offset : p_.slab_offset) + 0.5 * p_.slab_size.y();  // near face at the offset
  b.center = Vec3(s.position.x() + reach * d.x(), s.position.y() + reach * d.y(), s.position.z());
  b.size = p_.slab_size;
  b.yaw = std::atan2(d.y(), d.x()) + M_PI / 2;  // box x along the face, y along C_n
  return b;
}

Box XplorerContactMapper::corner_slab(const ContactSample& s, const Eigen::Vector2d& prev_w,
                                      const Eigen::Vector2d& now_w) const {
  Eigen::Vector2d diag = prev_w + now_w;
  if (diag.norm() < 1e-6) diag = now_w;
  diag.normalize();
  Box b;
  b.center = Vec3(s.position.x() + p_.corner_offset * diag.x(), s.position.y() + p_.corner_offset * diag.y(),
                  s.position.z());
  b.size = p_.slab_size;
  // Placed diagonally (001 Sec. IV-B), oriented like the new face's slab: a
  // slab turned by 45 deg would stick out of the faces by ~3 cm (README).
  b.yaw = std::atan2(now_w.y(), now_w.x()) + M_PI / 2;
  return b;
}

void XplorerContactMapper::stamp(double t, const Box& b, const Eigen::Vector2d& contact, const Eigen::Vector2d& near) {
  if (holding_) {  // README "Steady first contact"
    held_.push_back({t, b, contact, near, path_});
    return;
  }
  if (p_.corner_release_s <= 0.0) {
    insert_slab(b);
  } else {
    pending_.emplace_back(t, b);
  }
}

void XplorerContactMapper::insert_slab(const Box& b) {
  if (std::none_of(lines_.begin(), lines_.end(), [](const FaceLine& l) { return l.clips; })) {
    map_->insert_box(b, p_.slab_spacing);
    return;
  }
  std::vector<Vec3> pts = PointMap::box_points(b, p_.slab_spacing);
  const std::size_t before = pts.size();
  pts.erase(std::remove_if(pts.begin(), pts.end(), [&](const Vec3& q) { return outside_faces(q); }), pts.end());
  stats_.clipped_points += before - pts.size();
  map_->insert(pts);
}

bool XplorerContactMapper::right_angle(const FaceLine& a, const FaceLine& b) const {
  const double cross = std::abs(a.dir.x() * b.dir.y() - a.dir.y() * b.dir.x());  // sin of the angle between the lines
  return std::abs(std::asin(std::clamp(cross, 0.0, 1.0)) - M_PI / 2) <= p_.face_clip_angle_tolerance;
}

bool XplorerContactMapper::outside_faces(const Vec3& q) const {
  for (const auto& l : lines_) {
    if (!l.clips) continue;
    const Eigen::Vector2d d = Eigen::Vector2d(q.x(), q.y()) - l.point;
    const double s = d.dot(l.dir);
    if (s < l.clip_min - p_.face_clip_margin || s > l.clip_max + p_.face_clip_margin) continue;
    if (d.dot(l.contact) < -p_.face_clip_tolerance) return true;  // on the vehicle's side of the face
  }
  return false;
}

std::optional<XplorerContactMapper::FaceLine> XplorerContactMapper::fit_face(const std::vector<FaceSample>& f) const {
  constexpr std::size_t kMinSamples = 10;
  if (f.size() < kMinSamples) return std::nullopt;
  Eigen::Vector2d mean_c = Eigen::Vector2d::Zero();
  for (const auto& s : f) mean_c += s.contact;
  if (mean_c.norm() < 1e-9) return std::nullopt;
  mean_c.normalize();
  std::vector<bool> in(f.size(), true);
  const double cos_tol = std::cos(std::min(p_.face_clip_angle_tolerance, M_PI / 6));
  FaceLine l;
  for (int iter = 0; iter < 4; ++iter) {  // trimmed least squares: fit, keep the points near the line, refit
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < f.size(); ++i)
      if (in[i]) c += f[i].point, ++n;
    if (n < kMinSamples) return std::nullopt;
    c /= static_cast<double>(n);
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (std::size_t i = 0; i < f.size(); ++i)
      if (in[i]) cov += (f[i].point - c) * (f[i].point - c).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    l.point = c;
    l.dir = es.eigenvectors().col(1);  // largest eigenvalue: along the face
    Eigen::Vector2d nrm(-l.dir.y(), l.dir.x());
    if (nrm.dot(mean_c) < 0.0) nrm = -nrm;
    l.contact = nrm;
    // On the line: the near face within face_clip_max_residual of it and C_n across it within
    // face_clip_angle_tolerance (a traversal round a polygon's corner without a turn fits a chord
    // whose normal is the mean of the two faces' C_n, 30-40 deg off each: tuning polygon 1004).
    for (std::size_t i = 0; i < f.size(); ++i)
      in[i] = std::abs((f[i].point - c).dot(nrm)) <= p_.face_clip_max_residual && f[i].contact.dot(nrm) >= cos_tol;
  }
  std::size_t n = 0;
  l.s_min = 1e300;
  l.s_max = -1e300;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (!in[i]) continue;
    ++n;
    const double s = (f[i].point - l.point).dot(l.dir);
    l.s_min = std::min(l.s_min, s);
    l.s_max = std::max(l.s_max, s);
  }
  if (n < kMinSamples || 2 * n < f.size()) return std::nullopt;  // most of the face's slabs on the line
  if (l.s_max - l.s_min < p_.face_clip_min_length) return std::nullopt;
  l.clip_min = l.s_min;
  l.clip_max = l.s_max;
  return l;
}

void XplorerContactMapper::commit(double t) {
  while (!pending_.empty() && pending_.front().first <= t - p_.corner_release_s) {
    insert_slab(pending_.front().second);
    pending_.pop_front();
  }
}

std::size_t XplorerContactMapper::release_corner(double t) {
  while (!face_.empty() && face_.back().t > t - p_.corner_release_s) face_.pop_back();  // not part of the face
  std::size_t n = 0;
  while (!pending_.empty() && pending_.back().first > t - p_.corner_release_s) {
    pending_.pop_back();
    ++n;
  }
  stats_.dropped_at_corner += n;
  return n;
}

void XplorerContactMapper::begin_steady_hold() {
  drop_held();
  holding_ = p_.steady_distance > 0.0;
}

void XplorerContactMapper::drop_held() {
  stats_.dropped_unsteady += held_.size();
  held_.clear();
}

void XplorerContactMapper::join_lines(std::size_t ia, std::size_t ib) {
  FaceLine& a = lines_[ia];
  FaceLine& b = lines_[ib];
  a.clips = b.clips = true;
  if (p_.face_clip_corner_reach <= 0.0) return;
  // The corner: a.point + sa a.dir = b.point + sb b.dir (README "Face clip to the corner").
  Eigen::Matrix2d m;
  m << a.dir, -b.dir;
  if (std::abs(m.determinant()) < 1e-6) return;
  const Eigen::Vector2d st = m.inverse() * (b.point - a.point);
  auto extend = [&](FaceLine& l, double s) {
    if (s < l.s_min && l.s_min - s <= p_.face_clip_corner_reach) l.clip_min = std::min(l.clip_min, s);
    if (s > l.s_max && s - l.s_max <= p_.face_clip_corner_reach) l.clip_max = std::max(l.clip_max, s);
  };
  extend(a, st.x());
  extend(b, st.y());
}

bool XplorerContactMapper::in_slab(const Eigen::Vector2d& x, const FaceSample& q) const {
  const double half = 0.5 * p_.slab_size.x() + p_.slab_spacing, depth = p_.slab_size.y() + p_.slab_spacing;
  const Eigen::Vector2d d = x - q.point;
  const double along_c = d.dot(q.contact);
  const double across = d.x() * q.contact.y() - d.y() * q.contact.x();
  return along_c >= -p_.slab_spacing && along_c <= depth && std::abs(across) <= half;
}

bool XplorerContactMapper::convex_corner(const FaceLine& a, const FaceLine& b) const {
  auto middle = [](const FaceLine& l) -> Eigen::Vector2d { return l.point + 0.5 * (l.s_min + l.s_max) * l.dir; };
  return (middle(b) - a.point).dot(a.contact) >= -p_.slab_size.y() &&
         (middle(a) - b.point).dot(b.contact) >= -p_.slab_size.y();
}

std::size_t XplorerContactMapper::clip_tilted(const FaceLine& l, const std::vector<FaceSample>& f) {
  const double cos_tol = std::cos(p_.face_clip_angle_tolerance);
  std::vector<const FaceSample*> tilted;
  for (const auto& q : f) {
    if (q.contact.dot(l.contact) >= cos_tol) continue;
    const double s = (q.point - l.point).dot(l.dir);
    if (s < l.clip_min - p_.face_clip_tilted_reach || s > l.clip_max + p_.face_clip_tilted_reach) continue;
    tilted.push_back(&q);
  }
  if (tilted.empty()) return 0;
  return map_->remove_if([&](const Vec3& v) {
    const Eigen::Vector2d x(v.x(), v.y());
    if ((x - l.point).dot(l.contact) >= -p_.face_clip_tolerance) return false;  // not outside the line
    for (const FaceSample* q : tilted)
      if (in_slab(x, *q)) return true;
    return false;
  });
}

std::size_t XplorerContactMapper::clip_fan(const std::vector<FaceSample>& f, const Eigen::Vector2d& n, double offset) {
  const double half = 0.5 * p_.slab_size.x() + p_.slab_spacing, depth = p_.slab_size.y() + p_.slab_spacing;
  std::vector<const FaceSample*> near;  // the slabs that can reach outside the line
  for (const auto& q : f)
    if (q.point.dot(n) < offset + std::hypot(half, depth)) near.push_back(&q);
  if (near.empty()) return 0;
  return map_->remove_if([&](const Vec3& v) {
    const Eigen::Vector2d x(v.x(), v.y());
    if (x.dot(n) >= offset - p_.face_clip_tolerance) return false;  // not outside the other face
    for (const FaceSample* q : near)  // in one of the face's slabs
      if (in_slab(x, *q)) return true;
    return false;
  });
}

void XplorerContactMapper::clip_corner_fan(const FanFace& fan, const std::optional<FaceLine>& line) {
  // Each face's normal: its line's, else its slabs' mean C_n.
  auto normal = [](const std::optional<FaceLine>& l, const std::vector<FaceSample>& f) {
    if (l) return l->contact;
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (const auto& q : f) c += q.contact;
    return c.norm() > 1e-9 ? Eigen::Vector2d(c.normalized()) : c;
  };
  const Eigen::Vector2d ca = normal(fan.line, fan.samples), cb = normal(line, face_);
  if (ca.norm() < 0.5 || cb.norm() < 0.5) return;
  const double turn = std::acos(std::clamp(ca.dot(cb), -1.0, 1.0));
  if (std::abs(turn - M_PI / 2) > p_.face_clip_angle_tolerance) return;  // no right-angled corner
  // Each face's side: its line, else the face perpendicular to the other one's line (a box)
  // through the median of its near-face points; none if neither face is a line.
  if (!fan.line && !line) return;
  // The median offset of a face's near-face points along n.
  auto median_offset = [](const std::vector<FaceSample>& f, const Eigen::Vector2d& n) {
    std::vector<double> off;
    off.reserve(f.size());
    for (const auto& q : f) off.push_back(q.point.dot(n));
    std::nth_element(off.begin(), off.begin() + static_cast<std::ptrdiff_t>(off.size() / 2), off.end());
    return off[off.size() / 2];
  };
  auto side = [&](const std::optional<FaceLine>& l, const std::optional<FaceLine>& other, const std::vector<FaceSample>& f,
                  const Eigen::Vector2d& c) {
    if (l) return std::make_pair(l->contact, l->point.dot(l->contact));
    const Eigen::Vector2d n = other->dir.dot(c) >= 0.0 ? other->dir : Eigen::Vector2d(-other->dir);
    return std::make_pair(n, median_offset(f, n));
  };
  const auto [na, oa] = side(fan.line, line, fan.samples, ca);
  const auto [nb, ob] = side(line, fan.line, face_, cb);
  // A convex corner only: there each face lies, by the median of its near-face points, on the
  // object's side of the other (the side C_n points to). At a concave corner each lies on the
  // other's free side, and clipping there would remove the faces themselves.
  if (median_offset(face_, na) < oa - p_.slab_size.y() || median_offset(fan.samples, nb) < ob - p_.slab_size.y()) {
    ++stats_.skipped_concave_fan_clips;
    return;
  }
  stats_.clipped_points += clip_fan(fan.samples, nb, ob);  // A's slabs (its fan) outside B
  stats_.clipped_points += clip_fan(face_, na, oa);        // B's slabs outside A
  ++stats_.fan_clips;
}

void XplorerContactMapper::end_face(bool turned, bool loop_closed) {
  const bool after_first_turn = face_after_first_turn_;
  face_after_first_turn_ = false;
  if (turned && ++turns_ended_ == 1) face_after_first_turn_ = true;
  const std::optional<std::size_t> prev_line = prev_line_;  // face clip: the face before, if it ended in a turn
  prev_line_.reset();
  if (holding_) {  // the traversal ended before a steady stretch: its slabs do not say where the face is
    drop_held();
    holding_ = false;
  }
  if (face_.empty()) {
    turned_face_.reset();  // a face without slabs between two turns: the faces either side are not adjacent
    fan_face_.reset();
    return;
  }
  const bool first = !first_face_seen_;
  if (!first_face_seen_) {
    first_face_seen_ = true;
    if (p_.face_clip_tilted) first_face_ = face_;
  }
  if (turned_face_ && p_.corner_fill_max_gap > 0.0) {
    if (const auto f = corner_between(*turned_face_, face_)) {
      fill_corner(*f);
      ++stats_.corner_fills;
    } else {
      ++stats_.skipped_corner_fill;
    }
  }
  std::optional<FaceLine> fitted;  // this face's line (face clip)
  if (p_.face_clip_min_length > 0.0) {  // README "Face clip"
    fitted = fit_face(face_);
    if (const auto& l = fitted) {
      lines_.push_back(*l);
      ++stats_.face_lines;
      const std::size_t last = lines_.size() - 1;
      if (after_first_turn) after_first_turn_line_ = last;
      // Right-angle corner with the face before, joined by a turn (face_clip_angle_tolerance).
      // A concave corner (each face on the other's free side) is not joined: clipping there
      // would remove the faces themselves.
      if (prev_line && right_angle(lines_[*prev_line], lines_.back()) &&
          convex_corner(lines_[*prev_line], lines_.back()))
        join_lines(*prev_line, last);
      // The loop closed on the first contact's face: the face after the first turn is its neighbour (rule 13).
      if (loop_closed && after_first_turn_line_ && *after_first_turn_line_ != last &&
          right_angle(lines_[*after_first_turn_line_], lines_.back()) &&
          convex_corner(lines_[*after_first_turn_line_], lines_.back()))
        join_lines(*after_first_turn_line_, last);
      if (p_.face_clip_angle_tolerance >= M_PI / 2) lines_.back().clips = true;
      stats_.clipped_points += map_->remove_if([&](const Vec3& q) { return outside_faces(q); });
      if (p_.face_clip_tilted) {  // README "Tilted slabs"
        stats_.clipped_points += clip_tilted(lines_.back(), face_);
        if (loop_closed) stats_.clipped_points += clip_tilted(lines_.back(), first_face_);
      }
      if (turned) prev_line_ = lines_.size() - 1;
    }
  }
  if (p_.corner_fan_clip) {  // README "Fan past a right-angled corner" (rule 16)
    if (fan_face_) clip_corner_fan(*fan_face_, fitted);
    // At the loop's closure the last face may meet the first traversal's face at a corner too.
    if (loop_closed && first_fan_face_) clip_corner_fan(*first_fan_face_, fitted);
    fan_face_.reset();
    if (turned) fan_face_ = FanFace{fitted, face_};
    if (first) first_fan_face_ = FanFace{fitted, face_};
  }
  if (turned) {
    turned_face_ = std::move(face_);
  } else {
    turned_face_.reset();
  }
  face_.clear();
}

std::optional<XplorerContactMapper::CornerFill> XplorerContactMapper::corner_between(
    const std::vector<FaceSample>& a, const std::vector<FaceSample>& b) const {
  if (a.empty() || b.empty()) return std::nullopt;
  const Eigen::Rotation2Dd to_move(-M_PI / 2);  // lambda = C_n turned by -90 deg (right-hand)
  // A line through the mean near-face point along the mean C_n's lambda, over
  // the samples within fit_length (along lambda) of the face's corner end.
  auto line = [&](const std::vector<FaceSample>& f, bool from_end, Eigen::Vector2d& point, Eigen::Vector2d& move,
                  Eigen::Vector2d& contact) {
    const FaceSample& ref = from_end ? f.back() : f.front();
    const Eigen::Vector2d t0 = to_move * ref.contact;
    Eigen::Vector2d sp = Eigen::Vector2d::Zero(), sc = Eigen::Vector2d::Zero();
    int n = 0;
    for (const auto& s : f) {
      if (std::abs((s.point - ref.point).dot(t0)) > p_.corner_fill_fit_length) continue;
      sp += s.point;
      sc += s.contact;
      ++n;
    }
    point = sp / n;
    contact = sc.normalized();
    move = to_move * contact;
  };
  Eigen::Vector2d pa, ta, ca, pb, tb, cb;
  line(a, true, pa, ta, ca);
  line(b, false, pb, tb, cb);
  if (!ca.allFinite() || !cb.allFinite()) return std::nullopt;
  const double turn = std::acos(std::clamp(ca.dot(cb), -1.0, 1.0));
  if (turn < p_.corner_fill_min_turn || turn > 0.75 * M_PI) return std::nullopt;
  // pa + s ta = pb + u tb
  Eigen::Matrix2d m;
  m << ta, -tb;
  if (std::abs(m.determinant()) < 1e-6) return std::nullopt;
  const Eigen::Vector2d su = m.inverse() * (pb - pa);
  CornerFill f;
  f.corner = pa + su.x() * ta;
  f.end_a = pa + (a.back().point - pa).dot(ta) * ta;     // a's last point on a's line
  f.start_b = pb + (b.front().point - pb).dot(tb) * tb;  // b's first point on b's line
  const double gap_a = (f.corner - f.end_a).dot(ta), gap_b = (f.start_b - f.corner).dot(tb);
  constexpr double kSlack = 0.02;  // [m] the corner may lie that far inside a mapped end (noise of the lines)
  if (gap_a < -kSlack || gap_b < -kSlack || gap_a > p_.corner_fill_max_gap || gap_b > p_.corner_fill_max_gap)
    return std::nullopt;
  double z = 0.0;
  for (const auto& s : a) z += s.z;
  for (const auto& s : b) z += s.z;
  f.z = z / static_cast<double>(a.size() + b.size());
  return f;
}

std::size_t XplorerContactMapper::fill_corner(const CornerFill& f) {
  const double h = p_.slab_spacing;
  const Eigen::Vector2d e1 = f.end_a - f.corner, e2 = f.start_b - f.corner;
  const int n = std::max(2, static_cast<int>(std::ceil(std::max(e1.norm(), e2.norm()) / h)) + 1);
  const int nz = std::max(2, static_cast<int>(std::ceil(p_.slab_size.z() / h - 1e-9)) + 1);
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; i + j < n; ++j) {  // barycentric grid of the triangle (corner, end_a, start_b)
      const Eigen::Vector2d q = f.corner + e1 * (static_cast<double>(i) / (n - 1)) + e2 * (static_cast<double>(j) / (n - 1));
      for (int k = 0; k < nz; ++k)
        pts.emplace_back(q.x(), q.y(), f.z - 0.5 * p_.slab_size.z() + p_.slab_size.z() * k / (nz - 1));
    }
  }
  map_->insert(pts);
  return pts.size();
}

void XplorerContactMapper::flush() {
  end_face(false);
  for (const auto& [t, b] : pending_) insert_slab(b);
  pending_.clear();
}

void XplorerContactMapper::observe_force(const Eigen::Vector2d& f) {
  if (!f.allFinite()) return;
  const double n = f.norm();
  if (!initiated_ && n >= p_.delta_map) {  // 001 Sec. IV-B: "initializes when |b_delta_f| >= delta_map"
    initiated_ = true;
    ++stats_.initiations;
  } else if (initiated_ && n < p_.delta_map_hold && !(p_.hold_in_traversal && in_traversal_)) {  // README "Hold through a traversal"
    initiated_ = false;
    ++stats_.releases;
  }
}

int XplorerContactMapper::update(const ContactSample& s) {
  ++stats_.samples;
  if (!s.position.allFinite() || !std::isfinite(s.yaw) || !std::isfinite(s.height) || !s.force_body.allFinite() ||
      !std::isfinite(s.t)) {
    ++stats_.rejected_nonfinite;
    return 0;
  }
  observe_force(s.force_body);
  commit(s.t);
  const Eigen::Vector2d here(s.position.x(), s.position.y());
  if (last_xy_) path_ += (here - *last_xy_).norm();  // steady_distance
  last_xy_ = here;
  if (s.t - last_stamp_t_ < 1.0 / p_.rate_hz - 1e-9) {  // 001 Sec. IV-B: 30 Hz
    ++stats_.skipped_rate;
    return 0;
  }
  if (s.height < p_.min_flight_height) {  // 001 Sec. V-D: only while flying
    ++stats_.skipped_not_flying;
    return 0;
  }
  if (!initiated_) {  // 001 Sec. V-D: |b_delta_f| >= delta_map (then >= delta_map_hold)
    ++stats_.skipped_low_force;
    return 0;
  }
  const BodyDirection c = contact_direction(s.force_body, 0.0);
  if (c == BodyDirection::kNone) {
    ++stats_.skipped_low_force;
    return 0;
  }
  if (p_.min_force_now > 0.0 && s.force_body_now &&
      !(s.force_body_now->allFinite() && s.force_body_now->norm() >= p_.min_force_now)) {
    ++stats_.skipped_no_contact_now;  // the averaged force still holds a contact that has ended (README "Contact now")
    return 0;
  }
  if (p_.recent_axis && s.force_body_recent && s.force_body_recent->allFinite() &&
      contact_direction(*s.force_body_recent, 0.0) != c) {
    ++stats_.skipped_recent_axis;  // the average still holds the face before the turn (README "Recent axis")
    return 0;
  }
  const Eigen::Rotation2Dd R(s.yaw);
  const Eigen::Vector2d c_w = p_.normal_from_force ? Eigen::Vector2d(-(R * s.force_body).normalized()) : Eigen::Vector2d(R * unit(c));
  const bool arms_known = s.arm_angles && std::all_of(s.arm_angles->begin(), s.arm_angles->end(), [](double a) {
                            return std::isfinite(a);
                          });
  if (p_.min_arm_deflection > 0.0 && arms_known && !both_arms_touch(R.inverse() * c_w, *s.arm_angles, p_.min_arm_deflection)) {
    ++stats_.skipped_one_arm;  // 001 Sec. V-C1: two arms in contact with the obstacle
    return 0;
  }
  last_stamp_t_ = s.t;
  int stamped = 0;
  double offset = p_.slab_offset;  // 001 Sec. IV-B: 0.21 m
  if (p_.edge_from_arms && arms_known) {
    offset = outline_reach(p_, R.inverse() * c_w, *s.arm_angles);  // the CAD outline with the arms as they are
    ++stats_.offset_from_arms;
  }
  const Eigen::Vector2d xy(s.position.x(), s.position.y());
  const Eigen::Vector2d near = xy + offset * c_w;  // the slab's near face
  if (holding_ && !held_.empty() &&
      (held_.front().contact.dot(c_w) < std::cos(p_.steady_angle) ||
       std::abs((near - held_.front().near).dot(held_.front().contact)) > p_.steady_offset))
    drop_held();  // off the face of the held slabs: the stretch starts again here (README "Steady first contact")
  Box slab = face_slab_world(s, c_w, offset);
  if (p_.touching_half_ratio > 0.0 && arms_known && !(s.time_in_state && *s.time_in_state > p_.touching_half_s)) {
    if (const int side = touching_side(R.inverse() * c_w, *s.arm_angles, p_.touching_half_ratio)) {
      // box x is along the face, to the left of C_n: keep the half on the touching guard's side
      const Eigen::Vector2d left = Eigen::Rotation2Dd(M_PI / 2) * c_w;
      const double q = 0.25 * slab.size.x() * side;
      slab.center.x() += q * left.x();
      slab.center.y() += q * left.y();
      slab.size.x() *= 0.5;
      ++stats_.touching_half;
    }
  }
  stamp(s.t, slab, c_w, near);
  // The face's slabs, for the corner fill only (off: not kept; with stamp_states empty a face
  // would otherwise last the whole flight).
  if (p_.corner_fill_max_gap > 0.0 || p_.face_clip_min_length > 0.0) face_.push_back({s.t, near, c_w, s.position.z()});
  ++stats_.slabs;
  ++stamped;
  const Eigen::Vector2d m_w = Eigen::Rotation2Dd(-M_PI / 2) * c_w;  // lambda in the world (right-hand)
  const double ang = std::atan2(m_w.y(), m_w.x());
  const int move_world = static_cast<int>(std::lround(ang / (M_PI / 2))) & 3;  // nearest world axis
  if (last_move_world_ && *last_move_world_ != move_world) {  // 001 Sec. IV-B: corner
    if (is_right_angle_corner(last_contact_, last_contact_world_, c, c_w, p_.corner_angle_tolerance)) {
      stamp(s.t, corner_slab(s, last_contact_world_, c_w), c_w, near);
      ++stats_.corner_slabs;
      ++stamped;
    } else {
      ++stats_.skipped_corner_angle;  // README "Right-angle corners"
    }
  }
  last_move_world_ = move_world;
  last_contact_world_ = c_w;
  last_contact_ = c;
  if (holding_ && !held_.empty() && path_ - held_.front().path >= p_.steady_distance) {
    holding_ = false;  // steady over steady_distance: the held slabs enter as any other
    for (const auto& h : held_) stamp(h.t, h.box, h.contact, h.near);
    held_.clear();
  }
  return stamped;
}

}  // namespace mapping_pcl
