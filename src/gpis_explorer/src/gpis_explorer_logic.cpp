// Node logic of gpis_explorer. See gpis_explorer_logic.hpp.
#include "gpis_explorer/gpis_explorer_logic.hpp"

#include <cmath>
#include <algorithm>
#include <climits>
#include <stdexcept>

#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace gpis_explorer {

using tactile_common::ParamMap;

void GpisExplorerLogic::Params::validate() const {
  sequencer.validate();
  // The staleness threshold and the fail-safe bound are the wall follower's
  // (WallFollowerParams::validate() checks them finite and >= 0); a zero age
  // would call every input stale.
  if (!(sequencer.wall.max_input_age_s > 0.0)) {
    throw std::invalid_argument("GpisExplorerLogic.max_input_age_s: must be > 0, got " +
                                std::to_string(sequencer.wall.max_input_age_s));
  }
}

ParamMap GpisExplorerLogic::default_parameters() {
  const SequencerParams s;
  ParamMap m(kNodeName, "defaults");
  // GPIS (000 eq. 33-35; public onboard code values)
  m.set("gpis.beta", s.explorer.gpis.beta);
  m.set("gpis.c", s.explorer.gpis.c);
  m.set("gpis.noise", s.explorer.gpis.noise);
  m.set("gpis.max_points", static_cast<int64_t>(s.explorer.gpis.max_points));  // 000 Fig. S6: 50
  // Solver: exact (000) or local GPs over a quadtree (GPisMap; README "Local solver")
  m.set("gpis.solver", std::string(to_string(s.explorer.solver)));
  m.set("gpis.leaf_points", static_cast<int64_t>(s.explorer.local.leaf_points));
  m.set("gpis.overlap", s.explorer.local.overlap);
  m.set("gpis.min_leaf_size", s.explorer.local.min_leaf_size);
  m.set("gpis.label_neighbours", static_cast<int64_t>(s.explorer.local.label_neighbours));
  m.set("grid_size", s.explorer.grid_size);
  m.set("grid_cells", static_cast<int64_t>(s.explorer.grid_cells));  // 000: 10 x 10 onboard
  m.set("grid_variance", s.explorer.grid_variance);
  m.set("variance_cells", static_cast<int64_t>(s.explorer.variance_cells));
  m.set("corner_curvature", s.explorer.corner_curvature);  // 000 eq. 41, q
  m.set("penalty_scale", s.explorer.penalty_scale);        // 000 eq. 45, c
  m.set("corner_exclusion", s.explorer.corner_exclusion);
  // Wall following (000 Fig. S4e; tactile_fsm's values)
  m.set("v_max", s.wall.v_max);
  m.set("omega_max", s.wall.omega_max);
  m.set("t_min", s.wall.t_min);
  m.set("t_max", s.wall.t_max);
  m.set("whisker_spacing", s.wall.whisker_spacing);
  m.set("hover_init_s", s.wall.hover_init_s);
  m.set("flight_height", s.wall.flight_height);
  m.set("follow_side", std::string(tactile_fsm::to_string(s.wall.follow_side)));
  // Sequencing (000 Methods)
  m.set("probe_directions", static_cast<int64_t>(s.probe_directions));
  m.set("follow_time_s", s.follow_time_s);
  m.set("retreat_time_s", s.retreat_time_s);
  m.set("surface_points_per_follow", static_cast<int64_t>(s.surface_points_per_follow));
  m.set("interior_points_per_retreat", static_cast<int64_t>(s.interior_points_per_retreat));
  m.set("retreat_speed", s.retreat_speed);
  m.set("probe_max_distance", s.probe_max_distance);
  m.set("yaw_gain", s.yaw_gain);
  m.set("yaw_tolerance", s.yaw_tolerance);
  m.set("target_radius", s.target_radius);
  m.set("exit_confirm_distance", s.exit_confirm_distance);
  m.set("min_target_distance", s.min_target_distance);
  m.set("side_clearance", s.side_clearance);
  m.set("wall_extension", s.wall_extension);
  m.set("approach_standoff", s.approach_standoff);
  m.set("path_clearance", s.path_clearance);
  m.set("approach_clearance", s.approach_clearance);
  m.set("slow_distance", s.slow_distance);
  m.set("slow_fraction", s.slow_fraction);
  m.set("align_probes", s.align_probes);
  m.set("retreat_toward_follow_start", s.retreat_toward_follow_start);
  m.set("diagonal_probes", s.diagonal_probes);
  m.set("corner_confirm_radius", s.corner_confirm_radius);
  m.set("line_gain", s.line_gain);
  m.set("return_via_probe_line", s.return_via_probe_line);
  m.set("visited_radius", s.visited_radius);
  m.set("whisk_amplitude", s.whisk_amplitude);
  m.set("whisk_rate", s.whisk_rate);
  m.set("turn_rate", s.turn_rate);
  m.set("whisk_speed", s.whisk_speed);
  m.set("corridor_half_width", s.corridor_half_width);
  m.set("exit_beyond", s.exit_beyond);
  m.set("retreat_clearance", s.retreat_clearance);
  m.set("check_dwell_s", s.check_dwell_s);
  m.set("check_sample_s", s.check_sample_s);
  m.set("follow_min_forward", s.follow_min_forward);

  m.set("replace_when_full", s.replace_when_full);
  m.set("max_updates", static_cast<int64_t>(s.max_updates));
  m.set("max_time_s", s.max_time_s);
  m.set("landing_duration_s", s.landing_duration_s);
  // Stale depth / odometry -> FAILSAFE_HOVER, landing after failsafe_land_after_s
  // (the wall follower's keys, defaults and rule).
  m.set("max_input_age_s", s.wall.max_input_age_s);
  m.set("failsafe_land_after_s", s.wall.failsafe_land_after_s);
  return m;
}

GpisExplorerLogic::Params GpisExplorerLogic::params_from(const ParamMap& m) {
  Params p;
  SequencerParams& s = p.sequencer;
  s.explorer.gpis.beta = m.get_double("gpis.beta");
  s.explorer.gpis.c = m.get_double("gpis.c");
  s.explorer.gpis.noise = m.get_double("gpis.noise");
  s.explorer.gpis.max_points = m.get_size("gpis.max_points", 1, 100000);
  try {
    s.explorer.solver = solver_from_string(m.get_string("gpis.solver"));
  } catch (const std::invalid_argument& e) {
    throw m.error("gpis.solver", e.what());
  }
  s.explorer.local.leaf_points = m.get_size("gpis.leaf_points", 1, 100000);
  s.explorer.local.overlap = m.get_double("gpis.overlap");
  s.explorer.local.min_leaf_size = m.get_double("gpis.min_leaf_size");
  s.explorer.local.label_neighbours = m.get_size("gpis.label_neighbours", 0, 100000);
  s.explorer.grid_size = m.get_double("grid_size");
  s.explorer.grid_cells = m.get_integer<uint32_t>("grid_cells", 2, 5000);
  s.explorer.grid_variance = m.get_bool("grid_variance");
  s.explorer.variance_cells = m.get_integer<uint32_t>("variance_cells", 0, 5000);  // not 1: validate()
  s.explorer.corner_curvature = m.get_double("corner_curvature");
  s.explorer.penalty_scale = m.get_double("penalty_scale");
  s.explorer.corner_exclusion = m.get_double("corner_exclusion");
  s.wall.v_max = m.get_double("v_max");
  s.wall.omega_max = m.get_double("omega_max");
  s.wall.t_min = m.get_double("t_min");
  s.wall.t_max = m.get_double("t_max");
  s.wall.whisker_spacing = m.get_double("whisker_spacing");
  s.wall.hover_init_s = m.get_double("hover_init_s");
  s.wall.flight_height = m.get_double("flight_height");
  try {
    s.wall.follow_side = tactile_fsm::side_from_string(m.get_string("follow_side").c_str());
  } catch (const std::invalid_argument& e) {
    throw m.error("follow_side", e.what());
  }
  s.probe_directions = m.get_int("probe_directions", 1, 16);
  s.follow_time_s = m.get_double("follow_time_s");
  s.retreat_time_s = m.get_double("retreat_time_s");
  s.surface_points_per_follow = m.get_int("surface_points_per_follow", 1, 1000);
  s.interior_points_per_retreat = m.get_int("interior_points_per_retreat", 0, 1);
  s.retreat_speed = m.get_double("retreat_speed");
  s.probe_max_distance = m.get_double("probe_max_distance");
  s.yaw_gain = m.get_double("yaw_gain");
  s.yaw_tolerance = m.get_double("yaw_tolerance");
  s.target_radius = m.get_double("target_radius");
  s.exit_confirm_distance = m.get_double("exit_confirm_distance");
  s.min_target_distance = m.get_double("min_target_distance");
  s.side_clearance = m.get_double("side_clearance");
  s.wall_extension = m.get_double("wall_extension");
  s.approach_standoff = m.get_double("approach_standoff");
  s.path_clearance = m.get_double("path_clearance");
  s.approach_clearance = m.get_double("approach_clearance");
  s.slow_distance = m.get_double("slow_distance");
  s.slow_fraction = m.get_double("slow_fraction");
  s.align_probes = m.get_bool("align_probes");
  s.retreat_toward_follow_start = m.get_bool("retreat_toward_follow_start");
  s.diagonal_probes = m.get_bool("diagonal_probes");
  s.corner_confirm_radius = m.get_double("corner_confirm_radius");
  s.replace_when_full = m.get_bool("replace_when_full");
  s.line_gain = m.get_double("line_gain");
  s.return_via_probe_line = m.get_bool("return_via_probe_line");
  s.visited_radius = m.get_double("visited_radius");
  s.whisk_amplitude = m.get_double("whisk_amplitude");
  s.whisk_rate = m.get_double("whisk_rate");
  s.turn_rate = m.get_double("turn_rate");
  s.whisk_speed = m.get_double("whisk_speed");
  s.corridor_half_width = m.get_double("corridor_half_width");
  s.exit_beyond = m.get_double("exit_beyond");
  s.retreat_clearance = m.get_double("retreat_clearance");
  s.check_dwell_s = m.get_double("check_dwell_s");
  s.check_sample_s = m.get_double("check_sample_s");
  s.follow_min_forward = m.get_double("follow_min_forward");

  s.max_updates = m.get_int("max_updates", 1, 1000000);
  s.max_time_s = m.get_double("max_time_s");
  s.landing_duration_s = m.get_double("landing_duration_s");
  s.wall.max_input_age_s = m.get_double("max_input_age_s");
  s.wall.failsafe_land_after_s = m.get_double("failsafe_land_after_s");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw tactile_common::ParamError(m.source() + ": " + m.node() + ".ros__parameters: " + e.what());
  }
  return p;
}

GpisExplorerLogic::GpisExplorerLogic(const Params& params) : params_((params.validate(), params)), seq_(params.sequencer) {}

void GpisExplorerLogic::on_depth(const tactile_msgs::msg::TactileDepth& msg) {
  ++stats_.received_depth;
  if ((msg.contact_left && !std::isfinite(msg.depth_left)) || (msg.contact_right && !std::isfinite(msg.depth_right))) {
    ++stats_.dropped_nonfinite;
    return;
  }
  const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
  if (stamp < depth_ns_) {
    ++stats_.dropped_out_of_order;
    return;
  }
  depth_ns_ = stamp;
  depth_t_ = tactile_common::to_seconds(stamp);
  in_.contact_left = msg.contact_left;
  in_.contact_right = msg.contact_right;
  in_.depth_left = msg.contact_left ? msg.depth_left : NAN;
  in_.depth_right = msg.contact_right ? msg.depth_right : NAN;
  in_.point_left = {msg.contact_point_left.x, msg.contact_point_left.y};
  in_.point_right = {msg.contact_point_right.x, msg.contact_point_right.y};
}

void GpisExplorerLogic::on_odometry(const nav_msgs::msg::Odometry& msg) {
  ++stats_.received_odom;
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  const double qn = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(qn) || qn < 1e-12) {
    ++stats_.dropped_nonfinite;
    return;
  }
  const int64_t stamp = tactile_common::from_stamp(msg.header.stamp);
  if (stamp < odom_ns_) {
    ++stats_.dropped_out_of_order;
    return;
  }
  odom_ns_ = stamp;
  odom_t_ = tactile_common::to_seconds(stamp);
  if (!msg.header.frame_id.empty()) odom_frame_ = msg.header.frame_id;
  if (!msg.child_frame_id.empty()) body_frame_ = msg.child_frame_id;
  in_.x = p.x;
  in_.y = p.y;
  in_.yaw = tactile_common::yaw_of(q);
}

tactile_msgs::msg::GpisMap GpisExplorerLogic::make_map(const GpisExplorer& ex, int64_t stamp_ns,
                                                      const std::string& frame) {
  tactile_msgs::msg::GpisMap m;
  tactile_common::to_stamp(stamp_ns, m.header.stamp);
  m.header.frame_id = frame;
  const GridSpec& g = ex.grid();
  m.origin_x = g.origin_x;
  m.origin_y = g.origin_y;
  m.resolution = g.resolution;
  m.width = g.width;
  m.height = g.height;
  m.mean.assign(ex.grid_mean().begin(), ex.grid_mean().end());
  m.variance.assign(ex.grid_variance().begin(), ex.grid_variance().end());
  for (std::size_t i = 0; i < ex.gpis().size(); ++i) {
    geometry_msgs::msg::Point pt;
    pt.x = ex.gpis().point(i).x();
    pt.y = ex.gpis().point(i).y();
    m.training_points.push_back(pt);
    m.training_labels.push_back(static_cast<int8_t>(ex.gpis().label(i)));
  }
  for (const auto& c : ex.last().contours) {
    m.contour_starts.push_back(static_cast<uint32_t>(m.contour.size()));
    for (const auto& q : c.contour.points) {
      geometry_msgs::msg::Point pt;
      pt.x = q.x();
      pt.y = q.y();
      m.contour.push_back(pt);
    }
  }
  for (const auto& c : ex.last().corners) {
    geometry_msgs::msg::Point pt;
    pt.x = c.x();
    pt.y = c.y();
    m.corners.push_back(pt);
  }
  return m;
}

GpisExplorerLogic::Outputs GpisExplorerLogic::on_timer(int64_t now_ns) {
  ++stats_.ticks;
  Outputs out;
  // The wall follower's staleness rule and threshold (one definition).
  const double age = params_.sequencer.wall.max_input_age_s;
  in_.t = tactile_common::to_seconds(now_ns);
  in_.pose_valid = tactile_fsm::input_fresh(in_.t, odom_t_, age);
  in_.depth_valid = tactile_fsm::input_fresh(in_.t, depth_t_, age);
  if (!in_.pose_valid || !in_.depth_valid) ++stats_.stale_ticks;
  const SequencerOutput so = seq_.step(in_);
  auto& sp = out.setpoint;
  tactile_common::to_stamp(now_ns, sp.header.stamp);
  sp.header.frame_id = body_frame_;  // body-frame velocities
  sp.vx = so.setpoint.vx;
  sp.vy = so.setpoint.vy;
  sp.yaw_rate = so.setpoint.yaw_rate;
  sp.height = so.setpoint.height;
  sp.land = so.setpoint.land;
  if (so.transitioned || last_state_ns_ == INT64_MIN || now_ns - last_state_ns_ >= kStatePeriodNs) {
    tactile_msgs::msg::FsmState st;
    st.header.stamp = sp.header.stamp;
    st.behaviour = kBehaviour;
    st.state = to_string(seq_.phase());
    st.previous_state = to_string(seq_.previous_phase());
    st.reason = seq_.reason();
    st.time_in_state = in_.t - seq_.phase_entered();
    st.transitions = seq_.transitions();
    out.state = st;
    last_state_ns_ = now_ns;
  }
  if (so.gpis_updated) {
    out.map = make_map(seq_.explorer(), now_ns, odom_frame_);
    ++stats_.maps_published;
    tactile_msgs::msg::ExplorationTarget t;
    t.header.stamp = sp.header.stamp;
    t.header.frame_id = odom_frame_;
    t.target.x = seq_.target().x();
    t.target.y = seq_.target().y();
    t.acquisition = seq_.target_acquisition();
    t.variance = seq_.target_variance();
    t.gpis_update = static_cast<uint32_t>(seq_.explorer().updates());
    t.exit_found = seq_.exit_found();
    out.target = t;
  }
  return out;
}

}  // namespace gpis_explorer
