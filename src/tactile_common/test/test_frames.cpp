#include "tactile_common/frames.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace tactile_common {
namespace {

RobotModel two_links() {
  RobotModel m;
  m.name = "test_robot";
  m.root.name = "base_link";
  RobotLink whisker;
  whisker.name = "whisker_left";
  whisker.parent = "base_link";
  whisker.origin.xyz = {0.05, 0.025, 0.0};
  whisker.origin.rpy = {0.0, -M_PI / 4, 0.0};
  whisker.shape = RobotLink::Shape::kCylinder;
  whisker.size = {0.0002, 0.2, 0.0};
  m.links.push_back(whisker);
  RobotLink imu;
  imu.name = "imu_link";
  imu.parent = "base_link";
  m.links.push_back(imu);
  return m;
}

TEST(FramePrefix, EmptyAndSlashTerminatedNamesAreAccepted) {
  EXPECT_NO_THROW(validate_frame_prefix(""));
  EXPECT_NO_THROW(validate_frame_prefix("cf1/"));
  EXPECT_NO_THROW(validate_frame_prefix("swarm/cf_2/"));
  EXPECT_EQ(prefixed("cf1/", "base_link"), "cf1/base_link");
  EXPECT_EQ(prefixed("", "base_link"), "base_link");
}

TEST(FramePrefix, BadPrefixesAreRejectedWithTheReason) {
  auto message = [](const char* prefix) {
    try {
      validate_frame_prefix(prefix, "tactile_sim.frame_prefix");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("/cf1/").find("must not start with '/'"), std::string::npos);
  EXPECT_NE(message("cf1").find("must end with '/'"), std::string::npos);
  EXPECT_NE(message("cf1//").find("'//'"), std::string::npos);
  EXPECT_NE(message("cf 1/").find("only letters"), std::string::npos);
  EXPECT_NE(message("cf1").find("tactile_sim.frame_prefix"), std::string::npos);
}

TEST(RigidTransform, QuaternionFollowsUrdfRpy) {
  RigidTransform t;
  t.rpy = {0.0, -M_PI / 4, 0.0};  // pitch about y
  auto q = t.quaternion();
  EXPECT_NEAR(q[0], 0.0, 1e-12);
  EXPECT_NEAR(q[1], std::sin(-M_PI / 8), 1e-12);
  EXPECT_NEAR(q[2], 0.0, 1e-12);
  EXPECT_NEAR(q[3], std::cos(M_PI / 8), 1e-12);
  // Roll then yaw (fixed axes): q = qz(yaw) * qx(roll).
  t.rpy = {M_PI / 2, 0.0, M_PI / 2};
  q = t.quaternion();
  EXPECT_NEAR(q[0], 0.5, 1e-12);
  EXPECT_NEAR(q[1], 0.5, 1e-12);
  EXPECT_NEAR(q[2], 0.5, 1e-12);
  EXPECT_NEAR(q[3], 0.5, 1e-12);
}

TEST(RobotModel, StaticFramesAndUrdfJointsComeFromTheSameLinks) {
  const auto m = two_links();
  const auto frames = static_frames(m, "cf1/");
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].parent, "cf1/base_link");
  EXPECT_EQ(frames[0].child, "cf1/whisker_left");
  EXPECT_DOUBLE_EQ(frames[0].transform.xyz[1], 0.025);
  const std::string urdf = to_urdf(m, "cf1/");
  EXPECT_NE(urdf.find("<robot name=\"test_robot\">"), std::string::npos);
  EXPECT_NE(urdf.find("<link name=\"cf1/base_link\"/>"), std::string::npos);
  EXPECT_NE(urdf.find("<parent link=\"cf1/base_link\"/>\n    <child link=\"cf1/whisker_left\"/>\n"
                      "    <origin xyz=\"0.05 0.025 0\" rpy=\"0 -0.785398163 0\"/>"),
            std::string::npos)
      << urdf;
  EXPECT_NE(urdf.find("<cylinder radius=\"0.0002\" length=\"0.2\"/>"), std::string::npos);
}

TEST(RobotModel, ValidateNamesTheLinkAndReason) {
  auto m = two_links();
  m.links[1].parent = "arm0";
  try {
    m.validate();
    FAIL() << "accepted an undefined parent";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("link 'imu_link': parent 'arm0' is not defined before it"),
              std::string::npos)
        << e.what();
  }
  m = two_links();
  m.links[1].name = "whisker_left";
  EXPECT_THROW(m.validate(), std::invalid_argument);
  m = two_links();
  m.links[0].origin.xyz[0] = NAN;
  EXPECT_THROW(m.validate(), std::invalid_argument);
  m = two_links();
  m.links[0].size[0] = -1.0;
  EXPECT_THROW(static_frames(m, ""), std::invalid_argument);
}

}  // namespace
}  // namespace tactile_common
