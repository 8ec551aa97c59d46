// Node logic of tdorc_filter: WhiskerPressure in, WhiskerSignal out, one
// instance per whisker (namespaced whisker/left, whisker/right by the launch
// file or the standalone host). No rclcpp: both hosts use this class.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>

#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_common/sample_clock.hpp"
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
    /// A gap (trusted time between two accepted samples, see SampleClock) up
    /// to this is bridged: the sample index advances by the missing sample
    /// periods, so the drift line is extrapolated across the gap as it is
    /// across a contact (000 eq. 8), and the band-pass continues. A longer gap
    /// resets the filter (window refills). Our choice, not from the paper:
    /// 5 s = 250 samples at the deck's 50 Hz (a held contact may extrapolate 20 s).
    double max_sample_gap_s = 5.0;
    /// Which clock to trust per sample (stamp, sequence, receive time):
    /// tactile_common::SampleClock. nominal_period_s is the deck's 50 Hz.
    tactile_common::SampleClockParams clock;
    void validate() const;
  };

  /// Counters of received and dropped input.
  struct Stats {
    uint64_t received = 0;
    uint64_t published = 0;
    uint64_t dropped_nonfinite = 0;      ///< NaN/inf in any pressure channel
    uint64_t dropped_wrong_whisker = 0;  ///< whisker_id unknown or not the one this instance latched
    uint64_t dropped_out_of_order = 0;   ///< dropped_duplicate + dropped_late
    uint64_t dropped_duplicate = 0;      ///< same sequence again, stamp not advancing
    uint64_t dropped_late = 0;           ///< sequence behind the last accepted one (e.g. two swapped)
    uint64_t stamps_repaired_ahead = 0;  ///< stamp far ahead of sequence and receive time: replaced, sample kept
    uint64_t stamps_repaired_behind = 0; ///< stamp behind (or not advancing): replaced, sample kept
    uint64_t clock_steps = 0;            ///< a persistent stamp offset taken as the new time base
    uint64_t sequence_restarts = 0;      ///< sequence went back by more than max_late_samples (kept)
    uint64_t gaps_bridged = 0;           ///< gaps <= max_sample_gap_s: index advanced, drift extrapolated
    uint64_t samples_missing = 0;        ///< sample periods without a sample (sum over the gaps)
    uint64_t resets_on_gap = 0;          ///< filter resets after a gap > max_sample_gap_s
    uint64_t sequence_gaps = 0;          ///< accepted samples whose sequence is not previous + 1 (counted only)
  };

  /// Every parameter the node reads, with the paper's defaults.
  static tactile_common::ParamMap default_parameters();
  /// Reads and validates; throws tactile_common::ParamError naming the source,
  /// the parameter and the reason.
  static Params params_from(const tactile_common::ParamMap& map);

  explicit TdorcFilterLogic(const Params& params);

  /// New parameters while running (`ros2 param set`): only the live keys of
  /// default_parameters() may differ from the current ones (contact_threshold, applied
  /// from the next sample on; the drift window and filter state stay). Throws
  /// std::invalid_argument naming the field if they do not validate or another field
  /// differs; nothing changes then.
  void set_params(const Params& params);

  /// One raw sample received at receive_ns (the node's clock; nullopt: not
  /// known, the sequence alone checks the stamp). Returns the signal (with
  /// the stamp SampleClock trusts), or nothing if the sample was dropped
  /// (counted in stats()). The first message fixes the whisker id of this
  /// instance.
  std::optional<tactile_msgs::msg::WhiskerSignal> on_pressure(const tactile_msgs::msg::WhiskerPressure& msg,
                                                              std::optional<int64_t> receive_ns);
  std::optional<tactile_msgs::msg::WhiskerSignal> on_pressure(const tactile_msgs::msg::WhiskerPressure& msg) {
    return on_pressure(msg, std::nullopt);
  }

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: pressure in (sensor data; the receive time checks its stamp), signal out.
  template <class Ports>
  static void wire(Ports& p, TdorcFilterLogic& l) {
    using tactile_common::ports::Pub;
    using tactile_common::ports::Sub;
    auto signal = p.template publisher<tactile_msgs::msg::WhiskerSignal>(kOutputTopic, Pub::kData);
    p.template subscribe<tactile_msgs::msg::WhiskerPressure>(
        kInputTopic, Sub::kSensorData, [&l, signal](const tactile_msgs::msg::WhiskerPressure& msg, int64_t receive_ns) {
          if (auto out = l.on_pressure(msg, receive_ns)) signal(std::move(*out));
        });
  }

  const Stats& stats() const { return stats_; }
  const Params& params() const { return params_; }
  const TdorcWhisker& whisker() const { return whisker_; }

 private:
  Params params_;
  TdorcWhisker whisker_;
  Stats stats_;
  tactile_common::SampleClock clock_;
  int whisker_id_ = -1;
  bool have_last_ = false;
  uint32_t last_sequence_ = 0;
};

}  // namespace tdorc_filter
