// TDORC: tactile drift online recurrent compensation (paper 000, Methods,
// "Tactile drift online recurrent compensation", eq. 1-11), with the TDOC and
// band-pass-only baselines of the paper's Results (Extended Data Fig. 2).
//
// Core layer: no ROS, no message types, no allocation per sample (the
// least-squares window is allocated once, at construction).
//
// Per channel and per accepted sample k (k = 0, 1, ... since the last reset):
//   S_r(k)                raw barometer pressure [Pa]                    (000 eq. 1)
//   N_td(t) = a*t + b     drift line, t = sample index relative to the
//                         first sample of the fitted window             (000 eq. 4)
//   a, b                  least squares over the window's n samples      (000 eq. 6, 7)
//   S_c(k) = S_r(k) - N_td(t_k), t_k = k - k_first(fitted window)        (000 eq. 5)
//   S_p(k) = biquad band-pass of S_c                                     (000 eq. 9-11)
//   contact(k) = S_p(k) > T_c (or |S_p(k)| > T_c)                        (000 Results, T_c = 20)
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tdorc_filter {

/// Which compensation runs (paper 000, Results / Extended Data Fig. 2b).
enum class Mode : uint8_t {
  kTdorc = 0,     ///< re-fit the drift on every free-flight sample (000 eq. 8), then band-pass
  kTdoc = 1,      ///< fit the drift once on the first n samples, never again, then band-pass
  kBandpass = 2,  ///< band-pass only: S_c = S_r (000 eq. 9-11)
};

/// "tdorc" / "tdoc" / "bandpass".
const char* to_string(Mode mode);
/// Parses "tdorc" / "tdoc" / "bandpass"; throws std::invalid_argument otherwise.
Mode mode_from_string(const char* text);

/// Parameters of TDORC. Defaults are the paper's values.
struct Params {
  Mode mode = Mode::kTdorc;
  /// n, samples in the least-squares window (000 Methods: "sliding window (n = 100)").
  int window = 100;
  /// T_c, contact threshold on S_p [Pa] (000 Results: "Using a threshold of 20").
  double contact_threshold = 20.0;
  /// false: contact when S_p > T_c (the paper's S_p^up > T, a pushed whisker
  /// raises the pressure); true: contact when |S_p| > T_c, which also counts
  /// the band-pass undershoot after a release as contact (more conservative:
  /// the drift stays frozen a little longer).
  bool absolute_threshold = false;
  // --- Sustained contact (workspace extension; paper defaults: off) -------
  // The band-pass (high-pass at 0.05 Hz, tau ~3 s) turns a held contact into
  // a decaying S_p. With eq. 8 as written, a whisker pressed against a wall
  // for more than a few seconds loses its contact flag while it still
  // touches; the drift window then learns contact samples, and their slope,
  // extrapolated while frozen, can hold S_p over T_c long after the release
  // (a "lock"). Likewise the rising edge of a contact, below T_c for a few
  // samples, enters the window and bends the line (one +200 Pa sample at the
  // window's end tilts a 100-sample fit by 0.12 Pa/sample).
  /// A free-flight sample enters the drift window only after `learn_delay`
  /// further samples were free too; a contact onset discards the pending
  /// ones, so a contact's rising edge never enters the window. 0: eq. 8 as
  /// written (learn every free sample at once).
  int learn_delay = 0;
  /// Once in contact (onset by S_p > T_c, the paper's rule), the whisker stays
  /// in contact while any channel's S_c (relative to the frozen drift line)
  /// exceeds T_c, for at most max_contact_hold samples; then only S_p decides
  /// again (so a drift-line error cannot hold the contact for ever).
  bool contact_hold = false;
  /// Limit of a held contact [samples] (1000 = 20 s at 50 Hz).
  int max_contact_hold = 1000;
  /// A held contact also ends when no channel's S_c is above this fraction of
  /// the largest S_c of that channel during the contact (a release drops S_c
  /// to the drift-line error, a partial retreat only part of the way); 0: off.
  double hold_release_fraction = 0.0;
  /// A held contact ends only after this many consecutive samples in which no
  /// channel's S_c is over the hold condition (T_c and the release fraction);
  /// the samples in between stay in contact (frozen drift, not learned). A
  /// whisker sliding along a wall stick-slips: single samples of the slip
  /// phase drop S_c of every channel near zero while the whisker is still
  /// pressed, and a release there lets the window learn pressed samples.
  /// 1: release at the first such sample.
  int hold_release_samples = 1;
  /// A held contact also ends when the whisker's S_c (sum of its three
  /// channels) falls below this fraction of its recent level in the contact
  /// (an exponential average over hold_level_samples samples, updated while
  /// in contact); 0: off.
  /// Gel hysteresis (000 eq. 1, N_h: "partial inelastic strain recovery")
  /// leaves an offset after every release that the frozen drift line does not
  /// remove; a whisker ticking a baffle's end piles these offsets up until
  /// they exceed any fraction of the contact's peak and hold the whisker "in
  /// contact" after it left. A release is a fall of S_c to a small part of
  /// the level just before it, whatever the offset.
  double hold_release_drop = 0.0;
  /// Time constant of the recent level [samples] (25 = 0.5 s at 50 Hz).
  int hold_level_samples = 25;
  /// Largest drift slope a re-fit may have [Pa per sample]; a fit beyond it
  /// is not used (the last line stays, as while frozen). Thermal drift is
  /// slow (the SITL's peaks at ~0.2 Pa/sample); a least-squares line through
  /// a window that holds pressed samples and then free ones (a release missed
  /// or mistaken) is steep, and frozen at the next contact its extrapolated
  /// ramp holds S_p over T_c for good (S_p of a ramp of c Pa/sample settles
  /// at ~161 c). 0: off (eq. 8 as written: every fit is used).
  double max_drift_slope = 0.0;
  /// A held contact also ends when the whisker's S_c (sum of its three
  /// channels) has gone quiet: the RMS of its sample-to-sample changes over
  /// the last hold_quiet_samples samples is below this [Pa]; 0: off.
  /// A whisker pressed by a flying drone follows every millimetre of the
  /// drone's motion and every stick-slip (in the SITL's held contacts the RMS
  /// is 10 Pa at the 1st percentile, 180 Pa median); a free whisker's S_c is
  /// the barometer noise (RMS of the changes of the sum ~6 Pa in flight) on
  /// top of a slow decay of the gel hysteresis (000 eq. 1, N_h) and the drift
  /// line's error, which is what a held contact of a whisker that left the
  /// wall reads, whatever its size.
  double hold_quiet_rms = 0.0;
  /// Samples over which that RMS is taken (25 = 0.5 s at 50 Hz).
  int hold_quiet_samples = 25;
  /// Band-pass numerator b0, b1, b2 (000 eq. 9-11, first-order Butterworth 0.05-1 Hz at 50 Hz).
  std::array<double, 3> bandpass_b{{0.0564, 0.0, -0.0564}};
  /// Band-pass denominator a0, a1, a2; a0 must be 1 (000 eq. 9-11).
  std::array<double, 3> bandpass_a{{1.0, -1.8865, 0.8872}};

  /// Throws std::invalid_argument naming the field and the reason, e.g.
  /// "TdorcParams.window: must be >= 2, got 1".
  void validate() const;
};

/// Field-by-field equality (a node logic refuses a live change that touches other fields).
bool operator==(const Params& a, const Params& b);
inline bool operator!=(const Params& a, const Params& b) { return !(a == b); }

/// Band-pass biquad in transposed direct form II (000 eq. 9-11):
///   S_p = b0*S_c + z0                 (9)
///   z0' = b1*S_c - a1*S_p + z1        (10)
///   z1' = b2*S_c - a2*S_p             (11)
class BandpassBiquad {
 public:
  BandpassBiquad(const std::array<double, 3>& b, const std::array<double, 3>& a);
  /// One sample through eq. 9-11. The first call after construction or reset()
  /// starts from zero state (z0 = z1 = 0).
  double step(double x);
  /// Sets the state to the steady state of a constant input x held forever
  /// (what scipy.signal.lfilter_zi(b, a) * x gives); with the band-pass
  /// (sum b = 0) the next output for input x is then 0.
  void init_steady_state(double x);
  void reset();
  double z0() const { return z0_; }
  double z1() const { return z1_; }

 private:
  std::array<double, 3> b_;
  std::array<double, 3> a_;
  double z0_ = 0.0;
  double z1_ = 0.0;
};

/// Result of a least-squares line fit: N_td(t) = slope*t + intercept, t = 0 at
/// the window's first sample.
struct LineFit {
  double slope = 0.0;      ///< a [Pa per sample] (000 eq. 6)
  double intercept = 0.0;  ///< b [Pa] at the window's first sample (000 eq. 7)
  int64_t first_index = 0; ///< sample index k of the window's first sample
  /// N_td at sample index k (extrapolates beyond the window).
  double at(int64_t k) const { return slope * static_cast<double>(k - first_index) + intercept; }
};

/// Least squares of a line over the last n (sample index, value) pairs
/// (000 eq. 4, 6, 7), O(1) per sample: running sums over a ring buffer.
///
/// Numerics: values are stored relative to the first value pushed after a
/// reset (subtraction of nearby pressures is exact), indices relative to a
/// base index; the running sums are recomputed from the buffer every n pushes
/// (amortised O(1)), so floating-point error of add/subtract does not
/// accumulate. Sums of t and t^2 are integers, kept exact in int64.
class DriftFit {
 public:
  /// Allocates the window once. window >= 2.
  explicit DriftFit(int window);
  /// Adds sample (k, value); drops the oldest when the window is full.
  /// Sample indices must increase strictly; gaps are allowed (samples skipped
  /// during contact keep their true time index).
  void push(int64_t k, double value);
  bool full() const { return count_ == window_; }
  int count() const { return count_; }
  int window() const { return window_; }
  /// Least squares over the current window (000 eq. 6, 7). Requires count() >= 2.
  LineFit fit() const;
  void reset();
  /// Bytes of state (object plus the window buffers).
  std::size_t state_size_bytes() const;

 private:
  void recompute_sums();

  int window_;
  std::vector<double> y_;    // value - ref_, ring buffer
  std::vector<int64_t> k_;   // sample index, ring buffer
  int head_ = 0;             // slot of the oldest sample
  int count_ = 0;
  int pushes_since_recompute_ = 0;
  bool have_ref_ = false;
  double ref_ = 0.0;         // value offset
  int64_t base_ = 0;         // index offset: t = k - base_
  int64_t sum_t_ = 0;
  int64_t sum_tt_ = 0;
  double sum_y_ = 0.0;
  double sum_ty_ = 0.0;
};

/// Output of one channel for one sample.
struct ChannelOutput {
  double raw = 0.0;          ///< S_r [Pa]
  double calibrated = 0.0;   ///< S_c = S_r - N_td (000 eq. 5) [Pa]; 0 until ready
  double compensated = 0.0;  ///< S_p (000 eq. 9-11) [Pa]; 0 until ready
  bool contact = false;      ///< S_p > T_c (or |S_p| > T_c)
  bool ready = false;        ///< a drift fit exists (always true in band-pass mode)
  double drift_slope = 0.0;      ///< a of the fit in use [Pa per sample]
  double drift_intercept = 0.0;  ///< b of the fit in use, at its window's first sample [Pa]
};

/// TDORC for one barometer channel.
///
/// Each sample is processed in two steps, so that the drift model only ever
/// learns from samples that were judged free flight:
///   1. compensate(): S_c = S_r - N_td with the current fit extrapolated to
///      this sample (000 eq. 5), S_p by the band-pass (eq. 9-11), contact;
///   2. learn(): with the contact decision of this sample (whisker level),
///      TDORC adds the sample to the window and re-fits a, b if not in
///      contact, and keeps the fit frozen otherwise (000 eq. 8: "If the
///      calibrated signal S_c(t) remains below a predefined threshold [...]
///      recalculates the drift parameters").
///
/// Until the first window is full (the first n samples after start or
/// reset) the channel is not ready: S_c = S_p = 0, no contact, the band-pass
/// does not run; those samples are assumed free flight (the paper hovers
/// after take-off "to initialize the TDORC"). The first output is for sample
/// n. TDOC fits once on those n samples and never again. In band-pass mode
/// the channel is ready from the first sample and learns nothing.
/// The band-pass starts from the steady state of its first input (so a
/// constant input gives S_p = 0 from the start, without the step transient
/// of a zero state); every later sample runs eq. 9-11 unchanged.
class TdorcChannel {
 public:
  /// Validates params, allocates the window.
  explicit TdorcChannel(const Params& params);
  /// Step 1 for sample `sample_index` (strictly increasing, one per accepted
  /// sample). `value` must be finite (the caller drops bad samples).
  ChannelOutput compensate(int64_t sample_index, double value);
  /// Step 2 for the same sample: `contact` is the whisker's contact decision
  /// for this sample.
  void learn(int64_t sample_index, double value, bool contact);
  /// Both steps for a channel used on its own (its own contact decides).
  ChannelOutput update(int64_t sample_index, double value);
  void reset();
  /// T_c for the next samples (a live parameter: read per sample, no state depends on it).
  void set_contact_threshold(double contact_threshold) { params_.contact_threshold = contact_threshold; }
  bool ready() const { return ready_; }
  /// Fits so far (0 before the first window is full; TDOC stays at 1).
  uint64_t fit_count() const { return fit_count_; }
  /// Re-fits not used because their slope exceeded Params::max_drift_slope.
  uint64_t implausible_fits() const { return implausible_fits_; }
  const LineFit& line() const { return line_; }
  int window_fill() const { return fit_.count(); }
  std::size_t state_size_bytes() const;

 private:
  Params params_;
  DriftFit fit_;
  BandpassBiquad filter_;
  LineFit line_;
  bool ready_ = false;
  bool filter_started_ = false;
  uint64_t fit_count_ = 0;
  uint64_t implausible_fits_ = 0;
  // Free samples waiting learn_delay samples before entering the window
  // (ring of capacity learn_delay + 1).
  std::vector<std::pair<int64_t, double>> pending_;
  int pending_head_ = 0;
  int pending_count_ = 0;
};

/// Output of one whisker (three channels) for one sample.
struct WhiskerOutput {
  std::array<ChannelOutput, 3> channel{};
  bool contact = false;       ///< any channel in contact, or a held contact (Params::contact_hold)
  bool contact_held = false;  ///< contact only by the hold rule (S_c > T_c after the S_p onset)
  bool ready = false;         ///< all channels ready
  /// TDORC only: the whisker is in contact at this sample, so the sample is
  /// not added to the window and the drift fit stays frozen (000 eq. 8).
  /// Always false in TDOC (its single fit is fixed by design, not by
  /// contact) and in band-pass mode.
  bool drift_frozen = false;
  int window_fill = 0;        ///< samples in the least-squares window (same for all channels)
};

/// TDORC for one whisker: three channels that share one contact state. The
/// whisker is in contact when any channel is; while it is, no channel's drift
/// is re-fitted (000 eq. 8: "calibration updates are applied only when no
/// contacts are detected"). Order per sample: all channels compensate with
/// the fits of the previous samples, the whisker contact is decided, then the
/// fits learn (or stay frozen); a contact onset never enters the window.
class TdorcWhisker {
 public:
  static constexpr int kChannels = 3;
  explicit TdorcWhisker(const Params& params);
  /// One sample of all three channels; values must be finite.
  WhiskerOutput update(const std::array<double, 3>& raw);
  /// `n` sample periods passed without a sample (a gap in the stream): the
  /// next sample's index is n larger, so the drift line N_td(t) (000 eq. 4,
  /// t in sample periods) is extrapolated over the gap, as it is across a
  /// contact; windows, fits, band-pass and contact state stay as they are.
  void skip(int64_t n) {
    if (n > 0) next_index_ += n;
  }
  void reset();
  /// T_c for the next samples, of all three channels (a live parameter: S_p and the hold
  /// conditions compare with it per sample; windows, fits and filter state stay).
  /// Throws std::invalid_argument if Params::validate() refuses it.
  void set_contact_threshold(double contact_threshold);
  const Params& params() const { return params_; }
  const TdorcChannel& channel(int i) const { return channels_[static_cast<std::size_t>(i)]; }
  int64_t samples() const { return next_index_; }
  bool contact() const { return contact_; }
  /// Samples since the current contact began (0 out of contact).
  int64_t contact_samples() const { return contact_samples_; }
  /// Bytes of state of the whole whisker (three channels, window buffers included).
  std::size_t state_size_bytes() const;

 private:
  Params params_;
  std::array<TdorcChannel, 3> channels_;
  int64_t next_index_ = 0;
  bool contact_ = false;
  int64_t contact_samples_ = 0;
  std::array<double, 3> contact_peak_{};  // largest S_c per channel during the current contact
  int below_samples_ = 0;  // consecutive held samples with no channel over the hold condition
  double contact_level_ = 0.0;  // recent level of the sum of the channels' S_c in the current contact (hold_release_drop)
  // hold_quiet_rms: squared sample-to-sample changes of the sum of the
  // channels' S_c over the last hold_quiet_samples ready samples (ring).
  std::vector<double> quiet_sq_;
  int quiet_head_ = 0;
  int quiet_count_ = 0;
  int quiet_pushes_ = 0;
  double quiet_sum_ = 0.0;
  double last_sum_ = 0.0;
  bool have_last_sum_ = false;
  void push_quiet(double sum);
  bool quiet() const;
};

}  // namespace tdorc_filter
