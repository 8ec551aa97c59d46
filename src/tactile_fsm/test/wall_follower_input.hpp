// The follower's input the whisker wall-follower tests start from
// (test_whisker_wall_follower.cpp, test_whisker_states.cpp).
#pragma once

#include "tactile_fsm/whisker_wall_follower.hpp"

namespace tactile_fsm::test {

// Fresh input at time t, drone at (x, y, yaw), no contact, target (2, 0).
inline WallFollowerInput input(double t, double x = 0.0, double y = 0.0, double yaw = 0.0) {
  WallFollowerInput in;
  in.t = t;
  in.depth_stamp = t;
  in.odom_stamp = t;
  in.x = x;
  in.y = y;
  in.yaw = yaw;
  in.has_target = true;
  in.target_x = 2.0;
  in.target_y = 0.0;
  return in;
}

}  // namespace tactile_fsm::test
