// The fail-safe every behaviour shares (issue 33, item 2): what happens when an
// input the behaviour flies on goes stale, when the flight's time runs out, and
// the landing that ends both. One class, so that the whisker wall follower, the
// GPIS sequencer, the XPLORER FSM and the wall-effect navigator cannot differ
// in how they treat a stale input.
//
//   NOMINAL ──(stale: an input older than max_input_age_s, while guarded)──▶ FAILSAFE_HOVER
//   FAILSAFE_HOVER ──(fresh: every input fresh again)──▶ NOMINAL (the behaviour resumes)
//   FAILSAFE_HOVER ──(hover_expired: failsafe_land_after_s in it)──▶ FAILSAFE_LAND (terminal)
//   NOMINAL ──(time_limit: time_limit_s since start, while guarded)──▶ TIME_LIMIT_LAND (terminal)
//
// In FAILSAFE_HOVER the behaviour holds its position (zero velocity, or its last
// position setpoint) and records nothing; in the two landing states it commands
// the landing. The behaviour says on each tick whether its state is *guarded*:
// a state that moves the vehicle on its inputs (not a hover at the start, not a
// landing already under way). Inputs are checked in the order given, so the
// first stale one names the fail-safe (e.g. depth before odometry).
//
// Core layer: no ROS, no messages. Times in seconds on one clock (the inputs'
// stamps and the tick's t).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "tactile_common/time.hpp"

namespace tactile_fsm {

/// An input a behaviour flies on. Its value is also the offset of its
/// REASON_FAILSAFE_*_STALE code in tactile_msgs/FsmState (1 + input).
enum class SafetyInput : uint8_t {
  kDepth = 0,         ///< whisker tactile depth (000)
  kOdometry = 1,      ///< the state estimate
  kForce = 2,         ///< XPLORER's arm wrench (001)
  kWallEstimate = 3,  ///< the wall-effect EKF's wall estimate (004)
};
const char* to_string(SafetyInput i);

enum class SafetyState : uint8_t {
  kNominal,        ///< the behaviour flies
  kFailsafeHover,  ///< an input stale: hold, record nothing
  kFailsafeLand,   ///< stale for failsafe_land_after_s: land (terminal)
  kTimeLimitLand,  ///< time_limit_s passed: land (terminal)
};
const char* to_string(SafetyState s);

/// The runner's reason codes, as tactile_msgs/FsmState REASON_FAILSAFE_* (1-9).
enum class SafetyReason : uint8_t {
  kNone = 0,
  kDepthStale = 1,         ///< REASON_FAILSAFE_DEPTH_STALE
  kOdometryStale = 2,      ///< REASON_FAILSAFE_ODOMETRY_STALE
  kForceStale = 3,         ///< REASON_FAILSAFE_FORCE_STALE
  kWallEstimateStale = 4,  ///< REASON_FAILSAFE_WALL_ESTIMATE_STALE
  kInputsFresh = 5,        ///< REASON_FAILSAFE_INPUTS_FRESH: back to the behaviour
  kStaleTooLong = 6,       ///< REASON_FAILSAFE_STALE_TOO_LONG: FAILSAFE_HOVER -> FAILSAFE_LAND
  kTimeLimit = 7,          ///< REASON_FAILSAFE_TIME_LIMIT: the flight's time limit, landing
};

struct SafetyParams {
  /// An input older than this is stale [s] (choice: 10 ticks at 50 Hz).
  double max_input_age_s = 0.2;
  /// FAILSAFE_HOVER this long -> FAILSAFE_LAND [s] (choice).
  double failsafe_land_after_s = 2.0;
  /// Guarded flight this long after the first tick -> TIME_LIMIT_LAND [s];
  /// infinity: the behaviour has no time limit.
  double time_limit_s = std::numeric_limits<double>::infinity();
  /// Throws std::invalid_argument naming `owner`.field, the value and the reason.
  void validate(const std::string& owner = "SafetyParams") const;
};

/// What the runner decided on one tick.
struct SafetyVerdict {
  SafetyState state = SafetyState::kNominal;
  bool entered = false;   ///< state changed on this tick (publish the FsmState now)
  bool resumed = false;   ///< FAILSAFE_HOVER -> NOMINAL on this tick: the behaviour resumes
  SafetyReason reason = SafetyReason::kNone;  ///< why the last change (kNone before any)
  const char* text = "";  ///< the same for a human
  /// The behaviour's own logic runs only when nominal.
  bool nominal() const { return state == SafetyState::kNominal; }
  /// The behaviour commands a landing.
  bool landing() const { return state == SafetyState::kFailsafeLand || state == SafetyState::kTimeLimitLand; }
};

/// Fresh at time t: stamped (finite) and at most max_age old (the one staleness
/// rule of the workspace, tactile_common/time.hpp; the INDI controller's uses it too).
using tactile_common::input_is_fresh;

class SafetyRunner {
 public:
  /// @param inputs the inputs the behaviour flies on, in the order they are
  ///               checked and passed to step() (at least one).
  SafetyRunner(const SafetyParams& params, std::vector<SafetyInput> inputs);

  /// One tick at time t. `stamps[i]` is the stamp of inputs[i] (NaN: never
  /// received). `guarded`: the behaviour's current state moves the vehicle on
  /// its inputs. Throws std::invalid_argument if the count of stamps is wrong.
  SafetyVerdict step(double t, std::initializer_list<double> stamps, bool guarded);
  SafetyVerdict step(double t, const std::vector<double>& stamps, bool guarded);

  void reset();
  SafetyState state() const { return state_; }
  double entered() const { return entered_; }
  /// The input that was stale on entering FAILSAFE_HOVER (the last time).
  SafetyInput stale_input() const { return stale_input_; }
  /// Entries of FAILSAFE_HOVER since reset.
  std::size_t failsafe_hovers() const { return failsafe_hovers_; }
  /// Time held in FAILSAFE_HOVER since reset [s] (the behaviour may pause its timers by it).
  double held_s() const { return held_s_; }
  const SafetyParams& params() const { return p_; }
  const std::vector<SafetyInput>& inputs() const { return inputs_; }

  // Named guards (public: tested one by one).
  /// The first input stale at t, or -1 when all are fresh.
  int first_stale(double t, const double* stamps) const;
  bool hover_expired(double t) const;
  bool time_limit_passed(double t) const;

 private:
  SafetyVerdict verdict(bool entered, bool resumed) const;
  void enter(SafetyState s, SafetyReason r, const char* text, double t);
  SafetyVerdict step_impl(double t, const double* stamps, std::size_t n, bool guarded);

  SafetyParams p_;
  std::vector<SafetyInput> inputs_;
  SafetyState state_ = SafetyState::kNominal;
  SafetyReason reason_ = SafetyReason::kNone;
  const char* text_ = "";
  SafetyInput stale_input_ = SafetyInput::kDepth;
  bool started_ = false;
  double start_ = 0.0;
  double entered_ = 0.0;
  double held_s_ = 0.0;
  std::size_t failsafe_hovers_ = 0;
};

}  // namespace tactile_fsm
