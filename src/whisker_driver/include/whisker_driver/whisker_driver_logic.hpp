// Node logic of the whisker driver: one instance per whisker (namespaced
// whisker/left or whisker/right), publishing tactile_msgs/WhiskerPressure on
// the relative topic "pressure" at rate_hz (50 Hz, paper 000: whisker deck at
// 50 Hz). No ROS; the rclcpp component and the standalone host call on_timer().
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tactile_common/parameters.hpp"
#include "tactile_common/ports.hpp"
#include "tactile_common/sample_clock.hpp"
#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "whisker_driver/frame_parser.hpp"
#include "whisker_driver/sources.hpp"

namespace whisker_driver {

struct WhiskerDriverParams {
  std::string source = "sim";          ///< "serial" | "sim" | "bag"
  std::string device = "/dev/ttyUSB0"; ///< serial device of the whisker deck
  int64_t baud = 115200;               ///< 000 hardware: UART link of the whisker deck
  std::string protocol = "text";       ///< "text" (whisker 1) | "csv" (whisker 2)
  int64_t whisker_id = 0;              ///< WhiskerPressure::WHISKER_LEFT (0) or WHISKER_RIGHT (1)
  std::string frame_id = "whisker_left";
  double rate_hz = 50.0;               ///< 000: whiskers sampled and processed at 50 Hz
  // Simulated source (tactile_sim::WhiskerBarometerModel, 000 eq. 1).
  int64_t sim_seed = 1;
  double sim_takeoff_s = 2.0;
  double sim_hover_s = 90.0;
  std::vector<double> sim_contact_start_s = {40.0};
  std::vector<double> sim_contact_duration_s = {2.0};
  std::vector<double> sim_contact_peak_nm = {2e-4};
  // Bag source.
  std::string bag_path;
  std::string bag_topic = "/whisker/left/pressure";

  /// Throws std::invalid_argument naming the field and the reason.
  void validate() const;
};

class WhiskerDriverLogic {
 public:
  using Params = WhiskerDriverParams;
  using WhiskerPressure = tactile_msgs::msg::WhiskerPressure;

  /// Relative output topic; the node runs in namespace whisker/left or whisker/right.
  static constexpr const char* kOutputTopic = "pressure";
  static constexpr const char* kNodeName = "whisker_driver";

  struct Outputs {
    std::vector<WhiskerPressure> pressure;  ///< in order, zero or more per tick
  };

  struct Stats {
    ParseStats parse;             ///< serial parser counters (zeros for sim/bag)
    uint64_t published = 0;       ///< messages returned by on_timer
    uint64_t source_errors = 0;   ///< serial disconnects / failed reopens, bag decode errors
    uint64_t sequence_gaps = 0;   ///< samples missing according to the sequence counter
    /// Time handling (tactile_common::SampleClock, README "Time"): which
    /// clock to trust per sample, from the sequence and the receive time
    /// (the bag's receive time for the bag source, the timer's clock else).
    uint64_t stamps_repaired_ahead = 0;   ///< stamp far ahead: replaced, sample published
    uint64_t stamps_repaired_behind = 0;  ///< stamp behind / not advancing: replaced, sample published
    uint64_t clock_steps = 0;             ///< persistent stamp offset taken as the new time base
    uint64_t dropped_duplicate = 0;       ///< same sequence and stamp again: not published
    uint64_t dropped_late = 0;            ///< sequence behind the last published one: not published
    uint64_t sequence_restarts = 0;       ///< sequence went back by more than a late sample would
    uint64_t gaps = 0;                    ///< published samples after a gap (missing sample periods)
    uint64_t samples_missing = 0;         ///< sample periods without a sample (sum over the gaps)
  };

  static tactile_common::ParamMap default_parameters();
  /// Reads and validates; errors name the source file and the parameter.
  static Params params_from(const tactile_common::ParamMap& map);

  /// Builds the source named by params.source (opens the serial port or the
  /// bag: throws SerialError / std::runtime_error naming the device or path).
  explicit WhiskerDriverLogic(const Params& params);
  /// With an explicit source (tests, standalone host).
  WhiskerDriverLogic(const Params& params, std::unique_ptr<WhiskerSource> source);

  Outputs on_timer(int64_t now_ns);
  /// now_ns of the last on_timer() that returned samples (nothing before the first): the
  /// age of the stream, which the bench rig's diagnostics report as a stall.
  std::optional<int64_t> last_output_ns() const { return last_output_ns_; }

  /// The node's ports (tactile_common/ports.hpp), for its rclcpp component and the
  /// `tactile` host: every period_ns() of wall time (the device streams in real time
  /// whatever the ROS clock does) the samples read are published on `pressure`.
  template <class Ports>
  static void wire(Ports& p, WhiskerDriverLogic& l) {
    auto pressure = p.template publisher<WhiskerPressure>(kOutputTopic, tactile_common::ports::Pub::kData);
    p.timer(
        l.period_ns(),
        [&l, pressure](int64_t now_ns) {
          for (auto& msg : l.on_timer(now_ns).pressure) pressure(std::move(msg));
        },
        tactile_common::ports::Clock::kSteady);
  }

  Stats stats() const;
  const Params& params() const { return params_; }
  /// Timer period from rate_hz [ns].
  int64_t period_ns() const;
  bool finished() const { return source_->finished(); }

 private:
  Params params_;
  std::unique_ptr<WhiskerSource> source_;
  Stats stats_;
  tactile_common::SampleClock clock_;
  bool have_last_seq_ = false;
  uint32_t last_seq_ = 0;
  std::optional<int64_t> last_output_ns_;
};

}  // namespace whisker_driver
