// Node logic of tdorc_filter: WhiskerPressure in, WhiskerSignal out, one
// instance per whisker (namespaced whisker/left, whisker/right by the launch
// file or the standalone host). No rclcpp: both hosts use this class.
#pragma once

#include <cstdint>
#include <optional>

#include "tactile_common/parameters.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "tactile_msgs/msg/whisker_signal.hpp"
#include "tdorc_filter/tdorc.hpp"

namespace tdorc_filter {

class TdorcFilterLogic {
 public:
  static constexpr const char* kNodeName = "tdorc_filter";
  /// Relative topics; the node is namespaced per whisker.
  static constexpr const char* kInputTopic = "pressure";  // tactile_msgs/msg/WhiskerPressure
  static constexpr const char* kOutputTopic = "signal";   // tactile_msgs/msg/WhiskerSignal

  struct Params {
    tdorc_filter::Params tdorc;
    /// A stamp gap larger than this resets the filter (window refills, the
    /// extrapolated drift would be stale). Our choice, not from the paper:
    /// 0.5 s = 25 samples at the deck's 50 Hz.
    double max_sample_gap_s = 0.5;
    void validate() const;
  };

  /// Counters of received and dropped input.
  struct Stats {
    uint64_t received = 0;
    uint64_t published = 0;
    uint64_t dropped_nonfinite = 0;      ///< NaN/inf in any pressure channel
    uint64_t dropped_wrong_whisker = 0;  ///< whisker_id unknown or not the one this instance latched
    uint64_t dropped_out_of_order = 0;   ///< stamp not after the previous accepted stamp
    uint64_t resets_on_gap = 0;          ///< filter resets after a stamp gap > max_sample_gap_s
    uint64_t sequence_gaps = 0;          ///< source sequence numbers skipped (counted only)
  };

  /// Every parameter the node reads, with the paper's defaults.
  static tactile_common::ParamMap default_parameters();
  /// Reads and validates; throws tactile_common::ParamError naming the source,
  /// the parameter and the reason.
  static Params params_from(const tactile_common::ParamMap& map);

  explicit TdorcFilterLogic(const Params& params);

  /// One raw sample. Returns the signal, or nothing if the sample was dropped
  /// (counted in stats()). The first message fixes the whisker id of this
  /// instance.
  std::optional<tactile_msgs::msg::WhiskerSignal> on_pressure(const tactile_msgs::msg::WhiskerPressure& msg);

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const TdorcWhisker& whisker() const { return whisker_; }

 private:
  Params params_;
  TdorcWhisker whisker_;
  Stats stats_;
  int whisker_id_ = -1;
  bool have_last_ = false;
  int64_t last_stamp_ns_ = 0;
  uint32_t last_sequence_ = 0;
};

}  // namespace tdorc_filter
