// Frames of the simulator (REP 105): every message's header names a frame of
// the tree the simulator broadcasts (static_frames() + the dynamic odom ->
// base_link and ground_truth/odom -> ground_truth/base_link), all behind the
// frame_prefix; the URDF's fixed joints are those static transforms; the
// geometry follows the vehicle parameters of the scenario.
#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>

#include "tactile_sim/logic/sim_logic.hpp"
#include "tactile_sim/scenario.hpp"

using tactile_sim::SimLogic;

namespace {

const std::string kScenarios = std::string(TACTILE_CONFIG_DIR) + "/scenarios/";

/// Every frame the simulator's transforms define, each with its parent ("" for map).
std::map<std::string, std::string> tree(const SimLogic& sim) {
  std::map<std::string, std::string> parent{{sim.frames().map, ""}};
  for (const auto& f : sim.static_frames()) parent[f.child] = f.parent;
  parent[sim.frames().base_link] = sim.frames().odom;  // dynamic (estimate)
  parent[sim.frames().ground_truth_base_link] = sim.frames().ground_truth_odom;  // dynamic (truth)
  return parent;
}

/// Header frames (and Odometry child frames) of every message in 2 s of flight.
std::set<std::string> stamped_frames(SimLogic& sim) {
  std::set<std::string> out;
  SimLogic::Outputs o;
  for (int64_t k = 0; k * sim.period_ns() < 2'000'000'000; ++k) {
    o.clear();
    sim.step(k * sim.period_ns(), o);
    auto add = [&out](const auto& v) {
      for (const auto& m : v) out.insert(m.msg.header.frame_id);
    };
    add(o.pressure), add(o.whisker_truth), add(o.imu), add(o.range), add(o.flow), add(o.arm_imu), add(o.thrust),
        add(o.wrench), add(o.wall), add(o.collisions), add(o.odometry);
    for (const auto& m : o.odometry) out.insert(m.msg.child_frame_id);
  }
  return out;
}

class SimFramesOfEveryVehicle : public ::testing::TestWithParam<const char*> {};

TEST_P(SimFramesOfEveryVehicle, EveryHeaderFrameIsAPrefixedFrameOfTheTree) {
  const auto scenario = tactile_sim::load_scenario(kScenarios + GetParam());
  SimLogic sim(scenario, 1, 0.0, "cf1/");
  const auto parents = tree(sim);
  const auto frames = stamped_frames(sim);
  ASSERT_FALSE(frames.empty());
  for (const auto& f : frames) {
    EXPECT_EQ(f.rfind("cf1/", 0), 0u) << GetParam() << ": frame '" << f << "' without the prefix";
    EXPECT_TRUE(parents.count(f)) << GetParam() << ": frame '" << f << "' is not in the transform tree";
  }
  // Every frame reaches map (the tree is connected).
  for (const auto& [frame, parent] : parents) {
    std::string f = frame;
    for (int depth = 0; depth < 10 && !parents.at(f).empty(); ++depth) {
      ASSERT_TRUE(parents.count(parents.at(f))) << frame << ": parent " << parents.at(f) << " undefined";
      f = parents.at(f);
    }
    EXPECT_EQ(f, "map") << frame;
  }
}

INSTANTIATE_TEST_SUITE_P(Vehicles, SimFramesOfEveryVehicle,
                         ::testing::Values("whisker_baffles_two_fsm.yaml", "xplorer_box.yaml", "ducted_wall.yaml",
                                           "whisker_stage_table1.yaml"));

TEST(SimFrames, GroundTruthHasItsOwnFramePair) {
  SimLogic sim(tactile_sim::load_scenario(kScenarios + "whisker_baffles_two_fsm.yaml"), 1);
  SimLogic::Outputs o;
  sim.step(0, o);
  ASSERT_EQ(o.odometry.size(), 2u);
  for (const auto& m : o.odometry) {
    if (m.topic == "odom") {
      EXPECT_EQ(m.msg.header.frame_id, "odom");
      EXPECT_EQ(m.msg.child_frame_id, "base_link");
    } else {
      EXPECT_EQ(m.topic, "ground_truth/odom");
      EXPECT_EQ(m.msg.header.frame_id, "ground_truth/odom");
      EXPECT_EQ(m.msg.child_frame_id, "ground_truth/base_link");
    }
  }
}

TEST(SimFrames, UrdfJointsAreTheStaticTransforms) {
  for (const char* file : {"whisker_baffles_two_fsm.yaml", "xplorer_box.yaml", "ducted_wall.yaml"}) {
    SimLogic sim(tactile_sim::load_scenario(kScenarios + file), 1, 0.0, "cf2/");
    const std::string urdf = sim.robot_description();
    size_t joints = 0;
    for (const auto& f : sim.static_frames()) {
      if (f.parent == "map") continue;  // map -> odom, map -> ground_truth/odom: not the robot's
      ++joints;
      char origin[160];
      std::snprintf(origin, sizeof origin, "<origin xyz=\"%.9g %.9g %.9g\" rpy=\"%.9g %.9g %.9g\"/>",
                    f.transform.xyz[0], f.transform.xyz[1], f.transform.xyz[2], f.transform.rpy[0],
                    f.transform.rpy[1], f.transform.rpy[2]);
      const std::string joint = "<parent link=\"" + f.parent + "\"/>\n    <child link=\"" + f.child + "\"/>\n    " +
                                origin;
      EXPECT_NE(urdf.find(joint), std::string::npos) << file << ": no joint " << joint << " in\n" << urdf;
    }
    const std::regex joint_re("<joint ");
    EXPECT_EQ(static_cast<size_t>(std::distance(std::sregex_iterator(urdf.begin(), urdf.end(), joint_re),
                                                std::sregex_iterator())),
              joints)
        << file;
  }
}

TEST(SimFrames, WhiskerFramesFollowTheVehicleParameters) {
  const auto scenario = tactile_sim::load_scenario_from_string(
      "name: w\nduration_s: 1\narena:\n  walls:\n    - points: [[1, -1], [1, 1]]\n"
      "vehicle:\n  type: whisker_crazyflie\n  params: {whisker_spacing: 0.08, whisker_base_x: 0.03, "
      "whisker_placement_deg: 30}\npilot:\n  - {hover: 1}\n",
      "w.yaml", ".");
  SimLogic sim(scenario, 1);
  bool left = false, right = false;
  for (const auto& f : sim.static_frames()) {
    if (f.child == "whisker_left" || f.child == "whisker_right") {
      EXPECT_EQ(f.parent, "base_link");
      EXPECT_DOUBLE_EQ(f.transform.xyz[0], 0.03);
      EXPECT_DOUBLE_EQ(f.transform.xyz[1], f.child == "whisker_left" ? 0.04 : -0.04);
      EXPECT_NEAR(f.transform.rpy[1], -30.0 * M_PI / 180.0, 1e-12);  // shaft pitched up by alpha
      (f.child == "whisker_left" ? left : right) = true;
    }
  }
  EXPECT_TRUE(left && right);
}

TEST(SimFrames, BadFramePrefixNamesTheParameter) {
  auto p = SimLogic::default_parameters();
  p.set("scenario", kScenarios + "whisker_hover.yaml");
  p.set("frame_prefix", std::string("/cf1"));
  try {
    SimLogic::from_parameters(p);
    FAIL() << "accepted frame_prefix /cf1";
  } catch (const tactile_common::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("tactile_sim.ros__parameters.frame_prefix: must not start with '/'"),
              std::string::npos)
        << e.what();
  }
  p.set("frame_prefix", std::string("cf1/"));
  EXPECT_EQ(SimLogic::from_parameters(p)->frames().base_link, "cf1/base_link");
}

}  // namespace
