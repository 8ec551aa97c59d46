// SafetyReason (safety_runner.hpp, core layer without messages) has the values of
// tactile_msgs/FsmState's REASON_FAILSAFE_* codes: checked here, where both are seen.
#include "tactile_fsm/safety_runner.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"

namespace tactile_fsm {
using tactile_msgs::msg::FsmState;
static_assert(static_cast<uint8_t>(SafetyReason::kNone) == FsmState::REASON_NONE);
static_assert(static_cast<uint8_t>(SafetyReason::kDepthStale) == FsmState::REASON_FAILSAFE_DEPTH_STALE);
static_assert(static_cast<uint8_t>(SafetyReason::kOdometryStale) == FsmState::REASON_FAILSAFE_ODOMETRY_STALE);
static_assert(static_cast<uint8_t>(SafetyReason::kForceStale) == FsmState::REASON_FAILSAFE_FORCE_STALE);
static_assert(static_cast<uint8_t>(SafetyReason::kWallEstimateStale) ==
              FsmState::REASON_FAILSAFE_WALL_ESTIMATE_STALE);
static_assert(static_cast<uint8_t>(SafetyReason::kInputsFresh) == FsmState::REASON_FAILSAFE_INPUTS_FRESH);
static_assert(static_cast<uint8_t>(SafetyReason::kStaleTooLong) == FsmState::REASON_FAILSAFE_STALE_TOO_LONG);
static_assert(static_cast<uint8_t>(SafetyReason::kTimeLimit) == FsmState::REASON_FAILSAFE_TIME_LIMIT);
}  // namespace tactile_fsm
