#include "mapping_pcl/xplorer_map_logic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace mapping_pcl {

using tactile_common::ParamMap;

namespace {
/// `state` is one of the FSM state names in `list` (stamp_states, release_states, contact_now_after).
bool listed(const std::vector<std::string>& list, const std::string& state) {
  return std::find(list.begin(), list.end(), state) != list.end();
}
}  // namespace

void XplorerMapLogic::Params::validate() const {
  stamping.validate();
  map.validate();
  auto bad = [](const char* f, const std::string& why) {
    throw std::invalid_argument(std::string("XplorerMapLogic.") + f + ": " + why);
  };
  if (force_average_samples < 1) bad("force_average_samples", "must be >= 1, got " + std::to_string(force_average_samples));
  if (!std::isfinite(floor_z)) bad("floor_z", "must be finite");
  if (!(publish_rate_hz >= 0.0) || !std::isfinite(publish_rate_hz)) bad("publish_rate_hz", "must be finite and >= 0 (0: never)");
  if (!(max_odometry_age_s > 0.0)) bad("max_odometry_age_s", "must be > 0");
  if (!(min_state_time_s >= 0.0) || !std::isfinite(min_state_time_s)) bad("min_state_time_s", "must be finite and >= 0");
  if (!(min_state_time_after_turn_s >= 0.0) || !std::isfinite(min_state_time_after_turn_s))
    bad("min_state_time_after_turn_s", "must be finite and >= 0");
  if (frame_id.empty()) bad("frame_id", "must not be empty");
  for (const auto& r : impact_turn_reasons)
    if (r.empty()) bad("impact_turn_reasons", "must not hold an empty reason (it would match every turn)");
  for (const auto& r : impact_turn_rules)
    if (r != "contact_now" && r != "steady" && r != "gate")
      bad("impact_turn_rules", "must hold only \"contact_now\", \"steady\", \"gate\", got \"" + r + "\"");
  if (!(max_arm_age_s > 0.0)) bad("max_arm_age_s", "must be > 0");
  if (force_now_samples < 0 || force_now_samples > force_average_samples)
    bad("force_now_samples", "must be in [0, force_average_samples], got " + std::to_string(force_now_samples));
}

ParamMap XplorerMapLogic::default_parameters() {
  const Params d;
  ParamMap m(kNodeName, "defaults");
  m.set("delta_map", d.stamping.delta_map);
  m.set("delta_map_hold", d.stamping.delta_map_hold);
  m.set("hold_in_traversal", d.stamping.hold_in_traversal);
  m.set("slab_size", std::vector<double>{d.stamping.slab_size.x(), d.stamping.slab_size.y(), d.stamping.slab_size.z()});
  m.set("slab_offset", d.stamping.slab_offset);
  m.set("corner_offset", d.stamping.corner_offset);
  m.set("rate_hz", d.stamping.rate_hz);
  m.set("corner_release_s", d.stamping.corner_release_s);
  m.set("slab_spacing", d.stamping.slab_spacing);
  m.set("min_flight_height", d.stamping.min_flight_height);
  m.set("normal_from_force", d.stamping.normal_from_force);
  m.set("voxel_leaf", d.map.voxel_leaf);
  m.set("outlier_mean_k", static_cast<int64_t>(d.map.outlier_mean_k));
  m.set("outlier_stddev", d.map.outlier_stddev);
  m.set("outlier_leaf", d.map.outlier_leaf);
  m.set("outlier_face_length", d.map.outlier_face_length);
  m.set("outlier_face_tolerance", d.map.outlier_face_tolerance);
  m.set("outlier_face_outside", d.map.outlier_face_outside);
  m.set("outlier_face_bound_length", d.map.outlier_face_bound_length);
  m.set("outlier_face_depth", d.map.outlier_face_depth);
  m.set("outlier_face_reach", d.map.outlier_face_reach);
  m.set("outlier_face_support", d.map.outlier_face_support);
  m.set("force_average_samples", static_cast<int64_t>(d.force_average_samples));
  m.set("floor_z", d.floor_z);
  m.set("publish_rate_hz", d.publish_rate_hz);
  m.set("max_odometry_age_s", d.max_odometry_age_s);
  m.set("frame_id", d.frame_id);
  m.set("ply_file", d.ply_file);
  m.set("ply_binary", d.ply_binary);
  m.set("stamp_states", d.stamp_states);
  m.set("min_state_time_s", d.min_state_time_s);
  m.set("min_state_time_after_turn_s", d.min_state_time_after_turn_s);
  m.set("edge_from_arms", d.stamping.edge_from_arms);
  m.set("min_arm_deflection", d.stamping.min_arm_deflection);
  m.set("arm_hinge_offset", d.stamping.arm_hinge_offset);
  m.set("arm_length", d.stamping.arm_length);
  m.set("guard_radius", d.stamping.guard_radius);
  m.set("max_arm_age_s", d.max_arm_age_s);
  m.set("min_force_now", d.stamping.min_force_now);
  m.set("force_now_samples", static_cast<int64_t>(d.force_now_samples));
  m.set("corner_angle_tolerance", d.stamping.corner_angle_tolerance);
  m.set("release_states", d.release_states);
  m.set("contact_now_after", d.contact_now_after);
  m.set("impact_turn_reasons", d.impact_turn_reasons);
  m.set("impact_turn_rules", d.impact_turn_rules);
  m.set("recent_axis", d.stamping.recent_axis);
  m.set("corner_fill_max_gap", d.stamping.corner_fill_max_gap);
  m.set("corner_fill_min_turn", d.stamping.corner_fill_min_turn);
  m.set("corner_fill_fit_length", d.stamping.corner_fill_fit_length);
  m.set("steady_distance", d.stamping.steady_distance);
  m.set("steady_angle", d.stamping.steady_angle);
  m.set("steady_offset", d.stamping.steady_offset);
  m.set("touching_half_ratio", d.stamping.touching_half_ratio);
  m.set("touching_half_s", d.stamping.touching_half_s);
  m.set("face_clip_min_length", d.stamping.face_clip_min_length);
  m.set("face_clip_max_residual", d.stamping.face_clip_max_residual);
  m.set("face_clip_tolerance", d.stamping.face_clip_tolerance);
  m.set("face_clip_margin", d.stamping.face_clip_margin);
  m.set("face_clip_angle_tolerance", d.stamping.face_clip_angle_tolerance);
  m.set("face_clip_corner_reach", d.stamping.face_clip_corner_reach);
  m.set("face_clip_tilted", d.stamping.face_clip_tilted);
  m.set("face_clip_tilted_reach", d.stamping.face_clip_tilted_reach);
  m.set("corner_fan_clip", d.stamping.corner_fan_clip);
  return m;
}

XplorerMapLogic::Params XplorerMapLogic::params_from(const ParamMap& m) {
  Params p;
  p.stamping.delta_map = m.get_double("delta_map");
  p.stamping.delta_map_hold = m.get_double("delta_map_hold");
  p.stamping.hold_in_traversal = m.get_bool("hold_in_traversal");
  const std::vector<double> s = m.get_double_array("slab_size");
  if (s.size() != 3) throw m.error("slab_size", "must have 3 elements (along the face, along C_n, height), got " + std::to_string(s.size()));
  p.stamping.slab_size = Vec3(s[0], s[1], s[2]);
  p.stamping.slab_offset = m.get_double("slab_offset");
  p.stamping.corner_offset = m.get_double("corner_offset");
  p.stamping.rate_hz = m.get_double("rate_hz");
  p.stamping.corner_release_s = m.get_double("corner_release_s");
  p.stamping.slab_spacing = m.get_double("slab_spacing");
  p.stamping.min_flight_height = m.get_double("min_flight_height");
  p.stamping.normal_from_force = m.get_bool("normal_from_force");
  p.map.voxel_leaf = m.get_double("voxel_leaf");
  p.map.outlier_mean_k = m.get_int("outlier_mean_k", 1, std::numeric_limits<int>::max());
  p.map.outlier_stddev = m.get_double("outlier_stddev");
  p.map.outlier_leaf = m.get_double("outlier_leaf");
  p.map.outlier_face_length = m.get_double("outlier_face_length");
  p.map.outlier_face_tolerance = m.get_double("outlier_face_tolerance");
  p.map.outlier_face_outside = m.get_double("outlier_face_outside");
  p.map.outlier_face_bound_length = m.get_double("outlier_face_bound_length");
  p.map.outlier_face_depth = m.get_double("outlier_face_depth");
  p.map.outlier_face_reach = m.get_double("outlier_face_reach");
  p.map.outlier_face_support = m.get_double("outlier_face_support");
  p.force_average_samples = m.get_int("force_average_samples", 1, std::numeric_limits<int>::max());
  p.floor_z = m.get_double("floor_z");
  p.publish_rate_hz = m.get_double("publish_rate_hz");
  p.max_odometry_age_s = m.get_double("max_odometry_age_s");
  p.frame_id = m.get_string("frame_id");
  p.ply_file = m.get_string("ply_file");
  p.ply_binary = m.get_bool("ply_binary");
  p.stamp_states = m.get_string_array("stamp_states");
  p.min_state_time_s = m.get_double("min_state_time_s");
  p.min_state_time_after_turn_s = m.get_double("min_state_time_after_turn_s");
  p.stamping.edge_from_arms = m.get_bool("edge_from_arms");
  p.stamping.min_arm_deflection = m.get_double("min_arm_deflection");
  p.stamping.arm_hinge_offset = m.get_double("arm_hinge_offset");
  p.stamping.arm_length = m.get_double("arm_length");
  p.stamping.guard_radius = m.get_double("guard_radius");
  p.max_arm_age_s = m.get_double("max_arm_age_s");
  p.stamping.min_force_now = m.get_double("min_force_now");
  // <= force_average_samples: validate() (its message names that parameter).
  p.force_now_samples = m.get_int("force_now_samples", 0, std::numeric_limits<int>::max());
  p.stamping.corner_angle_tolerance = m.get_double("corner_angle_tolerance");
  p.release_states = m.get_string_array("release_states");
  p.contact_now_after = m.get_string_array("contact_now_after");
  p.impact_turn_reasons = m.get_string_array("impact_turn_reasons");
  p.impact_turn_rules = m.get_string_array("impact_turn_rules");
  p.stamping.recent_axis = m.get_bool("recent_axis");
  p.stamping.corner_fill_max_gap = m.get_double("corner_fill_max_gap");
  p.stamping.corner_fill_min_turn = m.get_double("corner_fill_min_turn");
  p.stamping.corner_fill_fit_length = m.get_double("corner_fill_fit_length");
  p.stamping.steady_distance = m.get_double("steady_distance");
  p.stamping.steady_angle = m.get_double("steady_angle");
  p.stamping.steady_offset = m.get_double("steady_offset");
  p.stamping.touching_half_ratio = m.get_double("touching_half_ratio");
  p.stamping.touching_half_s = m.get_double("touching_half_s");
  p.stamping.face_clip_min_length = m.get_double("face_clip_min_length");
  p.stamping.face_clip_max_residual = m.get_double("face_clip_max_residual");
  p.stamping.face_clip_tolerance = m.get_double("face_clip_tolerance");
  p.stamping.face_clip_margin = m.get_double("face_clip_margin");
  p.stamping.face_clip_angle_tolerance = m.get_double("face_clip_angle_tolerance");
  p.stamping.face_clip_corner_reach = m.get_double("face_clip_corner_reach");
  p.stamping.face_clip_tilted = m.get_bool("face_clip_tilted");
  p.stamping.face_clip_tilted_reach = m.get_double("face_clip_tilted_reach");
  p.stamping.corner_fan_clip = m.get_bool("corner_fan_clip");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw m.error_from(e);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

XplorerMapLogic::XplorerMapLogic(const Params& params)
    : params_((params.validate(), params)), map_(params.map), mapper_(params.stamping, map_) {}

int64_t XplorerMapLogic::period_ns() const { return tactile_common::from_seconds(1.0 / params_.stamping.rate_hz); }

void XplorerMapLogic::on_wrench_body(const geometry_msgs::msg::WrenchStamped& msg) {
  ++stats_.received_wrench;
  const Eigen::Vector2d f(msg.wrench.force.x, msg.wrench.force.y);
  if (!f.allFinite()) {
    ++stats_.dropped_nonfinite;
    return;
  }
  if (msg.header.frame_id != "base_link" && !(odom_ && msg.header.frame_id == odom_->child_frame_id)) {
    ++stats_.dropped_wrong_frame;  // a world-frame wrench would stamp in the wrong direction
    return;
  }
  forces_.push_back(f);  // 001 Sec. V-C: moving average of the body force
  force_sum_ += f;
  while (static_cast<int>(forces_.size()) > params_.force_average_samples) {
    force_sum_ -= forces_.front();
    forces_.pop_front();
  }
}

void XplorerMapLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.received_odometry;
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(q.w) ||
      !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) {
    ++stats_.dropped_nonfinite;
    return;
  }
  odom_ = msg;
}

void XplorerMapLogic::on_fsm_state(const tactile_msgs::msg::FsmState& msg) {
  const bool changed = !fsm_state_ || *fsm_state_ != msg.state;
  const bool left_stamp_state =
      changed && fsm_state_ &&
      listed(params_.stamp_states, *fsm_state_);
  fsm_state_ = msg.state;
  fsm_state_since_s_ = tactile_common::to_seconds(tactile_common::from_stamp(msg.header.stamp)) - msg.time_in_state;
  fsm_previous_state_ = msg.previous_state;
  if (changed) {
    // README "Re-contact after a contact-lost turn": a turn entered because the face was
    // lost brings the vehicle back to the object from off its face, like Exploration.
    if (msg.state == kTurningState)
      turn_after_impact_reason_ = std::any_of(params_.impact_turn_reasons.begin(), params_.impact_turn_reasons.end(),
                                              [&](const std::string& r) { return msg.reason.rfind(r, 0) == 0; });
    entered_after_impact_turn_ = !listed(params_.contact_now_after, msg.previous_state) &&
                                 msg.previous_state == kTurningState && turn_after_impact_reason_;
    entered_after_impact_ = listed(params_.contact_now_after, msg.previous_state) || entered_after_impact_turn_;
  }
  // A corner release (001 Sec. IV-A: the yaw-rate peak that starts Tactile-turning):
  // the slabs stamped just before it overhang the face's end (corner_release_s).
  // Likewise at every other end of a traversal in release_states (README "Release on every end of a traversal").
  if (changed && listed(params_.release_states, msg.state))
    mapper_.release_corner(fsm_state_since_s_);
  // The end of a face traversal (README "Corner fill"): the corner between it
  // and the face before is filled if that one ended in a Tactile-turning.
  // README "Hold through a traversal": an initiated mapping lasts the traversal.
  if (changed) mapper_.hold_initiation(listed(params_.stamp_states, msg.state));
  if (left_stamp_state) mapper_.end_face(msg.state == kTurningState, msg.state == kDoneState);
  // A traversal after an impact (entered from a state of contact_now_after:
  // Exploration) holds its slabs until C_n is steady (README "Steady first contact").
  if (changed && listed(params_.stamp_states, msg.state) && entered_after_impact_ && impact_rule("steady"))
    mapper_.begin_steady_hold();
}

void XplorerMapLogic::on_arm_imu(const tactile_msgs::msg::ArmImuArray& msg) {
  ++stats_.received_arm_imu;
  const int64_t t = tactile_common::from_stamp(msg.header.stamp);
  for (const auto& a : msg.arms) {
    const double th = a.arm_angle;
    if (a.arm_id > 3 || !std::isfinite(th) || std::abs(th) > 0.8) {  // 0.8 rad: beyond the 30 deg end stops
      ++stats_.dropped_arm_samples;
      continue;
    }
    arm_angles_[a.arm_id] = th;
    arm_stamp_ns_[a.arm_id] = t;
  }
}

std::optional<sensor_msgs::msg::PointCloud2> XplorerMapLogic::on_timer(int64_t now_ns) {
  mapper_.commit(tactile_common::to_seconds(now_ns));
  const bool gated =
      fsm_state_ && !params_.stamp_states.empty() &&
      (!listed(params_.stamp_states, *fsm_state_) ||
       tactile_common::to_seconds(now_ns) - fsm_state_since_s_ <
           (short_gate_after_turn() && fsm_previous_state_ == kTurningState && !(entered_after_impact_ && impact_rule("gate"))
                ? params_.min_state_time_after_turn_s
                : params_.min_state_time_s));
  if (gated) {
    ++stats_.ticks_gated;
    // The initiation latch sees the force in every state: the firm contact
    // that initiates mapping (001 Sec. IV-B) is the one that started the traversal.
    if (!forces_.empty()) mapper_.observe_force(force_sum_ / static_cast<double>(forces_.size()));
  } else if (!odom_ || forces_.empty() ||
      tactile_common::to_seconds(now_ns - tactile_common::from_stamp(odom_->header.stamp)) > params_.max_odometry_age_s) {
    ++stats_.ticks_without_input;
  } else {
    const auto& p = odom_->pose.pose.position;
    const auto& q = odom_->pose.pose.orientation;
    ContactSample s;
    s.t = tactile_common::to_seconds(now_ns);
    s.position = Vec3(p.x, p.y, p.z);
    s.yaw = tactile_common::yaw_of(q);
    s.height = p.z - params_.floor_z;
    s.force_body = force_sum_ / static_cast<double>(forces_.size());
    if (fsm_state_) s.time_in_state = s.t - fsm_state_since_s_;
    const bool check_now =
        !fsm_state_ || params_.contact_now_after.empty() || (entered_after_impact_ && impact_rule("contact_now"));
    if (params_.force_now_samples > 0) {  // README "Contact now": the latest samples, not the 1 s average
      const std::size_t k = std::min<std::size_t>(forces_.size(), static_cast<std::size_t>(params_.force_now_samples));
      Eigen::Vector2d now = Eigen::Vector2d::Zero();
      for (std::size_t i = forces_.size() - k; i < forces_.size(); ++i) now += forces_[i];
      s.force_body_recent = now / static_cast<double>(k);  // README "Recent axis": in every state
      if (check_now) s.force_body_now = s.force_body_recent;
    }
    const int64_t max_age = tactile_common::from_seconds(params_.max_arm_age_s);
    if (std::all_of(arm_stamp_ns_.begin(), arm_stamp_ns_.end(),
                    [&](int64_t t) { return t >= 0 && now_ns - t <= max_age; })) {
      s.arm_angles = arm_angles_;
    }
    mapper_.update(s);
  }
  if (params_.publish_rate_hz <= 0.0) return std::nullopt;
  if (last_publish_ns_ >= 0 && now_ns - last_publish_ns_ < tactile_common::from_seconds(1.0 / params_.publish_rate_hz))
    return std::nullopt;
  last_publish_ns_ = now_ns;
  ++stats_.published;
  return to_point_cloud2(map_.cloud(), params_.frame_id, now_ns);
}

MapMeasurement XplorerMapLogic::finalize() {
  mapper_.flush();
  map_.voxel_filter();
  map_.remove_outliers();
  return map_.measure();
}

void XplorerMapLogic::save_ply(const std::string& path) const {
  const std::string out = path.empty() ? params_.ply_file : path;
  if (out.empty()) throw std::invalid_argument("XplorerMapLogic::save_ply: no path (parameter ply_file is empty)");
  PlyInfo info;
  info.frame = params_.frame_id;
  info.comment = "XPLORER contact map (paper 001 Sec. IV-B)";
  write_ply(out, map_.cloud(), params_.ply_binary ? PlyFormat::kBinaryLittleEndian : PlyFormat::kAscii, info);
}

}  // namespace mapping_pcl
