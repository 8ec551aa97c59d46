// SITL scenario tests of the XPLORER graph (paper 001): simulator ->
// xplorer_force_est -> xplorer_fsm -> /cmd_position, xplorer_mapping. Each
// scenario is one seeded run (< 1 s of wall time each) asserting the paper's
// metrics as measured in this SITL (src/tactile_fsm/docs/xplorer_fsm.md, "Results").
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include "mapping_pcl/xplorer_map_logic.hpp"
#include "sim_test_util.hpp"
#include "tactile_bag/bag.hpp"
#include "tactile_bag/typed.hpp"
#include "tactile_fsm/xplorer_explorer.hpp"
#include "tactile_fsm/xplorer_fsm_logic.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"

namespace fs = std::filesystem;

namespace {

nlohmann::json run(const std::string& scenario) { return tactile_cli::test::run_scenario(scenario); }
nlohmann::json run_trials(const std::string& scenario, int trials) {
  return tactile_cli::test::run_scenario(scenario, trials);
}

}  // namespace

// 001 Sec. V-B: push the wall with 1 N; the fused estimate within the paper's
// hardware accuracy (0.3 N) of the simulated contact force, the CoM collision
// peak kept by the fusion.
TEST(XplorerSitl, StaticWrenchEstimateMatchesTheContactForce) {
  const auto m = run("xplorer_static_wrench.yaml");
  ASSERT_TRUE(m["success"].get<bool>());
  const auto& x = m["xplorer"];
  EXPECT_EQ(x["final_state"], "static_wrench");
  EXPECT_LT(x["force_error_n"].get<double>(), 0.3);
  EXPECT_NEAR(x["force_estimate_n"].get<double>(), 1.0, 0.1);  // regulated to the 1 N reference
  EXPECT_NEAR(x["force_true_n"].get<double>(), 1.0, 0.15);
  EXPECT_TRUE(x["fusion_keeps_peak"].get<bool>());
  EXPECT_LT(x["force_settle_s"].get<double>(), 10.0);
}

// 001 Fig. 4 with the CoM estimate of real hardware: the thrust of eq. 5 is
// command x 32.5 N on a nonlinear rotor curve (exact at hover only) and the
// accelerometer carries vibration and a calibration bias. The CoM-only
// estimate then stays out of a 0.1 N band of the contact force far longer
// than the fused one, which converges to the arm-based estimate and keeps the
// collision peak. (With the ideal CoM model of xplorer_static_wrench.yaml the
// CoM estimate is nearly exact and settles first: 1.6 s vs 6.7 s, README.)
TEST(XplorerSitl, FusionSettlesBeforeTheImperfectComEstimate) {
  const auto m = run("xplorer_static_wrench_imperfect.yaml");
  ASSERT_TRUE(m["success"].get<bool>());
  const auto& x = m["xplorer"];
  EXPECT_LT(x["force_error_n"].get<double>(), 0.3);
  EXPECT_NEAR(x["force_true_n"].get<double>(), 1.0, 0.15);
  EXPECT_LT(x["force_settle_s"].get<double>(), 10.0);
  EXPECT_GT(x["force_settle_com_only_s"].get<double>(), x["force_settle_s"].get<double>() + 5.0);
  EXPECT_TRUE(x["fusion_faster_than_com"].get<bool>());
  EXPECT_TRUE(x["fusion_keeps_peak"].get<bool>());
  EXPECT_GT(x["collision_peak_fused_n"].get<double>(), 2.0);  // the impact shows (steady push: 1 N)
}

// The same with NaN and out-of-range arm angles, lost arm IMU sets and
// accelerometer spikes: handled (counted, attitude fallback, median), the
// estimate stays within 0.3 N.
TEST(XplorerSitl, StaticWrenchSurvivesFaultyArmImusAndSpikes) {
  const auto m = run("xplorer_static_wrench_faults.yaml");
  ASSERT_TRUE(m["success"].get<bool>());
  EXPECT_GT(m["faults_injected"]["nan"].get<int>(), 0);
  EXPECT_GT(m["faults_injected"]["spike"].get<int>(), 0);
  const auto& n = m["nodes"]["/xplorer_force_est"];
  EXPECT_GT(n["arm_from_orientation"].get<int>(), 0);
  EXPECT_GT(n["arm_out_of_range"].get<int>(), 0);
  EXPECT_LT(m["xplorer"]["force_error_n"].get<double>(), 0.3);
  EXPECT_NEAR(m["xplorer"]["force_true_n"].get<double>(), 1.0, 0.15);
}

// 001 Sec. V-C2 / V-D: start outside the 1.22 m x 1.0 m box, traverse it with
// all three states, close the loop, map it (001: 1.231 x 1.019 m, 96.72 %;
// issue goal >= 98 %), on every one of five seeded trials. Each convex corner
// is one Tactile-turning that re-contacts the next face (turn_pivot: the
// vehicle orbits the corner instead of being spun round it by the released
// push; with the previous rule seeds 2 and 3 failed, docs/tuning/tactile_fsm.md "Convex corners").
TEST(XplorerSitl, BoxTraversalClosesTheLoopAndMapsTheBoxOnEverySeed) {
  const auto m = run_trials("xplorer_box_traversal.yaml", 5);
  EXPECT_EQ(m["success_count"].get<int>(), 5);
  for (const auto& t : m["per_trial"]) {
    const auto& x = t["xplorer"];
    const auto seed = t["seed"].get<int>();
    EXPECT_TRUE(x["loop_closed"].get<bool>()) << seed;
    EXPECT_EQ(x["turns"].get<int>(), 4) << seed;               // one per convex corner
    EXPECT_EQ(x["turns_recontacted"].get<int>(), 4) << seed;   // unlike the rigid chassis (below)
    EXPECT_EQ(x["traversal_contact_lost"].get<int>(), 0) << seed;
    // Slab near faces at the deflected arms' outline (mapping edge_from_arms).
    EXPECT_NEAR(x["map_length_m"].get<double>(), 1.22, 0.02) << seed;
    EXPECT_NEAR(x["map_width_m"].get<double>(), 1.0, 0.02) << seed;
    EXPECT_GE(x["map_area_accuracy"].get<double>(), 0.98) << seed;  // the goal (001: 96.72 %)
  }
}

// Not a paper experiment: the same box turned by a random angle in [-30, 30]
// deg per trial (the corner handling was tuned on the axis-aligned box). Every
// trial still turns the four corners and closes the loop; the oblique first
// contact leaves the map 1-2.5 cm long on one side (97.7-99.0 % on seeds 1-5;
// 88.9 % on seed 8, README), so the area is asserted at 97 %.
TEST(XplorerSitl, TurnedBoxTraversalClosesTheLoop) {
  const auto m = run_trials("xplorer_box_traversal_turned.yaml", 5);
  EXPECT_EQ(m["success_count"].get<int>(), 5);
  for (const auto& t : m["per_trial"]) {
    const auto& x = t["xplorer"];
    const auto seed = t["seed"].get<int>();
    EXPECT_TRUE(x["loop_closed"].get<bool>()) << seed;
    // Four corners turned, each re-contacting the next face, the last one possibly
    // ended by the loop's closure inside it (loop_turn_min_winding); none failed.
    EXPECT_EQ(x["turns_recontacted"].get<int>() + x["turns_closing_the_loop"].get<int>(), 4) << seed;
    EXPECT_LE(x["turns_closing_the_loop"].get<int>(), 1) << seed;
    EXPECT_EQ(x["turns_without_recontact"].get<int>(), 0) << seed;
    EXPECT_EQ(x["traversal_contact_lost"].get<int>(), 0) << seed;
    EXPECT_GE(x["map_area_accuracy"].get<double>(), 0.97) << seed;
  }
}

// 001 Sec. V-C4, Fig. 5(iii): the same box with a rigid chassis
// (vehicle.params.rigid_arms) fails in all four trials, the way the paper
// reports: it traverses the first face, but at the convex corner it cannot
// hold the face (without the arms' give the contact torque yaws it slowly
// round the edge, below the turning trigger), loses contact, and ends flying
// off the box in Exploration; the loop never closes. The compliant vehicle
// (test above) turns every corner and never loses the face. (001 saw the
// rigid vehicle enter Tactile-turning and fail to re-contact; here it fails
// one step earlier, at the same corner: README.)
TEST(XplorerSitl, RigidArmsFailBoxTraversalAtTheConvexCorner) {
  const auto m = run_trials("xplorer_box_traversal_rigid.yaml", 4);
  EXPECT_EQ(m["success_count"].get<int>(), 0);
  for (const auto& t : m["per_trial"]) {
    const auto& x = t["xplorer"];
    const auto seed = t["seed"].get<int>();
    EXPECT_FALSE(x["loop_closed"].get<bool>()) << seed;
    ASSERT_FALSE(x["first_contact_time_s"].is_null()) << seed;  // it found and traversed the first face
    EXPECT_GT(x["traversed_path_m"].get<double>(), 0.5) << seed;
    EXPECT_GE(x["turns_without_recontact"].get<int>() + x["traversal_contact_lost"].get<int>(), 1) << seed;
    EXPECT_LT(x["turns_recontacted"].get<int>(), 3) << seed;    // never round three corners
    EXPECT_EQ(x["final_state"], "exploration") << seed;         // flew off the box
  }
}

// 001 Sec. V-C3, Fig. 6: the pipe (0.4 m) and the trash can (0.5 m) are
// traversed round to loop closure in Tactile-traversal (yaw in admittance
// follows the surface, no Tactile-turning), and the map's footprint matches
// the cylinder (hull vs pi r^2, bounding dimensions vs the diameter).
TEST(XplorerSitl, PipeAndBinTraversalCloseTheLoop) {
  for (const auto& [file, radius] : {std::pair<std::string, double>{"xplorer_pipe_traversal.yaml", 0.2},
                                     std::pair<std::string, double>{"xplorer_bin_traversal.yaml", 0.25}}) {
    const auto m = run(file);
    EXPECT_TRUE(m["success"].get<bool>()) << file;
    const auto& x = m["xplorer"];
    EXPECT_TRUE(x["loop_closed"].get<bool>()) << file;
    EXPECT_EQ(x["final_state"], "done") << file;
    EXPECT_EQ(x["traversal_contact_lost"].get<int>(), 0) << file;
    EXPECT_GE(x["traversed_path_m"].get<double>(), 2.0) << file;
    EXPECT_NEAR(x["map_length_m"].get<double>(), 2 * radius, 0.03) << file;
    EXPECT_NEAR(x["map_width_m"].get<double>(), 2 * radius, 0.03) << file;
    EXPECT_NEAR(x["map_hull_area_m2"].get<double>(), M_PI * radius * radius, 0.05 * M_PI * radius * radius) << file;
  }
}

// 001 Sec. V-C1: wall traversal (Exploration and Tactile-traversal).
TEST(XplorerSitl, WallTraversalFollowsTheWall) {
  const auto m = run("xplorer_wall_traversal.yaml");
  EXPECT_TRUE(m["success"].get<bool>());
  EXPECT_GE(m["xplorer"]["traversed_path_m"].get<double>(), 2.0);
}

// 001 Sec. V-E: ricocheting reaches a goal at the wall faster than the
// conventional waypoint flight (001: tau_r 1.046 s vs 2.27 s).
TEST(XplorerSitl, RicochetRisesFasterThanWaypointFlight) {
  const auto r = run("xplorer_ricochet_wall.yaml");
  const auto w = run("xplorer_waypoint_wall.yaml");
  ASSERT_TRUE(r["success"].get<bool>());
  ASSERT_TRUE(w["success"].get<bool>());
  EXPECT_GE(r["xplorer"]["collisions_detected"].get<int>(), 1);
  EXPECT_EQ(w["xplorer"]["collisions_detected"].get<int>(), 0);
  ASSERT_FALSE(r["xplorer"]["rise_time_s"].is_null());
  ASSERT_FALSE(r["xplorer"]["settling_time_s"].is_null());
  ASSERT_FALSE(w["xplorer"]["settling_time_s"].is_null());
  EXPECT_LT(r["xplorer"]["rise_time_s"].get<double>(), w["xplorer"]["rise_time_s"].get<double>());
  EXPECT_LT(r["xplorer"]["settling_time_s"].get<double>(), w["xplorer"]["settling_time_s"].get<double>());
}

// The reason codes in a bag written by `tactile sim` (the box of 001 Sec. V-C, seed 1): read
// back, every FsmState of the exploration FSM carries reason_code, C_n and lambda; each
// transition's code is one that leads from its previous state to its state; the corner turns
// are the metrics' turns; the loop closes with its code. mapping_pcl's names of the turning
// reasons (impact_turn_reasons) are tactile_fsm's names of those codes.
TEST(XplorerSitl, BagCarriesTheReasonCodesOfTheTransitions) {
  using tactile_msgs::msg::FsmState;
  const fs::path out = fs::temp_directory_path() / ("tactile_cli_test_xplorer_reasons_" + std::to_string(::getpid()));
  fs::remove_all(out);
  tactile_cli::SimOptions o;
  o.scenario = (tactile_cli::test::config_dir() / "scenarios" / "xplorer_box_traversal.yaml").string();
  o.out_dir = out.string();
  o.config_dir = tactile_cli::test::config_dir().string();
  o.seed = 1;
  o.progress = false;
  o.write_png = false;
  const auto m = tactile_cli::run_sim(o);
  ASSERT_TRUE(m["success"].get<bool>());
  // (previous state, state) -> the codes of that transition (FsmState.msg).
  const std::map<std::pair<std::string, std::string>, std::set<uint8_t>> allowed = {
      {{"takeoff", "exploration"}, {FsmState::REASON_XPLORER_HOVER_HEIGHT_REACHED}},
      {{"exploration", "tactile_traversal"}, {FsmState::REASON_XPLORER_CONTACT, FsmState::REASON_XPLORER_CONTACT_SQUARE_UP}},
      {{"tactile_traversal", "tactile_turning"},
       {FsmState::REASON_XPLORER_YAW_RATE_PEAK, FsmState::REASON_XPLORER_CONTACT_LOST_TURN}},
      {{"tactile_traversal", "exploration"},
       {FsmState::REASON_XPLORER_CONTACT_LOST, FsmState::REASON_XPLORER_CONTACT_LOST_SQUARING}},
      {{"tactile_turning", "tactile_traversal"}, {FsmState::REASON_XPLORER_RE_CONTACT}},
      {{"tactile_turning", "exploration"}, {FsmState::REASON_XPLORER_TURN_LIMIT}},
      {{"tactile_traversal", "done"}, {FsmState::REASON_XPLORER_LOOP_CLOSED}},
      {{"tactile_turning", "done"}, {FsmState::REASON_XPLORER_LOOP_CLOSED}},
  };
  tactile_bag::Reader bag((out / "bag").string());
  const std::string topic = std::string("/") + tactile_fsm::XplorerFsmLogic::kStateTopic;
  bag.set_topic_filter({topic});
  tactile_bag::SerializedMessage msg;
  std::string state;
  int messages = 0, turns = 0, traversal_messages = 0;
  FsmState last;
  while (bag.read_next(msg)) {
    const auto s = tactile_bag::decode<FsmState>(msg);
    ++messages;
    EXPECT_EQ(s.behaviour, tactile_fsm::XplorerFsmLogic::kBehaviour);
    if (messages == 1) {
      EXPECT_EQ(s.state, "takeoff");
      EXPECT_EQ(s.reason_code, FsmState::REASON_NONE);
    }
    if (s.state != state && messages > 1) {  // a transition
      const auto it = allowed.find({s.previous_state, s.state});
      ASSERT_NE(it, allowed.end()) << s.previous_state << " -> " << s.state;
      EXPECT_EQ(it->second.count(s.reason_code), 1u)
          << s.previous_state << " -> " << s.state << ": code " << int{s.reason_code} << " (" << s.reason << ")";
      if (s.reason_code == FsmState::REASON_XPLORER_YAW_RATE_PEAK ||
          s.reason_code == FsmState::REASON_XPLORER_CONTACT_LOST_TURN)
        ++turns;
    }
    if (s.state == "tactile_traversal" || s.state == "tactile_turning") {  // C_n and lambda of the right-hand traversal
      ++traversal_messages;
      EXPECT_NE(s.contact_direction, FsmState::DIRECTION_NONE) << s.state;
      EXPECT_EQ(s.move_direction, static_cast<uint8_t>(tactile_common::right_hand(
                                      static_cast<tactile_common::BodyDirection>(s.contact_direction))));
    }
    state = s.state;
    last = s;
  }
  EXPECT_GT(traversal_messages, 100);
  EXPECT_EQ(turns, m["xplorer"]["turns"].get<int>());
  EXPECT_EQ(turns, 4);  // one per corner of the box
  EXPECT_EQ(last.state, "done");
  EXPECT_EQ(last.reason_code, FsmState::REASON_XPLORER_LOOP_CLOSED);
  for (const auto& [name, code] : mapping_pcl::XplorerMapLogic::turning_reasons())
    EXPECT_EQ(name, tactile_fsm::to_string(static_cast<tactile_fsm::XplorerReason>(code)));
  fs::remove_all(out);
}

// Issue 33, the shared fail-safe: the odometry stops for good 8 s into the box
// traversal (in contact, pushing the face). xplorer_fsm held its last setpoint
// forever; now FAILSAFE_HOVER (the last setpoint) 0.2 s later, FAILSAFE_LAND
// failsafe_land_after_s (2 s) after that, the height setpoint descending at
// 0.25 m/s with no odometry read, and the vehicle ends on the floor with its
// thrust below hover.
TEST(XplorerSitl, StaleOdometryLands) {
  const auto m = tactile_cli::test::run_edited_scenario(
      "xplorer_box_traversal.yaml", {{"duration_s: 150.0", "duration_s: 20.0"}},
      "faults:\n  - {type: dropout, topic: /odom, start_s: 8.0, duration_s: 100.0}\n");
  const auto& x = m["xplorer"];
  EXPECT_EQ(x["failsafe_state"], "FAILSAFE_LAND");
  std::map<std::string, double> entered;
  for (const auto& s : x["state_log"]) entered.emplace(s["state"].get<std::string>(), s["t"].get<double>());
  ASSERT_TRUE(entered.count("FAILSAFE_HOVER"));
  ASSERT_TRUE(entered.count("FAILSAFE_LAND"));
  EXPECT_NEAR(entered["FAILSAFE_HOVER"], 8.2, 0.05);  // max_input_age_s after the last odometry
  EXPECT_NEAR(entered["FAILSAFE_LAND"] - entered["FAILSAFE_HOVER"], 2.0, 0.03);
  EXPECT_EQ(m["nodes"]["/xplorer_fsm"]["failsafe_hovers"].get<int>(), 1);
  EXPECT_EQ(m["nodes"]["/xplorer_fsm"]["failsafe_landings"].get<int>(), 1);
  const auto& g = m["ground_truth"];
  std::printf("stale odometry: FAILSAFE_HOVER %.2f s, FAILSAFE_LAND %.2f s, final z %.4f m, thrust %.2f N\n",
              entered["FAILSAFE_HOVER"], entered["FAILSAFE_LAND"], g["final_z_m"].get<double>(),
              x["final_thrust_n"].get<double>());
  EXPECT_LT(g["final_z_m"].get<double>(), 0.01);  // on the floor (z = 0), not hovering at 0.7 m
  const double hover_thrust = 1.12 * 9.81;        // XplorerParams mass (001 Sec. V-A1)
  EXPECT_LT(x["final_thrust_n"].get<double>(), 0.8 * hover_thrust);
}
