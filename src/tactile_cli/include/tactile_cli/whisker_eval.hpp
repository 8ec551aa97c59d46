// Evaluations of the whiskered-drone graph in `tactile sim` (paper 000):
// tactile depth against the simulator's ground truth (Table 1 / Table S1
// metrics for the MLP, MLP + KF simplified and MLP + KF full models), and
// wall following against the truth (depth in band, heading error).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactile_cli/host.hpp"
#include "tactile_msgs/msg/fsm_state.hpp"
#include "tactile_msgs/msg/tactile_depth.hpp"
#include "tactile_msgs/msg/whisker_ground_truth.hpp"
#include "tactile_sim/arena.hpp"

namespace tactile_cli {

/// Ground truth of both whiskers by stamp, from /ground_truth/whisker/*/contact
/// (or filled with add(): `tactile fly` takes it from the simulated Crazyflie).
class WhiskerTruth {
 public:
  WhiskerTruth() = default;
  explicit WhiskerTruth(Host& host);
  struct Sample {
    bool contact = false;
    double depth = 0.0;
  };
  /// Truth of whisker `side` (0 left, 1 right) at `stamp_ns`, if recorded.
  const Sample* at(int side, int64_t stamp_ns) const;
  void add(int side, int64_t stamp_ns, const Sample& s) { samples_[side][stamp_ns] = s; }
  /// Every sample of whisker `side`, by stamp.
  const std::map<int64_t, Sample>& samples(int side) const { return samples_[side]; }

 private:
  std::map<int64_t, Sample> samples_[2];
};

/// Runs tactile_depth three times side by side (estimator mlp, kf_simplified,
/// kf_full, publishing on /evaluation/depth/<model>) and compares each with
/// the truth: MAE / RMSE per whisker [mm] over samples where the whisker
/// truly touches and the estimator reports contact, orientation MAE [deg]
/// (theta = atan((d_l - d_r) / s), 000 eq. 22) where both touch, and
/// reconstruction MAE [mm] (distance of the estimated contact point in the
/// odometry frame to the nearest arena wall).
class DepthEvaluation {
 public:
  /// `overrides`: the scenario's tactile_depth parameters (the estimator is set per instance).
  DepthEvaluation(Host& host, const WhiskerTruth& truth, const tactile_sim::Arena& arena,
                  const tactile_common::ParamMap& overrides);
  /// {"mlp": {...}, "mlp_kf_simplified": {...}, "mlp_kf_full": {...}}
  nlohmann::json metrics() const;

 private:
  const WhiskerTruth& truth_;
  const tactile_sim::Arena& arena_;
  double spacing_ = 0.05;
  std::map<std::string, std::vector<tactile_msgs::msg::TactileDepth>> estimates_;
};

/// The whisker FSM's state transitions on /fsm_state (stamp, state), and its
/// wall-following episodes (states WALL_FOLLOWING/...). Used by the SITL
/// evaluation and by `tactile fly` (no truth there).
class FsmStateLog {
 public:
  explicit FsmStateLog(Host& host);
  struct Episode {
    int64_t start_ns = -1;  ///< first WALL_FOLLOWING stamp; -1: never followed a wall
    int64_t end_ns = -1;    ///< first stamp after it in another state; -1: still following
  };
  /// The first wall-following episode (000 Fig. 6: a sweep along the wall).
  Episode first_wall_following() const;
  /// Number of wall-following episodes.
  size_t wall_following_episodes() const;
  /// {first_sweep_start_s, first_sweep_s, wall_following_episodes}; an episode
  /// still running lasts until `end_ns`.
  nlohmann::json sweep_metrics(int64_t end_ns) const;
  const std::vector<std::pair<int64_t, std::string>>& transitions() const { return states_; }
  const std::string& last_state() const { return state_; }

 private:
  std::string state_;
  std::vector<std::pair<int64_t, std::string>> states_;
};

/// Wall-following quality of the whisker FSM against the truth, over the
/// 50 Hz samples while the FSM is in WALL_FOLLOWING: depth_in_band_fraction
/// (every touching whisker's true depth in [T_min, T_max]) and
/// mean_abs_heading_error_deg (|atan((d_l - d_r) / s)| of the true depths
/// where both whiskers touch: 0 when the drone faces the wall squarely).
/// The first wall-following episode is also reported on its own, as the
/// paper's darkness sweeps (000 Fig. 6: 7 s along the wall): its start
/// (first_sweep_start_s, simulation time), its length (first_sweep_s) and the
/// in-band fraction over its first sweep_window_s (first_sweep_in_band_fraction).
class WallFollowingEvaluation {
 public:
  WallFollowingEvaluation(Host& host, const WhiskerTruth& truth, double t_min, double t_max, double spacing);
  /// Window of first_sweep_in_band_fraction [s] (000 Fig. 6: 7 s sweeps).
  static constexpr double kSweepWindowS = 7.0;
  /// `end_ns`: end of a wall-following episode still running (< 0: the last
  /// evaluated sample). Without truth samples the truth-based fields are null.
  nlohmann::json metrics(int64_t end_ns = -1) const;
  const std::string& last_state() const { return log_.last_state(); }

 private:
  const WhiskerTruth& truth_;
  double t_min_, t_max_, spacing_;
  FsmStateLog log_;
};

}  // namespace tactile_cli
