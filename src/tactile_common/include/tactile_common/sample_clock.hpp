// Which clock to trust for a stream of numbered samples (whisker pressures):
// the header stamp, the source's sequence number, or the time the sample was
// received (the bag's receive time in a replay, the node's clock live).
// ROS-free core, no message types: the whisker driver and the TDORC node logic
// both classify every sample with it and count every decision.
//
// Rules, per sample, against the last accepted sample (seq s0, stamp t0, receive r0):
//   d  = seq - s0 (signed, modulo 2^32), dt = stamp - t0, dr = receive - r0,
//   T  = sample period, estimated from in-order consecutive samples (starts at
//        nominal_period_s), tol = tolerance_s.
//   1. d == 0 and the stamp does not advance: duplicate -> dropped.
//   2. d < 0, |d| <= max_late_samples and the stamp is not ahead (dt <= tol):
//      late (arrived after a later sample, e.g. two swapped) -> dropped.
//      Any other d < 0 (or d == 0 with a new stamp): the source restarted its
//      counter; the sequence says nothing about this sample (restart, counted).
//   3. The stamp is trusted when it advances (dt > 0) and agrees within tol
//      with the sequence (|dt - d*T|) or with the receive time (|dt - dr|):
//      in order. A real stall (source paused or samples lost) moves stamp and
//      receive time (and the sequence when samples were lost) together.
//   4. Otherwise the stamp alone disagrees: it is repaired to t0 + d*T (or
//      t0 + max(dr, T) when the sequence is not usable) and the sample is
//      kept (stamp repaired ahead / behind). One bad stamp costs no sample.
//   5. step_samples consecutive repairs with the same offset (within tol) are
//      a clock step, not a glitch: the stamp is taken as it is from then on
//      (clock step, counted).
// Every accepted sample reports the trusted time since the previous one and
// the sample periods missing in between (round(elapsed / T) - 1).
#pragma once

#include <cstdint>
#include <optional>

namespace tactile_common {

struct SampleClockParams {
  double nominal_period_s = 0.02;  ///< first period estimate (whisker deck: 50 Hz, paper 000)
  double tolerance_s = 0.1;        ///< two clocks agree when their elapsed times differ by at most this
  int64_t max_late_samples = 50;   ///< a sample this many or fewer behind (sequence) is late, more: a restart
  int64_t step_samples = 25;       ///< repairs in a row with one offset that make a clock step
  /// Throws std::invalid_argument "SampleClockParams.<field>: <reason>".
  void validate() const;
};

enum class SampleKind : uint8_t {
  kFirst,           ///< first sample: accepted as it is
  kInOrder,         ///< stamp agrees with the sequence or the receive time
  kRepairedAhead,   ///< stamp too far ahead of both: replaced
  kRepairedBehind,  ///< stamp behind or too close: replaced
  kClockStep,       ///< step_samples repairs with one offset: the new stamp base is taken
  kDuplicate,       ///< same sequence, stamp not advancing: dropped
  kLate,            ///< sequence behind the last accepted one: dropped
};

const char* to_string(SampleKind kind);

struct SampleDecision {
  SampleKind kind = SampleKind::kFirst;
  bool accept = true;      ///< false: drop the sample (duplicate, late)
  int64_t stamp_ns = 0;    ///< stamp to use (the original unless repaired)
  int64_t elapsed_ns = 0;  ///< trusted time since the previous accepted sample (0 for the first)
  int64_t missing = 0;     ///< sample periods without a sample before this one (>= 0)
  bool restart = false;    ///< the sequence went back (or stood still with a new stamp): source restarted
};

/// Counters of every decision.
struct SampleClockStats {
  uint64_t in_order = 0;         ///< accepted as they were (the first sample included)
  uint64_t repaired_ahead = 0;   ///< stamps replaced, the original was ahead
  uint64_t repaired_behind = 0;  ///< stamps replaced, the original was behind
  uint64_t clock_steps = 0;      ///< new stamp bases taken
  uint64_t duplicates = 0;       ///< dropped
  uint64_t late = 0;             ///< dropped
  uint64_t restarts = 0;         ///< sequence restarts (sample kept)
  uint64_t gaps = 0;             ///< accepted samples with missing > 0
  uint64_t missing = 0;          ///< sum of the missing sample periods
};

class SampleClock {
 public:
  explicit SampleClock(const SampleClockParams& params = {});

  /// Classifies one sample. receive_ns: when it was received (nullopt: not
  /// known, the sequence alone checks the stamp).
  SampleDecision classify(uint32_t sequence, int64_t stamp_ns, std::optional<int64_t> receive_ns);
  void reset();

  const SampleClockStats& stats() const { return stats_; }
  const SampleClockParams& params() const { return params_; }
  /// Current estimate of the sample period [ns].
  double period_ns() const { return period_ns_; }

 private:
  SampleClockParams params_;
  SampleClockStats stats_;
  bool have_last_ = false;
  uint32_t last_seq_ = 0;
  int64_t last_stamp_ = 0;  // stamp in use (repaired) of the last accepted sample
  int64_t last_raw_ = 0;    // its original stamp
  bool have_receive_ = false;
  int64_t last_receive_ = 0;
  double period_ns_ = 0.0;
  int64_t repair_run_ = 0;
  int64_t repair_offset_ = 0;
};

}  // namespace tactile_common
