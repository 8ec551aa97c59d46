#include "tdorc_filter/tdorc.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tdorc_filter {

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& reason) {
  throw std::invalid_argument("TdorcParams." + field + ": " + reason);
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

}  // namespace

const char* to_string(Mode mode) {
  switch (mode) {
    case Mode::kTdorc:
      return "tdorc";
    case Mode::kTdoc:
      return "tdoc";
    case Mode::kBandpass:
      return "bandpass";
  }
  return "unknown";
}

Mode mode_from_string(const char* text) {
  if (std::strcmp(text, "tdorc") == 0) return Mode::kTdorc;
  if (std::strcmp(text, "tdoc") == 0) return Mode::kTdoc;
  if (std::strcmp(text, "bandpass") == 0) return Mode::kBandpass;
  throw std::invalid_argument(std::string("TdorcParams.mode: must be \"tdorc\", \"tdoc\" or \"bandpass\", got \"") +
                              text + "\"");
}

void Params::validate() const {
  if (mode != Mode::kTdorc && mode != Mode::kTdoc && mode != Mode::kBandpass) {
    bad("mode", "unknown mode " + std::to_string(static_cast<int>(mode)));
  }
  if (window < 2) bad("window", "must be >= 2, got " + std::to_string(window));
  // Bound keeps the exact int64 sums of t and t^2 far from overflow and the
  // state small; the paper uses 100.
  if (window > 100000) bad("window", "must be <= 100000, got " + std::to_string(window));
  if (!std::isfinite(contact_threshold)) bad("contact_threshold", "must be finite, got " + num(contact_threshold));
  if (absolute_threshold && contact_threshold < 0.0) {
    bad("contact_threshold", "must be >= 0 with absolute_threshold, got " + num(contact_threshold));
  }
  if (learn_delay < 0 || learn_delay > 10000) bad("learn_delay", "must be in [0, 10000], got " + std::to_string(learn_delay));
  if (!(hold_release_fraction >= 0.0 && hold_release_fraction < 1.0)) {
    bad("hold_release_fraction", "must be in [0, 1), got " + num(hold_release_fraction));
  }
  if (!(hold_release_drop >= 0.0 && hold_release_drop < 1.0)) {
    bad("hold_release_drop", "must be in [0, 1), got " + num(hold_release_drop));
  }
  if (!(max_drift_slope >= 0.0) || !std::isfinite(max_drift_slope)) {
    bad("max_drift_slope", "must be finite and >= 0, got " + num(max_drift_slope));
  }
  if (!(hold_quiet_rms >= 0.0) || !std::isfinite(hold_quiet_rms)) {
    bad("hold_quiet_rms", "must be finite and >= 0, got " + num(hold_quiet_rms));
  }
  if (hold_quiet_samples < 2 || hold_quiet_samples > 10000) {
    bad("hold_quiet_samples", "must be in [2, 10000], got " + std::to_string(hold_quiet_samples));
  }
  if (hold_level_samples < 1 || hold_level_samples > 100000) {
    bad("hold_level_samples", "must be in [1, 100000], got " + std::to_string(hold_level_samples));
  }
  if (max_contact_hold < 1) bad("max_contact_hold", "must be >= 1, got " + std::to_string(max_contact_hold));
  if (hold_release_samples < 1 || hold_release_samples > 10000) {
    bad("hold_release_samples", "must be in [1, 10000], got " + std::to_string(hold_release_samples));
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(bandpass_b[i])) bad("bandpass_b[" + std::to_string(i) + "]", "must be finite, got " + num(bandpass_b[i]));
    if (!std::isfinite(bandpass_a[i])) bad("bandpass_a[" + std::to_string(i) + "]", "must be finite, got " + num(bandpass_a[i]));
  }
  if (bandpass_a[0] != 1.0) bad("bandpass_a[0]", "must be 1 (normalised denominator, 000 eq. 9-11), got " + num(bandpass_a[0]));
  // Stability (Jury criterion for z^2 + a1 z + a2): |a2| < 1 and |a1| < 1 + a2.
  if (!(std::fabs(bandpass_a[2]) < 1.0) || !(std::fabs(bandpass_a[1]) < 1.0 + bandpass_a[2])) {
    bad("bandpass_a", "poles must lie inside the unit circle (|a2| < 1 and |a1| < 1 + a2), got [" +
                          num(bandpass_a[0]) + ", " + num(bandpass_a[1]) + ", " + num(bandpass_a[2]) + "]");
  }
}

bool operator==(const Params& a, const Params& b) {
  return a.mode == b.mode && a.window == b.window && a.contact_threshold == b.contact_threshold &&
         a.absolute_threshold == b.absolute_threshold && a.learn_delay == b.learn_delay &&
         a.contact_hold == b.contact_hold && a.max_contact_hold == b.max_contact_hold &&
         a.hold_release_fraction == b.hold_release_fraction && a.hold_release_samples == b.hold_release_samples &&
         a.hold_release_drop == b.hold_release_drop && a.hold_level_samples == b.hold_level_samples &&
         a.max_drift_slope == b.max_drift_slope && a.hold_quiet_rms == b.hold_quiet_rms &&
         a.hold_quiet_samples == b.hold_quiet_samples && a.bandpass_b == b.bandpass_b && a.bandpass_a == b.bandpass_a;
}

// ---------------------------------------------------------------- BandpassBiquad

BandpassBiquad::BandpassBiquad(const std::array<double, 3>& b, const std::array<double, 3>& a) : b_(b), a_(a) {}

double BandpassBiquad::step(double x) {
  const double y = b_[0] * x + z0_;            // 000 eq. 9
  z0_ = b_[1] * x - a_[1] * y + z1_;           // 000 eq. 10
  z1_ = b_[2] * x - a_[2] * y;                 // 000 eq. 11
  return y;
}

void BandpassBiquad::init_steady_state(double x) {
  // Constant input x forever: output y = H(1) x, H(1) = sum(b) / sum(a)
  // (finite: validate() requires poles inside the unit circle). Then eq. 11
  // and eq. 10 at their fixed point give the state.
  const double y = x * (b_[0] + b_[1] + b_[2]) / (a_[0] + a_[1] + a_[2]);
  z1_ = b_[2] * x - a_[2] * y;
  z0_ = b_[1] * x - a_[1] * y + z1_;
}

void BandpassBiquad::reset() {
  z0_ = 0.0;
  z1_ = 0.0;
}

// ---------------------------------------------------------------- DriftFit

DriftFit::DriftFit(int window)
    : window_(window), y_(static_cast<std::size_t>(window > 0 ? window : 0), 0.0),
      k_(static_cast<std::size_t>(window > 0 ? window : 0), 0) {
  if (window < 2) bad("window", "must be >= 2, got " + std::to_string(window));
}

void DriftFit::reset() {
  head_ = 0;
  count_ = 0;
  pushes_since_recompute_ = 0;
  have_ref_ = false;
  ref_ = 0.0;
  base_ = 0;
  sum_t_ = 0;
  sum_tt_ = 0;
  sum_y_ = 0.0;
  sum_ty_ = 0.0;
}

void DriftFit::push(int64_t k, double value) {
  if (!have_ref_) {
    // Pressures of one barometer stay within a factor 2 of each other, so
    // value - ref_ is exact (Sterbenz) and the sums hold only the small drift.
    ref_ = value;
    base_ = k;
    have_ref_ = true;
  }
  const double y = value - ref_;
  int slot;
  if (count_ == window_) {
    slot = head_;
    const int64_t t_old = k_[slot] - base_;
    const double y_old = y_[slot];
    sum_t_ -= t_old;
    sum_tt_ -= t_old * t_old;
    sum_y_ -= y_old;
    sum_ty_ -= static_cast<double>(t_old) * y_old;
    head_ = (head_ + 1) % window_;
  } else {
    slot = (head_ + count_) % window_;
    ++count_;
  }
  y_[slot] = y;
  k_[slot] = k;
  const int64_t t = k - base_;
  sum_t_ += t;
  sum_tt_ += t * t;
  sum_y_ += y;
  sum_ty_ += static_cast<double>(t) * y;
  // Guard against accumulated rounding in sum_y_/sum_ty_ and against large t
  // after long gaps: rebuild the sums every n pushes (amortised O(1)).
  if (++pushes_since_recompute_ >= window_ || t > static_cast<int64_t>(window_) * 1024) recompute_sums();
}

void DriftFit::recompute_sums() {
  pushes_since_recompute_ = 0;
  if (count_ == 0) return;
  base_ = k_[head_];
  sum_t_ = 0;
  sum_tt_ = 0;
  sum_y_ = 0.0;
  sum_ty_ = 0.0;
  for (int i = 0; i < count_; ++i) {
    const int slot = (head_ + i) % window_;
    const int64_t t = k_[slot] - base_;
    sum_t_ += t;
    sum_tt_ += t * t;
    sum_y_ += y_[slot];
    sum_ty_ += static_cast<double>(t) * y_[slot];
  }
}

LineFit DriftFit::fit() const {
  LineFit line;
  if (count_ < 2) {
    line.first_index = count_ == 1 ? k_[head_] : 0;
    line.intercept = count_ == 1 ? ref_ + y_[head_] : 0.0;
    return line;
  }
  const int64_t n = count_;
  // 000 eq. 6: a = (n*sum(t*S_r) - sum(t)*sum(S_r)) / (n*sum(t^2) - sum(t)^2).
  // The denominator is an exact integer (> 0: the indices are distinct).
  const int64_t den = n * sum_tt_ - sum_t_ * sum_t_;
  const double a = (static_cast<double>(n) * sum_ty_ - static_cast<double>(sum_t_) * sum_y_) / static_cast<double>(den);
  // 000 eq. 7: b = (sum(S_r) - a*sum(t)) / n, with t relative to base_ and
  // S_r relative to ref_.
  const double b_rel = (sum_y_ - a * static_cast<double>(sum_t_)) / static_cast<double>(n);
  line.slope = a;
  line.first_index = k_[head_];
  // Re-express at the window's first sample (t = 0 there) and in absolute Pa.
  line.intercept = ref_ + (b_rel + a * static_cast<double>(line.first_index - base_));
  return line;
}

std::size_t DriftFit::state_size_bytes() const {
  return sizeof(*this) + y_.capacity() * sizeof(double) + k_.capacity() * sizeof(int64_t);
}

// ---------------------------------------------------------------- TdorcChannel

namespace {
const Params& validated(const Params& p) {
  p.validate();
  return p;
}
}  // namespace

TdorcChannel::TdorcChannel(const Params& params)
    : params_(validated(params)),
      fit_(params.window),
      filter_(params.bandpass_b, params.bandpass_a),
      pending_(static_cast<std::size_t>(params.learn_delay) + 1) {}

void TdorcChannel::reset() {
  fit_.reset();
  filter_.reset();
  line_ = LineFit{};
  ready_ = false;
  filter_started_ = false;
  fit_count_ = 0;
  implausible_fits_ = 0;
  pending_head_ = 0;
  pending_count_ = 0;
}

ChannelOutput TdorcChannel::compensate(int64_t sample_index, double value) {
  ChannelOutput out;
  out.raw = value;
  double calibrated;
  if (params_.mode == Mode::kBandpass) {
    ready_ = true;
    calibrated = value;  // band-pass baseline: no drift model
  } else {
    if (!ready_) return out;  // first window still filling
    // 000 eq. 4-5: S_c = S_r - (a*t + b), t = this sample's index in the
    // fitted window's time base (the line is extrapolated past the window).
    calibrated = value - line_.at(sample_index);
    out.drift_slope = line_.slope;
    out.drift_intercept = line_.intercept;
  }
  if (!filter_started_) {
    filter_.init_steady_state(calibrated);
    filter_started_ = true;
  }
  const double sp = filter_.step(calibrated);  // 000 eq. 9-11
  out.ready = true;
  out.calibrated = calibrated;
  out.compensated = sp;
  out.contact = params_.absolute_threshold ? std::fabs(sp) > params_.contact_threshold
                                           : sp > params_.contact_threshold;
  return out;
}

void TdorcChannel::learn(int64_t sample_index, double value, bool contact) {
  if (params_.mode == Mode::kBandpass) return;
  if (!ready_) {
    // First window after start/reset, assumed free flight: fit once full.
    fit_.push(sample_index, value);
    if (fit_.full()) {
      line_ = fit_.fit();  // 000 eq. 6, 7
      ++fit_count_;
      ready_ = true;
    }
  } else if (params_.mode == Mode::kTdorc && contact) {
    // Contact: the samples still waiting may hold the contact's rising edge.
    pending_count_ = 0;
  } else if (params_.mode == Mode::kTdorc) {
    // 000 eq. 8: free flight -> slide the window and re-fit a, b, with the
    // sample of learn_delay samples ago (this one, when learn_delay = 0).
    const int cap = static_cast<int>(pending_.size());
    pending_[static_cast<std::size_t>((pending_head_ + pending_count_) % cap)] = {sample_index, value};
    ++pending_count_;
    if (pending_count_ > params_.learn_delay) {
      const auto [k, v] = pending_[static_cast<std::size_t>(pending_head_)];
      pending_head_ = (pending_head_ + 1) % cap;
      --pending_count_;
      fit_.push(k, v);
      const LineFit fit = fit_.fit();  // 000 eq. 6, 7
      if (params_.max_drift_slope > 0.0 && std::fabs(fit.slope) > params_.max_drift_slope) {
        ++implausible_fits_;  // the window straddles a contact step: keep the last line
      } else {
        line_ = fit;
        ++fit_count_;
      }
    }
  }
  // TDOC after its fit, or TDORC in contact: the line stays frozen.
}

ChannelOutput TdorcChannel::update(int64_t sample_index, double value) {
  const ChannelOutput out = compensate(sample_index, value);
  learn(sample_index, value, out.contact);
  return out;
}

std::size_t TdorcChannel::state_size_bytes() const {
  return sizeof(*this) - sizeof(fit_) + fit_.state_size_bytes() + pending_.capacity() * sizeof(pending_[0]);
}

// ---------------------------------------------------------------- TdorcWhisker

TdorcWhisker::TdorcWhisker(const Params& params)
    : params_(validated(params)),
      channels_{{TdorcChannel(params), TdorcChannel(params), TdorcChannel(params)}},
      quiet_sq_(params.hold_quiet_rms > 0.0 ? static_cast<std::size_t>(params.hold_quiet_samples) : 1, 0.0) {}

void TdorcWhisker::set_contact_threshold(double contact_threshold) {
  Params next = params_;
  next.contact_threshold = contact_threshold;
  next.validate();
  params_ = next;
  for (auto& c : channels_) c.set_contact_threshold(contact_threshold);
}

void TdorcWhisker::reset() {
  for (auto& c : channels_) c.reset();
  next_index_ = 0;
  contact_ = false;
  contact_samples_ = 0;
  contact_peak_ = {};
  contact_level_ = 0.0;
  below_samples_ = 0;
  std::fill(quiet_sq_.begin(), quiet_sq_.end(), 0.0);
  quiet_head_ = quiet_count_ = quiet_pushes_ = 0;
  quiet_sum_ = last_sum_ = 0.0;
  have_last_sum_ = false;
}

void TdorcWhisker::push_quiet(double sum) {
  if (!have_last_sum_) {
    last_sum_ = sum;
    have_last_sum_ = true;
    return;
  }
  const double d = sum - last_sum_;
  last_sum_ = sum;
  const int n = static_cast<int>(quiet_sq_.size());
  const int slot = (quiet_head_ + quiet_count_) % n;
  if (quiet_count_ == n) {
    quiet_sum_ -= quiet_sq_[static_cast<std::size_t>(quiet_head_)];
    quiet_head_ = (quiet_head_ + 1) % n;
  } else {
    ++quiet_count_;
  }
  quiet_sq_[static_cast<std::size_t>(slot)] = d * d;
  quiet_sum_ += d * d;
  // Rebuild the running sum every n pushes so rounding does not accumulate.
  if (++quiet_pushes_ >= n) {
    quiet_pushes_ = 0;
    quiet_sum_ = 0.0;
    for (double v : quiet_sq_) quiet_sum_ += v;
  }
}

bool TdorcWhisker::quiet() const {
  const int n = static_cast<int>(quiet_sq_.size());
  if (params_.hold_quiet_rms <= 0.0 || quiet_count_ < n) return false;
  // RMS of the changes < hold_quiet_rms  <=>  sum of squares < n * rms^2.
  return quiet_sum_ < static_cast<double>(n) * params_.hold_quiet_rms * params_.hold_quiet_rms;
}

WhiskerOutput TdorcWhisker::update(const std::array<double, 3>& raw) {
  WhiskerOutput out;
  const int64_t k = next_index_++;
  bool any = false;
  bool all_ready = true;
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    out.channel[i] = channels_[i].compensate(k, raw[i]);
    any = any || out.channel[i].contact;
    all_ready = all_ready && out.channel[i].ready;
  }
  if (params_.hold_quiet_rms > 0.0 && all_ready) {
    push_quiet(out.channel[0].calibrated + out.channel[1].calibrated + out.channel[2].calibrated);
  }
  // Whisker-level contact freezes every channel's fit (000 eq. 8).
  // Sustained contact (Params::contact_hold): after an S_p onset the whisker
  // stays in contact while the calibrated signal of any channel is over T_c,
  // and until hold_release_samples consecutive samples had none over it.
  bool held = false;
  if (params_.contact_hold && params_.mode != Mode::kBandpass && !any && contact_ && all_ready && contact_samples_ < params_.max_contact_hold) {
    bool over = false;
    double sum = 0.0;
    for (std::size_t i = 0; i < out.channel.size(); ++i) {
      const double sc = out.channel[i].calibrated;
      over = over || (sc > params_.contact_threshold && sc > params_.hold_release_fraction * contact_peak_[i]);
      sum += sc;
    }
    // A release drops the whisker's S_c (sum of the channels) to a small part
    // of its recent level, whatever offset the gel hysteresis leaves.
    if (params_.hold_release_drop > 0.0) over = over && sum > params_.hold_release_drop * contact_level_;
    // A whisker whose S_c went quiet (barometer noise only) is no longer
    // moved by a wall, whatever offset the hysteresis and the line leave.
    if (quiet()) over = false;
    below_samples_ = over ? 0 : below_samples_ + 1;
    held = below_samples_ < params_.hold_release_samples;
  }
  const bool contact = any || held;
  if (!contact || any) below_samples_ = 0;
  contact_samples_ = contact ? contact_samples_ + 1 : 0;
  double sum = 0.0;
  for (std::size_t i = 0; i < out.channel.size(); ++i) {
    contact_peak_[i] = contact ? std::max(contact_peak_[i], out.channel[i].calibrated) : 0.0;
    sum += out.channel[i].calibrated;
  }
  // Recent level of the whisker's S_c (sum of the channels): the onset's
  // value, then an exponential average over hold_level_samples samples.
  const double level_gain = 1.0 / static_cast<double>(params_.hold_level_samples);
  contact_level_ = !contact ? 0.0 : (contact_samples_ == 1 ? sum : contact_level_ + level_gain * (sum - contact_level_));
  // Freeze while in contact (000 eq. 8).
  const bool freeze = contact;
  for (std::size_t i = 0; i < channels_.size(); ++i) channels_[i].learn(k, raw[i], freeze);
  contact_ = contact;
  out.contact = contact;
  out.contact_held = held;
  out.ready = all_ready;
  out.drift_frozen = params_.mode == Mode::kTdorc && all_ready && freeze;
  out.window_fill = channels_[0].window_fill();
  return out;
}

std::size_t TdorcWhisker::state_size_bytes() const {
  std::size_t s = sizeof(*this);
  for (const auto& c : channels_) s += c.state_size_bytes() - sizeof(TdorcChannel);
  return s;
}

}  // namespace tdorc_filter
