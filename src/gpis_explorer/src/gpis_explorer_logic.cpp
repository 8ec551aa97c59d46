// Node logic of gpis_explorer. See gpis_explorer_logic.hpp.
#include "gpis_explorer/gpis_explorer_logic.hpp"

#include <cmath>
#include <algorithm>
#include <climits>
#include <limits>
#include <stdexcept>

#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace gpis_explorer {

// The sequencer's reason codes are FsmState's REASON_GPIS_* (block 50-79).
using tactile_msgs::msg::FsmState;
static_assert(static_cast<uint8_t>(SequencerReason::kNone) == FsmState::REASON_NONE);
static_assert(static_cast<uint8_t>(SequencerReason::kHoverDone) == FsmState::REASON_GPIS_HOVER_DONE);
static_assert(static_cast<uint8_t>(SequencerReason::kAligned) == FsmState::REASON_GPIS_ALIGNED);
static_assert(static_cast<uint8_t>(SequencerReason::kProbeFoundNoWall) == FsmState::REASON_GPIS_PROBE_FOUND_NO_WALL);
static_assert(static_cast<uint8_t>(SequencerReason::kWhiskContact) == FsmState::REASON_GPIS_WHISK_CONTACT);
static_assert(static_cast<uint8_t>(SequencerReason::kContact) == FsmState::REASON_GPIS_CONTACT);
static_assert(static_cast<uint8_t>(SequencerReason::kBesideCorridor) == FsmState::REASON_GPIS_BESIDE_CORRIDOR);
static_assert(static_cast<uint8_t>(SequencerReason::kTooNearTheGuard) == FsmState::REASON_GPIS_TOO_NEAR_THE_GUARD);
static_assert(static_cast<uint8_t>(SequencerReason::kCornerAhead) == FsmState::REASON_GPIS_CORNER_AHEAD);
static_assert(static_cast<uint8_t>(SequencerReason::kWallFollowed) == FsmState::REASON_GPIS_WALL_FOLLOWED);
static_assert(static_cast<uint8_t>(SequencerReason::kSurfaceBeside) == FsmState::REASON_GPIS_SURFACE_BESIDE);
static_assert(static_cast<uint8_t>(SequencerReason::kRetreatedNextProbe) == FsmState::REASON_GPIS_RETREATED_NEXT_PROBE);
static_assert(static_cast<uint8_t>(SequencerReason::kNextProbe) == FsmState::REASON_GPIS_NEXT_PROBE);
static_assert(static_cast<uint8_t>(SequencerReason::kProbesDone) == FsmState::REASON_GPIS_PROBES_DONE);
static_assert(static_cast<uint8_t>(SequencerReason::kRetreatedRefit) == FsmState::REASON_GPIS_RETREATED_REFIT);
static_assert(static_cast<uint8_t>(SequencerReason::kOpenProbeReturn) == FsmState::REASON_GPIS_OPEN_PROBE_RETURN);
static_assert(static_cast<uint8_t>(SequencerReason::kOpenProbeExit) == FsmState::REASON_GPIS_OPEN_PROBE_EXIT);
static_assert(static_cast<uint8_t>(SequencerReason::kTargetViaStaging) == FsmState::REASON_GPIS_TARGET_VIA_STAGING);
static_assert(static_cast<uint8_t>(SequencerReason::kTargetChosen) == FsmState::REASON_GPIS_TARGET_CHOSEN);
static_assert(static_cast<uint8_t>(SequencerReason::kAtStaging) == FsmState::REASON_GPIS_AT_STAGING);
static_assert(static_cast<uint8_t>(SequencerReason::kTargetReached) == FsmState::REASON_GPIS_TARGET_REACHED);
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeDepthStale) == FsmState::REASON_FAILSAFE_DEPTH_STALE);
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeOdometryStale) == FsmState::REASON_FAILSAFE_ODOMETRY_STALE);
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeInputsFresh) == FsmState::REASON_FAILSAFE_INPUTS_FRESH);
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeStaleTooLong) == FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeDepthStale) ==
              static_cast<uint8_t>(tactile_fsm::SafetyReason::kDepthStale));
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeOdometryStale) ==
              static_cast<uint8_t>(tactile_fsm::SafetyReason::kOdometryStale));
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeInputsFresh) ==
              static_cast<uint8_t>(tactile_fsm::SafetyReason::kInputsFresh));
static_assert(static_cast<uint8_t>(SequencerReason::kFailsafeStaleTooLong) ==
              static_cast<uint8_t>(tactile_fsm::SafetyReason::kStaleTooLong));
static_assert(static_cast<uint8_t>(SequencerReason::kUpdateLimit) == FsmState::REASON_GPIS_UPDATE_LIMIT);
static_assert(static_cast<uint8_t>(SequencerReason::kNoTarget) == FsmState::REASON_GPIS_NO_TARGET);
static_assert(static_cast<uint8_t>(SequencerReason::kOpenSpace) == FsmState::REASON_GPIS_OPEN_SPACE);
static_assert(static_cast<uint8_t>(SequencerReason::kExitFlownThrough) == FsmState::REASON_GPIS_EXIT_FLOWN_THROUGH);
static_assert(static_cast<uint8_t>(SequencerReason::kTimeLimit) == FsmState::REASON_GPIS_TIME_LIMIT);
static_assert(static_cast<uint8_t>(SequencerReason::kLanded) == FsmState::REASON_GPIS_LANDED);

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
  using tactile_common::at_least;
  using tactile_common::closed;
  using tactile_common::ParamRange;
  using tactile_common::positive;
  const SequencerParams s;
  const double inf = std::numeric_limits<double>::infinity();
  ParamMap m(kNodeName, "defaults");
  // The node's parameter spec (README "Node"): value, description (from the Params comments
  // of gpis.hpp, local_gpis.hpp, explorer.hpp, sequencer.hpp and the wall follower's), unit
  // and the range params_from()/validate() accept for the key alone (relations between
  // keys -- min_leaf_size >= 2 overlap, t_max > t_min, turn_rate <= whisk_rate -- are
  // validate()'s and named in the text). Every key is read at start (ros2 param set:
  // read-only): the GPIS, its factor and the sequencing state are built from them.
  // GPIS (000 eq. 33-35; public onboard code values)
  m.set("gpis.beta", s.explorer.gpis.beta,
        {"beta, exponent of the IMQ kernel (000 eq. 33; 0.5 in the public onboard code)", "", positive(), false,
         tactile_common::choice("0.5 as in 000's public onboard code")});
  m.set("gpis.c", s.explorer.gpis.c,
        {"c, scale of the IMQ kernel (000 eq. 33; 1.0 in the public onboard code)", "m", positive(), false,
         tactile_common::choice("1.0 as in 000's public onboard code")});
  m.set("gpis.noise", s.explorer.gpis.noise,
        {"sigma^2, observation noise variance added to K (000 eq. 34-35; 1e-2 in the public onboard code)", "",
         positive(), false, tactile_common::choice("1e-2 as in 000's public onboard code")});
  m.set("gpis.max_points", static_cast<int64_t>(s.explorer.gpis.max_points),
        {"training budget (000 Supplementary \"Memory usage\": 50 onboard; the ground station uses thousands)", "",
         closed(1, 100000), false, tactile_common::paper("000 Supplementary \"Memory usage\": 50 onboard")});
  // Solver: exact (000) or local GPs over a quadtree (GPisMap; README "Local solver")
  m.set("gpis.solver", std::string(to_string(s.explorer.solver)),
        {"exact: one GP over every point (000 eq. 33-40); local: local GPs over a quadtree, blended "
         "(GPisMap, Lee et al. ICRA 2019; README \"Local solver\")", "", {}, false,
         tactile_common::paper("000 eq. 33-40 (exact); local: GPisMap, README \"Local solver\"")});
  m.set("gpis.leaf_points", static_cast<int64_t>(s.explorer.local.leaf_points),
        {"local solver: a leaf holding more training points splits into four (GPisMap's leaf capacity; our value)",
         "", closed(1, 100000), false, tactile_common::choice()});
  m.set("gpis.overlap", s.explorer.local.overlap,
        {"local solver: margin of a leaf's GP points and blending ramp (GPisMap's overlap; our value); "
         "<= min_leaf_size / 2", "m", positive(), false, tactile_common::choice()});
  m.set("gpis.min_leaf_size", s.explorer.local.min_leaf_size,
        {"local solver: leaves are not split below this side (our choice); >= 2 overlap so a weight's ramps "
         "never meet", "m", positive(), false, tactile_common::choice()});
  m.set("gpis.label_neighbours", static_cast<int64_t>(s.explorer.local.label_neighbours),
        {"local solver: points of each label nearest to a leaf's centre added to its GP (our choice)", "",
         closed(0, 100000), false, tactile_common::choice()});
  m.set("grid_size", s.explorer.grid_size,
        {"side of the prediction grid, centred on the start (our choice: twice the 2 m room)", "m", positive(), false,
         tactile_common::choice("twice the 2 m room")});
  m.set("grid_cells", static_cast<int64_t>(s.explorer.grid_cells),  // 000: 10 x 10 onboard
        {"prediction grid nodes per side (000 Supplementary \"Memory usage\": 10 x 10 onboard)", "",
         closed(2, 5000), false, tactile_common::paper("000 Supplementary \"Memory usage\": 10 x 10 onboard")});
  m.set("grid_variance", s.explorer.grid_variance,
        {"predict the variance on the whole grid (the uncertainty map of 000 Fig. 5); false: only at the "
         "contour points the target needs", "", {}, false, tactile_common::choice()});
  m.set("variance_cells", static_cast<int64_t>(s.explorer.variance_cells),
        {"nodes per side of the variance map: 0 every grid node; 2-5000 that many, interpolated (picture only; "
         "our choice); 1 is refused", "", closed(0, 5000), false, tactile_common::choice()});
  m.set("corner_curvature", s.explorer.corner_curvature,  // 000 eq. 41, q
        {"q, curvature threshold of a corner point, kappa < q < 0 (000 eq. 41; -1 our value: radius below 1 m)",
         "1/m", ParamRange{-inf, 0.0, true, true}, false,
         tactile_common::choice("000 eq. 41 gives the rule, not q: radius below 1 m")});
  m.set("penalty_scale", s.explorer.penalty_scale,  // 000 eq. 45, c
        {"c of the corner potential P (000 eq. 45)", "m", positive(), false,
         tactile_common::choice("000 eq. 45 gives the rule, not c")});
  m.set("corner_exclusion", s.explorer.corner_exclusion,
        {"candidate targets closer than this to a corner centroid are never chosen (our choice: = penalty_scale)",
         "m", at_least(0.0), false, tactile_common::choice("= penalty_scale")});
  // Wall following (000 Fig. S4e; tactile_fsm's values)
  m.set("v_max", s.wall.v_max, {"V_max, wall-following forward speed (000 Results: 20 cm/s)", "m/s", positive(), false,
        tactile_common::paper("000 Results: 20 cm/s")});
  m.set("omega_max", s.wall.omega_max,
        {"omega_max, wall-following turn rate (000 Fig. S4e; 25 deg/s our value)", "rad/s", positive(), false,
         tactile_common::choice("000 Fig. S4e names omega_max, not its value")});
  m.set("t_min", s.wall.t_min, {"T_min, near edge of the depth band (000 Fig. 4c: 60 mm)", "m", positive(), false,
        tactile_common::paper("000 Fig. 4c: 60 mm")});
  m.set("t_max", s.wall.t_max, {"T_max, far edge of the depth band (000 Fig. 4c: 100 mm); > t_min", "m", {}, false,
        tactile_common::paper("000 Fig. 4c: 100 mm")});
  m.set("whisker_spacing", s.wall.whisker_spacing,
        {"s, lateral distance of the whisker bases (000 eq. 21)", "m", positive(), false,
         tactile_common::paper("000 Methods: whiskers 5 cm apart; eq. 21")});
  m.set("hover_init_s", s.wall.hover_init_s,
        {"hover before exploring, for TDORC initialisation (000 Methods \"Hovering\")", "s", at_least(0.0), false,
         tactile_common::paper("000 Methods \"Hovering\": TDORC initialisation")});
  m.set("flight_height", s.wall.flight_height, {"height setpoint", "m", positive(), false, tactile_common::choice()});
  m.set("follow_side", std::string(tactile_fsm::to_string(s.wall.follow_side)),
        {"wall-following direction of the probes: right or left", "", {}, false, tactile_common::choice()});
  // Sequencing (000 Methods)
  m.set("probe_directions", static_cast<int64_t>(s.probe_directions),
        {"probe directions (000 Methods: \"four orthogonal directions (90 deg apart)\")", "", closed(1, 16), false,
         tactile_common::paper("000 Methods: four orthogonal directions (90 deg apart)")});
  m.set("follow_time_s", s.follow_time_s,
        {"wall follow after a probe's contact (000 Methods: \"follows the wall for 2 seconds\")", "s", positive(), false,
         tactile_common::paper("000 Methods: follows the wall for 2 seconds")});
  m.set("retreat_time_s", s.retreat_time_s,
        {"retreat after a wall follow (000 Methods: \"flies backward for 1 second\")", "s", positive(), false,
         tactile_common::paper("000 Methods: flies backward for 1 second")});
  m.set("surface_points_per_follow", static_cast<int64_t>(s.surface_points_per_follow),
        {"surface points stored per wall follow (000 Methods: \"four data points per wall-follow\")", "",
         closed(1, 1000), false, tactile_common::paper("000 Methods: four data points per wall-follow")});
  m.set("interior_points_per_retreat", static_cast<int64_t>(s.interior_points_per_retreat),
        {"interior points stored per retreat (000 Methods: \"and one per retreat\"): 0 or 1 (its end point)",
         "", closed(0, 1), false, tactile_common::paper("000 Methods: one per retreat")});
  m.set("retreat_speed", s.retreat_speed,
        {"backward speed of the retreat (our choice: V_max / 2 as the FSM's FLY_BACKWARD, 000 Fig. S4e)", "m/s",
         positive(), false, tactile_common::choice("V_max / 2 as the whisker FSM's FLY_BACKWARD")});
  m.set("probe_max_distance", s.probe_max_distance,
        {"a probe with no contact after this distance found an opening (our choice)", "m", positive(), false,
         tactile_common::choice()});
  m.set("yaw_gain", s.yaw_gain, {"yaw control: rate = gain * error, |rate| <= omega_max (our choice)", "1/s",
                                 positive(), false, tactile_common::choice()});
  m.set("yaw_tolerance", s.yaw_tolerance, {"aligned below this yaw error (our choice, ~3 deg)", "rad", positive(), false,
        tactile_common::choice()});
  m.set("target_radius", s.target_radius, {"target reached within this (our choice)", "m", positive(), false,
        tactile_common::choice()});
  m.set("exit_confirm_distance", s.exit_confirm_distance,
        {"beyond a contact-free target, this much more contact-free flight = exit flown through (our choice)", "m",
         positive(), false,
         tactile_common::tuned("README \"issue 17, rooms round 2\": tuning rooms 1000-1599, held out 19000-20299 555 of 600; 0.8 -> 1.2 m")});
  m.set("min_target_distance", s.min_target_distance,
        {"targets closer than this to the drone are skipped (our choice)", "m", at_least(0.0), false,
         tactile_common::choice()});
  m.set("side_clearance", s.side_clearance,
        {"a sideways wall follow ends early at a known surface point this near ahead of the frame sideways "
         "(our choice; 000 Results: corners \"risk collisions\")", "m", at_least(0.0), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("wall_extension", s.wall_extension,
        {"... or at a wall line touched before, extended this far beyond its touched span, across the sideways "
         "path (our choice); 0: off", "m", at_least(0.0), false,
         tactile_common::tuned("README \"issue 17, rooms round 2\": tuning rooms 1000-1599, held out 19000-20299 555 of 600")});
  m.set("approach_standoff", s.approach_standoff,
        {"approach a target head-on from a staging point this far inside along the GPIS normal (000 eq. 36; our "
         "choice); 0: straight to the target", "m", at_least(0.0), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("path_clearance", s.path_clearance,
        {"legs to a staging point keep this from every known surface point (our choice)", "m", at_least(0.0), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("approach_clearance", s.approach_clearance,
        {"the head-on leg keeps this from known surface points: a wall end beside it (our choice)", "m", at_least(0.0),
         false, tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("slow_distance", s.slow_distance,
        {"forward legs at slow_fraction * V_max while a known surface point is this near the whisker tips "
         "(our choice)", "m", at_least(0.0), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("slow_fraction", s.slow_fraction,
        {"fraction of V_max within slow_distance (our choice)", "", ParamRange{0.0, 1.0, true, false}, false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("align_probes", s.align_probes,
        {"probes after the first wall follow turned orthogonal to that wall (000's four orthogonal directions, "
         "aligned; our choice); false: the start heading", "", {}, false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("retreat_toward_follow_start", s.retreat_toward_follow_start,
        {"the retreat after a wall follow also moves sideways back toward where the follow started (our choice)", "",
         {}, false,
          tactile_common::tuned("README \"issue 17, rooms round 2\": tuning rooms 1000-1599, held out 19000-20299 555 of 600")});
  m.set("diagonal_probes", s.diagonal_probes,
        {"no wall within probe_max_distance in any probe direction: probe the diagonals before landing with "
         "open_space (our choice)", "", {}, false,
         tactile_common::tuned("README \"issue 17, rooms round 2\": tuning rooms 1000-1599, held out 19000-20299 555 of 600")});
  m.set("corner_confirm_radius", s.corner_confirm_radius,
        {"no target left: corner centroids (000 eq. 42-43) with no surface point this near are set aside and the "
         "choice made again (our choice); 0: off", "m", at_least(0.0), false,
         tactile_common::tuned("docs/gpis_explorer_results.md Round 3: held out 22000-22299 280 -> 283 of 300")});
  m.set("line_gain", s.line_gain,
        {"forward legs hold their line: body-y velocity = -gain * lateral offset, <= V_max / 2 (our choice)", "1/s",
         at_least(0.0), false, tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("return_via_probe_line", s.return_via_probe_line,
        {"RETURN after a probe's wall follow goes across to the probe's line first, then along it (our choice)", "",
         {}, false,
          tactile_common::tuned("README \"issue 17, rooms round 2\": tuning rooms 1000-1599, held out 19000-20299 555 of 600")});
  m.set("visited_radius", s.visited_radius,
        {"a target whose leg ended in a contact is visited: contour points this near it are not chosen again "
         "(our choice)", "m", at_least(0.0), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("whisk_amplitude", s.whisk_amplitude,
        {"whisking on legs into unexplored space: yaw +- this about the leg's heading (000 Fig. 1d; our choice); "
         "0: straight legs at V_max", "rad", ParamRange{0.0, M_PI / 2, false, true}, false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("whisk_rate", s.whisk_rate, {"whisking yaw rate (our choice; 000 gives none); >= turn_rate", "rad/s",
                                     positive(), false,
                                     tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("turn_rate", s.turn_rate,
        {"TURN in place at most this yaw rate, gain 4 * yaw_gain (our choice); <= whisk_rate; 0: omega_max at "
         "yaw_gain", "rad/s", at_least(0.0), false,
         tactile_common::tuned("docs/gpis_explorer_results.md Round 2: held out 19000-19299 248 -> 269 of 300 with replace_when_full")});
  m.set("whisk_speed", s.whisk_speed, {"speed along a whisking leg (our choice: V_max / 2)", "m/s", positive(), false,
        tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("corridor_half_width", s.corridor_half_width,
        {"a whisk contact stops the leg only within this of its axis (guard 8 cm + 3 cm; our choice)", "m", positive(),
         false, tactile_common::choice("guard 8 cm + 3 cm")});
  m.set("exit_beyond", s.exit_beyond,
        {"... with every known surface point at least this far behind the drone along the leg (our choice)", "m",
         at_least(0.0), false, tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("retreat_clearance", s.retreat_clearance,
        {"a retreat hovers instead when it would bring the centre this near a known surface point (guard 8 cm + "
         "6 cm; our choice)", "m", at_least(0.0), false, tactile_common::choice("guard 8 cm + 6 cm")});
  m.set("check_dwell_s", s.check_dwell_s,
        {"after a whisk stop: whisk back to the leg's heading and hover this long (our choice)", "s", positive(), false,
         tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("check_sample_s", s.check_sample_s,
        {"the points touched this long after the whisk contact decide wall follow or retreat (our choice)", "s",
         at_least(0.0), false, tactile_common::choice("README collision-avoidance rules: diagnosed SITL collisions")});
  m.set("follow_min_forward", s.follow_min_forward,
        {"nearest touched point in the corridor at least this far ahead: wall follow; nearer: retreat (whisker base "
         "5 cm + t_min 6 cm)", "m", at_least(0.0), false, tactile_common::choice("whisker base 5 cm + t_min 6 cm")});

  m.set("replace_when_full", s.replace_when_full,
        {"budget full: a new point replaces the older of the closest same-label pair, or is dropped when it is the "
         "redundant one (our choice; 000 gives the budget only)", "", {}, false,
         tactile_common::tuned("docs/gpis_explorer_results.md Round 2: held out 19000-19299 248 -> 269 of 300 with turn_rate")});
  m.set("max_updates", static_cast<int64_t>(s.max_updates),
        {"give up after this many GPIS updates (our choice)", "", closed(1, 1000000), false, tactile_common::choice()});
  m.set("max_time_s", s.max_time_s, {"give up after this long (our choice)", "s", positive(), false,
        tactile_common::choice()});
  m.set("landing_duration_s", s.landing_duration_s, {"LANDING -> DONE after this", "s", positive(), false,
        tactile_common::choice()});
  // Stale depth / odometry -> FAILSAFE_HOVER, landing after failsafe_land_after_s
  // (the wall follower's keys, defaults and rule).
  m.set("max_input_age_s", s.wall.max_input_age_s,
        {"depth / odometry older than this is stale: FAILSAFE_HOVER (10 ticks at 50 Hz; the whisker FSM's rule)", "s",
         positive(), false, tactile_common::choice("10 ticks at 50 Hz, the whisker FSM's rule")});
  m.set("failsafe_land_after_s", s.wall.failsafe_land_after_s,
        {"stale this long: LANDING, outcome inputs_stale", "s", at_least(0.0), false, tactile_common::choice()});
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
  in_.pose_valid = tactile_fsm::input_is_fresh(in_.t, odom_t_, age);
  in_.depth_valid = tactile_fsm::input_is_fresh(in_.t, depth_t_, age);
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
    st.reason_code = static_cast<uint8_t>(seq_.reason_code());
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
