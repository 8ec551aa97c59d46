// Sources of whisker samples, all producing tactile_msgs/WhiskerPressure.
// Node-logic layer: uses message types, no ROS.
//
// - SerialSource: bench-rig whisker deck over a serial port (text or CSV protocol).
// - SimSource: tactile_sim::WhiskerBarometerModel flying a scripted scenario.
// - BagSource: WhiskerPressure messages of one topic of a rosbag2 bag (tactile_bag).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tactile_msgs/msg/whisker_pressure.hpp"
#include "tactile_sim/whisker_barometer_model.hpp"
#include "whisker_driver/frame_parser.hpp"
#include "whisker_driver/serial_port.hpp"

namespace whisker_driver {

using WhiskerPressure = tactile_msgs::msg::WhiskerPressure;

/// Common interface: poll(now) appends every sample that became available.
class WhiskerSource {
 public:
  virtual ~WhiskerSource() = default;
  /// Appends the samples available at `now_ns` (clock of the caller) to out.
  virtual void poll(int64_t now_ns, std::vector<WhiskerPressure>& out) = 0;
  /// Like poll, and appends to receive_ns when each sample was received
  /// (same length as out). Default: now_ns for every sample; the bag source
  /// gives the bag's receive time of each message.
  virtual void poll_received(int64_t now_ns, std::vector<WhiskerPressure>& out, std::vector<int64_t>& receive_ns) {
    const size_t before = out.size();
    poll(now_ns, out);
    receive_ns.resize(receive_ns.size() + (out.size() - before), now_ns);
  }
  /// Parser counters (serial source); zeros for the others.
  virtual ParseStats parse_stats() const { return {}; }
  /// True when the source has nothing more to give (end of a bag).
  virtual bool finished() const { return false; }
  /// Device / decode errors so far.
  virtual uint64_t errors() const { return 0; }
};

/// Identity of the published samples.
struct SampleIdentity {
  uint8_t whisker_id = WhiskerPressure::WHISKER_LEFT;
  std::string frame_id = "whisker_left";
};

/// Reads the whisker deck from a serial port. Each poll reads what is buffered
/// (non-blocking), parses it and stamps the frames with the caller's clock:
/// the last frame of a poll gets now_ns, earlier ones of the same poll are
/// spaced by sample_period_ns before it (the deck streams at 50 Hz).
class SerialSource : public WhiskerSource {
 public:
  SerialSource(SerialPort port, Protocol protocol, SampleIdentity id,
               int64_t sample_period_ns = 20000000, int baud = 115200);
  /// Never throws on device errors: a disconnect (hang-up, I/O error) closes the
  /// port, counts an error and retries opening it at most once per second.
  void poll(int64_t now_ns, std::vector<WhiskerPressure>& out) override;
  ParseStats parse_stats() const override { return parser_->stats(); }
  const SerialPort& port() const { return port_; }
  uint64_t errors() const override { return errors_; }
  const std::string& last_error() const { return last_error_; }

  static constexpr int64_t kReopenIntervalNs = 1000000000;

 private:
  SerialPort port_;
  std::string device_;
  int baud_;
  uint64_t errors_ = 0;
  std::string last_error_;
  int64_t next_reopen_ns_ = 0;
  std::unique_ptr<FrameParser> parser_;
  SampleIdentity id_;
  int64_t period_ns_;
  std::vector<WhiskerFrame> frames_;
  std::vector<char> buf_;
};

/// A contact episode: half-sine base-moment pulse [start, start + duration).
struct ContactEpisode {
  double start_s = 0.0;
  double duration_s = 0.0;
  double peak_load_nm = 0.0;  ///< peak base bending moment [N m]
};

/// Scripted flight for the simulated source. Times relative to the first poll.
struct SimScenario {
  double takeoff_s = 2.0;    ///< motors start
  double hover_s = 90.0;     ///< motors stop at takeoff_s + hover_s
  std::vector<ContactEpisode> contacts;
  /// Base moment at scenario time t [N m] (sum of the half-sine pulses).
  double load(double t) const;
  bool motors_on(double t) const { return t >= takeoff_s && t < takeoff_s + hover_s; }
};

/// Simulated whisker at a fixed rate: sample k (k = 0, 1, ...) is stamped
/// t0 + k * period exactly, where t0 is now_ns of the first poll, and is
/// emitted by the first poll with now_ns >= its stamp.
class SimSource : public WhiskerSource {
 public:
  SimSource(const tactile_sim::WhiskerBarometerParams& model, uint64_t seed, SimScenario scenario,
            SampleIdentity id, double rate_hz = 50.0);
  void poll(int64_t now_ns, std::vector<WhiskerPressure>& out) override;
  /// Samples per poll are capped (a clock jump does not stall the caller);
  /// the rest follow on later polls.
  static constexpr int kMaxSamplesPerPoll = 1000;

 private:
  tactile_sim::WhiskerBarometerModel model_;
  SimScenario scenario_;
  SampleIdentity id_;
  int64_t period_ns_;
  bool started_ = false;
  int64_t t0_ns_ = 0;
  uint64_t k_ = 0;  // next sample index
};

}  // namespace whisker_driver
