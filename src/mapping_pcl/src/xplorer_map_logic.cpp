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

const std::vector<std::pair<std::string, uint8_t>>& XplorerMapLogic::turning_reasons() {
  using tactile_msgs::msg::FsmState;
  static const std::vector<std::pair<std::string, uint8_t>> reasons = {
      {"yaw_rate_peak", FsmState::REASON_XPLORER_YAW_RATE_PEAK},         // a convex corner (001 Sec. IV-A)
      {"contact_lost_turn", FsmState::REASON_XPLORER_CONTACT_LOST_TURN},  // about a face's end after a contact lost
  };
  return reasons;
}

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
  for (const auto& r : impact_turn_reasons) {
    const auto& known = turning_reasons();
    if (std::none_of(known.begin(), known.end(), [&](const auto& k) { return k.first == r; })) {
      std::string names;
      for (const auto& k : known) names += (names.empty() ? "\"" : ", \"") + k.first + "\"";
      bad("impact_turn_reasons", "must hold only reasons of entering tactile_turning (" + names + "), got \"" + r + "\"");
    }
  }
  for (const auto& r : impact_turn_rules)
    if (r != "contact_now" && r != "steady" && r != "gate")
      bad("impact_turn_rules", "must hold only \"contact_now\", \"steady\", \"gate\", got \"" + r + "\"");
  if (!(max_arm_age_s > 0.0)) bad("max_arm_age_s", "must be > 0");
  if (force_now_samples < 0 || force_now_samples > force_average_samples)
    bad("force_now_samples", "must be in [0, force_average_samples], got " + std::to_string(force_now_samples));
}

ParamMap XplorerMapLogic::default_parameters() {
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  using tactile_common::tuned;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr int kIntMax = std::numeric_limits<int>::max();
  const ParamRange up_to_inf{0.0, kInf, true, false};  // "> 0" without a finite check: inf = never stale
  const Params d;
  const XplorerMapParams& s = d.stamping;
  ParamMap m(kNodeName, "defaults");
  // The mapper's parameter spec: value, description (from the Params comments; README
  // "Parameters" and "Procedural objects"), unit, the range params_from()/validate() take for
  // the key alone (a bound set by another key is named in the description), and none live:
  // the map, the stamping state and the FSM gates are built at start, so `ros2 param set`
  // refuses every key (read-only).
  m.set("delta_map", s.delta_map,
        {"|b_delta_f| that initiates the mapping (001 Sec. V-D)", "N", positive(), false,
         paper("001 Sec. V-D: delta_map = 1.51 N")});
  m.set("delta_map_hold", s.delta_map_hold,
        {"once initiated, the mapping goes on while the force stays at least this; <= delta_map "
         "(choice; README \"Mapping is initiated\")", "N", positive(), false,
         tuned("README rule 1: 0.5 N, block 1000 8 -> 22 of 50")});
  m.set("hold_in_traversal", s.hold_in_traversal,
        {"an initiation inside a traversal (stamp_states) holds until the traversal ends (choice; rule 14, "
         "README \"Hold through a traversal\")", "", {}, false,
         tuned("README rule 14: block 12700 +8, held out 13000-13299 284 of 300 with rule 15")});
  m.set("slab_size", std::vector<double>{s.slab_size.x(), s.slab_size.y(), s.slab_size.z()},
        {"slab along the face, along C_n, height; 3 values, each finite and > 0 (001 Sec. IV-B)", "m", {}, false,
         paper("001 Sec. IV-B: 0.25 x 0.08 x 0.5 m boxes")});
  m.set("slab_offset", s.slab_offset,
        {"vehicle centre -> slab's near face along C_n (001 Sec. IV-B)", "m", at_least(0.0), false,
         paper("001 Sec. IV-B: 0.21 m")});
  m.set("corner_offset", s.corner_offset,
        {"vehicle centre -> corner slab centre, along the diagonal (001 Sec. IV-B)", "m", at_least(0.0), false,
         paper("001 Sec. IV-B: 0.417 m")});
  m.set("rate_hz", s.rate_hz, {"stamping rate (001 Sec. IV-B: 30 Hz)", "Hz", positive(), false,
        paper("001 Sec. IV-B: 30 Hz")});
  m.set("corner_release_s", s.corner_release_s,
        {"slabs are held back this long; a corner release drops those stamped within it (choice; README "
         "\"Corner release\"); 0: every slab enters at once", "s", at_least(0.0), false,
         tuned("README rule 2: 0.6 s, block 1000 boxes 0 -> 13 of 17")});
  m.set("slab_spacing", s.slab_spacing,
        {"point spacing inside a slab (choice; the map is voxel-filtered at 1 cm)", "m", positive(), false,
         choice("2 cm: the map is voxel-filtered at 1 cm")});
  m.set("min_flight_height", s.min_flight_height,
        {"\"mapping only when flying\": height above floor_z (choice); finite", "m", {}, false, choice()});
  m.set("normal_from_force", s.normal_from_force,
        {"false: slab along the contact axis C_n (001); true: opposite to the measured force (choice, not kept)",
         "", {}, false, tuned("README \"Rules off\": true 37 -> 22 of 50; false is 001's C_n")});
  m.set("voxel_leaf", d.map.voxel_leaf, {"voxel-grid leaf of the map (issue 6: 1 cm)", "m", positive(), false,
        choice("issue 6: 1 cm")});
  m.set("outlier_mean_k", static_cast<int64_t>(d.map.outlier_mean_k),
        {"neighbours of the statistical outlier removal (choice)", "", closed(1, kIntMax), false, choice()});
  m.set("outlier_stddev", d.map.outlier_stddev,
        {"std-dev multiplier of the statistical outlier removal (choice)", "", positive(), false, choice()});
  m.set("outlier_leaf", d.map.outlier_leaf,
        {"> 0: the outlier removal judges the map voxelised at this leaf; 0: on the map's own points (choice; "
         "rule 17, README \"Outlier removal at the slab spacing\", not kept)", "m", at_least(0.0), false,
         tuned("README rule 17, not kept: 0.02 m blocks 13300 / 13000 283 -> 279, 286 -> 281")});
  m.set("outlier_face_length", d.map.outlier_face_length,
        {"faces: supported hull edges at least this long; removed points near them are put back (choice; "
         "rule 18, README \"Face ends kept by the faces' lines\"); 0: off", "m", at_least(0.0), false,
         tuned("README rule 18: blocks 13000 / 12700 / 13300 +1 / +1 / +2, held out 293 of 300")});
  m.set("outlier_face_tolerance", d.map.outlier_face_tolerance,
        {"support and height tolerance of the faces (rule 18); >= 1e-4 m: one byte per bin per face", "m",
         at_least(1e-4), false, choice("rule 18")});
  m.set("outlier_face_outside", d.map.outlier_face_outside,
        {"a removed point is put back at most this far outside every face's line (rule 18); finite", "m", {},
         false, choice("rule 18")});
  m.set("outlier_face_bound_length", d.map.outlier_face_bound_length,
        {"shorter supported hull edges at least this long bound without extending (rule 18)", "m", positive(),
         false, choice("rule 18")});
  m.set("outlier_face_depth", d.map.outlier_face_depth,
        {"a removed point is put back within this depth inside a face's line (rule 18: slab depth 0.08 m and a "
         "margin)", "m", at_least(0.0), false, choice("rule 18: slab depth 0.08 m and a margin")});
  m.set("outlier_face_reach", d.map.outlier_face_reach,
        {"... and at most this far beyond that face's ends (rule 18)", "m", at_least(0.0), false, choice("rule 18")});
  m.set("outlier_face_support", d.map.outlier_face_support,
        {"fraction of a hull edge's length that must hold kept points to make it a face (rule 18)", "",
         ParamRange{0.0, 1.0, true, false}, false, choice("rule 18")});
  m.set("force_average_samples", static_cast<int64_t>(d.force_average_samples),
        {"moving average of the body force (001 Sec. V-C: 50 samples); >= force_now_samples", "samples",
         closed(1, kIntMax), false, paper("001 Sec. V-C: 50 samples")});
  m.set("floor_z", d.floor_z, {"floor height for the flying check; finite", "m", {}, false, choice()});
  m.set("publish_rate_hz", d.publish_rate_hz,
        {"PointCloud2 rate (choice: the full map is large); 0: never", "Hz", at_least(0.0), false, choice()});
  m.set("max_odometry_age_s", d.max_odometry_age_s,
        {"older odometry pauses the stamping (choice)", "s", up_to_inf, false, choice()});
  m.set("frame_id", d.frame_id,
        {"frame of the cloud: the odometry poses' frame (REP 105); not empty", "", {}, false, choice("REP 105")});
  m.set("ply_file", d.ply_file, {"PLY written by save_ply(); \"\": none", "", {}, false, choice()});
  m.set("ply_binary", d.ply_binary, {"false: ASCII PLY as 001; true: binary little endian", "", {}, false,
        paper("001 Sec. IV-B: PLY in the ASCII format")});
  m.set("stamp_states", d.stamp_states,
        {"stamp only while the FSM is in one of these states (once an FsmState is heard); empty: always "
         "(choice; 001 gates on force only)", "", {}, false,
         choice("001 gates on force only; README \"Initiation and the stamp's gates\"")});
  m.set("min_state_time_s", d.min_state_time_s,
        {"... and has been in it this long (choice: the 1 s force average still holds the turn)", "s",
         at_least(0.0), false, tuned("README rule 4: 1 s (2 s: polygons 5 -> 9 of 18 with 1 s)")});
  m.set("min_state_time_after_turn_s", d.min_state_time_after_turn_s,
        {"... or this long in a traversal entered from Tactile-turning (choice; README \"Recent axis\")", "s",
         at_least(0.0), false, tuned("README rule 8: blocks 1000 / 2000 38 -> 44, 39 -> 42 of 50")});
  m.set("edge_from_arms", s.edge_from_arms,
        {"face-slab offset from the vehicle CAD with the arms as the arm IMUs measure them, not the fixed "
         "slab_offset (choice; 001 Sec. IV-B maps with the CAD model)", "", {}, false,
         tuned("README \"Offset from the deflected arms\": faces 4.5-5.5 mm inside with the fixed offset (SITL)")});
  m.set("min_arm_deflection", s.min_arm_deflection,
        {"stamp only if both arms on the C_n side are deflected at least this much (choice; 001 Sec. V-C1, "
         "README \"Two arms in contact\"); 0: no check", "rad", at_least(0.0), false,
         tuned("README rule 3: 0.002 rad (0.005 cut the 0.4 m pipe's loop); 001 Sec. V-C1")});
  m.set("arm_hinge_offset", s.arm_hinge_offset,
        {"vehicle centre -> arm hinge along the diagonal (vehicle CAD)", "m", at_least(0.0), false,
         choice("vehicle CAD")});
  m.set("arm_length", s.arm_length, {"arm hinge -> motor (vehicle CAD)", "m", positive(), false,
        choice("vehicle CAD")});
  m.set("guard_radius", s.guard_radius, {"propeller guard radius round the motor (vehicle CAD)", "m",
                                         at_least(0.0), false, choice("vehicle CAD")});
  m.set("max_arm_age_s", d.max_arm_age_s,
        {"older arm angles: the fixed slab_offset is used (choice; arm IMUs at 50 Hz)", "s", up_to_inf, false,
         choice("arm IMUs at 50 Hz")});
  m.set("min_force_now", s.min_force_now,
        {"stamp only if the mean of the latest force_now_samples wrench samples is at least this (choice; "
         "README \"Contact now\"); 0: no check", "N", at_least(0.0), false,
         tuned("README rule 5: block 1000 34 -> 38 of 50, held out 41 -> 42 with rules 6-7")});
  m.set("force_now_samples", static_cast<int64_t>(d.force_now_samples),
        {"latest wrench samples of the contact-now force (choice: 0.2 s at 50 Hz); <= force_average_samples; "
         "0: not used", "samples", closed(0, kIntMax), false,
         tuned("README rule 5: 10 samples = 0.2 s, block 1000 34 -> 38 of 50")});
  m.set("corner_angle_tolerance", s.corner_angle_tolerance,
        {"corner slab only when C_n turned by 90 deg within this (choice; README \"Right-angle corners\"); "
         ">= pi/2: every lambda change (001)", "rad", closed(0.0, M_PI), false,
         tuned("README rule 6: 10 deg (SITL box turns 83-84 deg), 37 -> 38 of 50")});
  m.set("release_states", d.release_states,
        {"entering one of these FSM states releases the held-back slabs (choice; README \"Corner release\", "
         "\"Release on every end of a traversal\")", "", {}, false,
         tuned("README rule 7: no change on the tuning block")});
  m.set("contact_now_after", d.contact_now_after,
        {"the contact-now check applies only in a state entered from one of these (empty: always) (choice; "
         "README \"Contact now\")", "", {}, false,
         tuned("README rule 5: applied always it cost the polygons' short faces")});
  m.set("impact_turn_reasons", d.impact_turn_reasons,
        {"a Tactile-turning entered for one of these reasons (FsmState.reason_code by name: contact_lost_turn, "
         "yaw_rate_peak) counts as an impact (choice; rule 10, README \"Re-contact after a contact-lost turn\"); "
         "empty: off", "", {}, false,
         tuned("README rule 10: blocks 1000 / 3000 +1, held out 9000-9049 46 -> 47 of 50")});
  m.set("impact_turn_rules", d.impact_turn_rules,
        {"first-contact rules after such a turn: any of contact_now, steady, gate (choice; rule 10)", "", {},
         false, tuned("README rule 10: blocks 1000 / 3000 +1, held out 9000-9049 46 -> 47 of 50")});
  m.set("recent_axis", s.recent_axis,
        {"stamp only if the force average's contact axis is also the latest samples' (choice; README "
         "\"Recent axis\")", "", {}, false, tuned("README rule 8: blocks 1000 / 2000 38 -> 44, 39 -> 42 of 50")});
  m.set("corner_fill_max_gap", s.corner_fill_max_gap,
        {"corner fill when the corner lies at most this beyond both mapped face ends (choice; README \"Corner "
         "fill\", not kept); 0: off", "m", at_least(0.0), false,
         tuned("README \"Rules off\": 0.4 m blocks 1000 / 2000 43 and 42, 44 and 42 without")});
  m.set("corner_fill_min_turn", s.corner_fill_min_turn,
        {"corner fill only if C_n turned by at least this (choice)", "rad", closed(0.0, 0.75 * M_PI), false,
         choice("corner fill, off")});
  m.set("corner_fill_fit_length", s.corner_fill_fit_length,
        {"face length fitted for each line of the corner fill (choice)", "m", positive(), false,
         choice("corner fill, off")});
  m.set("steady_distance", s.steady_distance,
        {"after an impact, slabs are held until they lay on one face over this path (choice; rule 9, README "
         "\"Steady first contact\"); 0: off", "m", at_least(0.0), false,
         tuned("README rule 9: blocks 1000 / 2000 44 -> 46, 42 -> 43; fresh 7000-7049 47 of 50")});
  m.set("steady_angle", s.steady_angle,
        {"... world C_n within this of the first held slab's (choice)", "rad",
         ParamRange{0.0, M_PI / 2, true, false}, false,
         tuned("README rule 9: 0.35 rad (0.1 rad took every cylinder's map)")});
  m.set("steady_offset", s.steady_offset,
        {"... near faces within this of its line (choice)", "m", positive(), false,
         tuned("README rule 9: 2 cm, blocks 1000 / 2000 44 -> 46, 42 -> 43")});
  m.set("touching_half_ratio", s.touching_half_ratio,
        {"only the slab half on the touching guard's side when the other facing arm deflects less than this "
         "fraction (choice; rule 11, README \"Touching-guard half\", not kept); 0: off", "", closed(0.0, 1.0),
         false, tuned("README rule 11, not kept: tuning +3 of 200, held out 46 -> 44 of 50")});
  m.set("touching_half_s", s.touching_half_s,
        {"... only within this long of the state's entry (choice)", "s", at_least(0.0), false, choice("rule 11, off")});
  m.set("face_clip_min_length", s.face_clip_min_length,
        {"face clip: a traversal's fitted line spanning at least this is a face; map points outside it are "
         "removed (choice; rule 12, README \"Face clip\"); 0: off", "m", at_least(0.0), false,
         tuned("README rule 12: tuning 129 -> 134 of 150, block 12400 263 -> 276 of 300")});
  m.set("face_clip_max_residual", s.face_clip_max_residual,
        {"face clip: slabs within this of the fitted line (choice)", "m", positive(), false,
         tuned("README rule 12: tuning 129 -> 134 of 150")});
  m.set("face_clip_tolerance", s.face_clip_tolerance,
        {"face clip: points more than this outside the face are removed (choice)", "m", at_least(0.0), false,
         tuned("README rule 12: tuning 129 -> 134 of 150")});
  m.set("face_clip_margin", s.face_clip_margin,
        {"face clip: the face's span extended by this (choice)", "m", at_least(0.0), false,
         tuned("README rule 12: tuning 129 -> 134 of 150")});
  m.set("face_clip_angle_tolerance", s.face_clip_angle_tolerance,
        {"face clip: slab C_n and the right angle to the next face within this (choice); >= pi/2: every line "
         "clips", "rad", closed(0.0, M_PI), false, tuned("README rule 12: tuning 129 -> 134 of 150")});
  m.set("face_clip_corner_reach", s.face_clip_corner_reach,
        {"face clip span extended to the corner within this (choice; rule 13, README \"Face clip to the "
         "corner\"); 0: off", "m", at_least(0.0), false,
         tuned("README rule 13, off: 0.6 m changed no seed of block 12700")});
  m.set("face_clip_tilted", s.face_clip_tilted,
        {"every fitted face line removes the tilted slabs outside it (choice; rule 15, README \"Tilted "
         "slabs\")", "", {}, false,
         tuned("README rule 15: block 12700 +4; held out 13000-13299 284 of 300 with rule 14")});
  m.set("face_clip_tilted_reach", s.face_clip_tilted_reach,
        {"... within its span extended by this (choice)", "m", at_least(0.0), false,
         tuned("README rule 15: 0.6 m, block 12700 +4")});
  m.set("corner_fan_clip", s.corner_fan_clip,
        {"remove the fan past a right-angled corner (choice; rule 16, README \"Fan past a right-angled "
         "corner\")", "", {}, false, tuned("README rule 16: blocks 13300 / 13000 283 -> 286, 286 -> 289")});
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
    : params_((params.validate(), params)), map_(params.map), mapper_(params.stamping, map_) {
  for (const auto& name : params_.impact_turn_reasons)
    for (const auto& [known, code] : turning_reasons())
      if (known == name) impact_turn_codes_.push_back(code);
}

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
    // lost brings the vehicle back to the object from off its face, like Exploration. Keyed
    // by the reason code: the reason text is for people and may be reworded.
    if (msg.state == kTurningState)
      turn_after_impact_reason_ =
          std::find(impact_turn_codes_.begin(), impact_turn_codes_.end(), msg.reason_code) != impact_turn_codes_.end();
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
