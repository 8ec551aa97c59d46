#include "whisker_driver/whisker_driver_logic.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "tactile_common/time.hpp"
#include "whisker_driver/serial_port.hpp"
#ifdef WHISKER_DRIVER_WITH_BAG
#include "whisker_driver/bag_source.hpp"
#endif

namespace whisker_driver {
namespace {
[[noreturn]] void bad(const std::string& field, const std::string& reason) {
  throw std::invalid_argument("WhiskerDriverParams." + field + ": " + reason);
}
}  // namespace

void WhiskerDriverParams::validate() const {
  if (source != "serial" && source != "sim" && source != "bag")
    bad("source", "must be \"serial\", \"sim\" or \"bag\", got \"" + source + "\"");
  if (protocol != "text" && protocol != "csv")
    bad("protocol", "must be \"text\" or \"csv\", got \"" + protocol + "\"");
  if (whisker_id != 0 && whisker_id != 1)
    bad("whisker_id", "must be 0 (WHISKER_LEFT) or 1 (WHISKER_RIGHT), got " + std::to_string(whisker_id));
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0))
    bad("rate_hz", "must be in (0, 1000], got " + std::to_string(rate_hz));
  if (source == "serial" && device.empty()) bad("device", "must not be empty for source \"serial\"");
  if (baud <= 0 || baud > std::numeric_limits<int>::max())
    bad("baud", "must be in [1, " + std::to_string(std::numeric_limits<int>::max()) + "], got " + std::to_string(baud));
  if (!(sim_takeoff_s >= 0.0) || !std::isfinite(sim_takeoff_s))
    bad("sim_takeoff_s", "must be >= 0, got " + std::to_string(sim_takeoff_s));
  if (!(sim_hover_s >= 0.0) || !std::isfinite(sim_hover_s))
    bad("sim_hover_s", "must be >= 0, got " + std::to_string(sim_hover_s));
  if (sim_contact_duration_s.size() != sim_contact_start_s.size() ||
      sim_contact_peak_nm.size() != sim_contact_start_s.size())
    bad("sim_contact_start_s", "sim_contact_start_s, sim_contact_duration_s and sim_contact_peak_nm "
                               "must have the same length");
  for (size_t i = 0; i < sim_contact_start_s.size(); ++i) {
    if (!std::isfinite(sim_contact_start_s[i]) || sim_contact_start_s[i] < 0.0)
      bad("sim_contact_start_s", "entries must be finite and >= 0");
    if (!std::isfinite(sim_contact_duration_s[i]) || sim_contact_duration_s[i] < 0.0)
      bad("sim_contact_duration_s", "entries must be finite and >= 0");
    if (!std::isfinite(sim_contact_peak_nm[i]) || sim_contact_peak_nm[i] < 0.0)
      bad("sim_contact_peak_nm", "entries must be finite and >= 0");
  }
  if (source == "bag" && bag_path.empty()) bad("bag_path", "must not be empty for source \"bag\"");
  if (source == "bag" && bag_topic.empty()) bad("bag_topic", "must not be empty for source \"bag\"");
}

tactile_common::ParamMap WhiskerDriverLogic::default_parameters() {
  const Params d;
  tactile_common::ParamMap m(kNodeName, "defaults");
  using tactile_common::at_least;
  using tactile_common::choice;
  using tactile_common::closed;
  using tactile_common::paper;
  using tactile_common::ParamRange;
  // The driver's spec (README): value, description, unit, the range validate() accepts
  // alone. None is live: the source (device, protocol, bag, synthetic whisker) is opened at
  // configure; `ros2 param set` refuses every key (read-only).
  m.set("source", d.source,
        {"where samples come from: serial (the whisker deck), sim (a synthetic whisker) or bag", "", {}, false,
         choice()});
  m.set("device", d.device,
        {"serial device of the whisker deck (source serial)", "", {}, false, choice()});
  m.set("baud", d.baud,
        {"UART baud rate of the whisker deck (000 hardware)", "baud", closed(1, std::numeric_limits<int>::max()), false,
         choice("115200 8N1, as the deck firmware; 000 gives UART, not the rate")});
  m.set("protocol", d.protocol,
        {"line format: text (whisker 1) or csv (whisker 2)", "", {}, false,
         choice("the deck firmware's line formats")});
  m.set("whisker_id", d.whisker_id,
        {"WhiskerPressure whisker_id: 0 left, 1 right", "", closed(0, 1), false, choice()});
  m.set("frame_id", d.frame_id,
        {"header frame of the pressures", "", {}, false, choice()});
  m.set("rate_hz", d.rate_hz,
        {"sample rate (000: 50 Hz)", "Hz", ParamRange{0.0, 1000.0, true, false}, false,
         paper("000 Methods: whisker deck on UART at 50 Hz")});
  m.set("sim_seed", d.sim_seed,
        {"seed of the synthetic whisker (source sim)", "", {}, false, choice()});
  m.set("sim_takeoff_s", d.sim_takeoff_s,
        {"synthetic take-off time", "s", at_least(0.0), false, choice()});
  m.set("sim_hover_s", d.sim_hover_s,
        {"synthetic hover duration", "s", at_least(0.0), false, choice()});
  m.set("sim_contact_start_s", d.sim_contact_start_s,
        {"synthetic contacts: start times (>= 0)", "s", {}, false, choice()});
  m.set("sim_contact_duration_s", d.sim_contact_duration_s,
        {"synthetic contacts: durations (>= 0), one per start", "s", {}, false, choice()});
  m.set("sim_contact_peak_nm", d.sim_contact_peak_nm,
        {"synthetic contacts: peak base moments (>= 0), one per start", "N m", {}, false,
         choice("2e-4 N m gives ~200 Pa (tactile_sim docs/whisker_signal_model.md)")});
  m.set("bag_path", d.bag_path,
        {"bag to replay (source bag)", "", {}, false, choice()});
  m.set("bag_topic", d.bag_topic,
        {"WhiskerPressure topic in that bag", "", {}, false, choice()});
  return m;
}

WhiskerDriverParams WhiskerDriverLogic::params_from(const tactile_common::ParamMap& m) {
  Params p;
  p.source = m.get_string("source");
  p.device = m.get_string("device");
  p.baud = m.get_int64("baud", 1, std::numeric_limits<int>::max());  // the serial port takes an int
  p.protocol = m.get_string("protocol");
  p.whisker_id = m.get_int64("whisker_id", 0, 1);
  p.frame_id = m.get_string("frame_id");
  p.rate_hz = m.get_double("rate_hz");
  // Any 64-bit value: used as its uint64 bit pattern (one stream per value).
  p.sim_seed = m.get_int64("sim_seed", std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max());
  p.sim_takeoff_s = m.get_double("sim_takeoff_s");
  p.sim_hover_s = m.get_double("sim_hover_s");
  p.sim_contact_start_s = m.get_double_array("sim_contact_start_s");
  p.sim_contact_duration_s = m.get_double_array("sim_contact_duration_s");
  p.sim_contact_peak_nm = m.get_double_array("sim_contact_peak_nm");
  p.bag_path = m.get_string("bag_path");
  p.bag_topic = m.get_string("bag_topic");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw m.error_from(e);  // "<Type>.<field>: <reason>" -> parameter <field>
  }
  return p;
}

namespace {
std::unique_ptr<WhiskerSource> make_source(const WhiskerDriverParams& p) {
  p.validate();
  SampleIdentity id{static_cast<uint8_t>(p.whisker_id), p.frame_id};
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / p.rate_hz));
  if (p.source == "serial") {
    SerialPort port(p.device, static_cast<int>(p.baud));
    return std::make_unique<SerialSource>(std::move(port), protocol_from_string(p.protocol), id,
                                          period_ns, static_cast<int>(p.baud));
  }
  if (p.source == "sim") {
    SimScenario sc;
    sc.takeoff_s = p.sim_takeoff_s;
    sc.hover_s = p.sim_hover_s;
    for (size_t i = 0; i < p.sim_contact_start_s.size(); ++i) {
      sc.contacts.push_back({p.sim_contact_start_s[i], p.sim_contact_duration_s[i], p.sim_contact_peak_nm[i]});
    }
    return std::make_unique<SimSource>(tactile_sim::WhiskerBarometerParams{},
                                       static_cast<uint64_t>(p.sim_seed), sc, id, p.rate_hz);
  }
#ifdef WHISKER_DRIVER_WITH_BAG
  return std::make_unique<BagSource>(p.bag_path, p.bag_topic);
#else
  throw std::runtime_error("whisker_driver: source \"bag\" is not available (built without tactile_bag)");
#endif
}
}  // namespace

WhiskerDriverLogic::WhiskerDriverLogic(const Params& params)
    : WhiskerDriverLogic(params, make_source(params)) {}

namespace {
tactile_common::SampleClockParams clock_params(const WhiskerDriverParams& p) {
  p.validate();
  tactile_common::SampleClockParams c;
  c.nominal_period_s = 1.0 / p.rate_hz;
  return c;
}
}  // namespace

WhiskerDriverLogic::WhiskerDriverLogic(const Params& params, std::unique_ptr<WhiskerSource> source)
    : params_(params), source_(std::move(source)), clock_(clock_params(params)) {
  params_.validate();
  if (!source_) throw std::invalid_argument("WhiskerDriverLogic: source must not be null");
}

int64_t WhiskerDriverLogic::period_ns() const {
  return static_cast<int64_t>(std::llround(1e9 / params_.rate_hz));
}

WhiskerDriverLogic::Outputs WhiskerDriverLogic::on_timer(int64_t now_ns) {
  using tactile_common::SampleKind;
  Outputs out;
  std::vector<WhiskerPressure> polled;
  std::vector<int64_t> received;
  source_->poll_received(now_ns, polled, received);
  out.pressure.reserve(polled.size());
  for (size_t i = 0; i < polled.size(); ++i) {
    WhiskerPressure& m = polled[i];
    // Which clock to trust (README "Time"): duplicates and late samples are
    // not published, a stamp that disagrees with both the sequence and the
    // receive time is replaced and the sample published.
    const auto d = clock_.classify(m.sequence, tactile_common::from_stamp(m.header.stamp),
                                   i < received.size() ? std::optional<int64_t>(received[i]) : std::nullopt);
    switch (d.kind) {
      case SampleKind::kDuplicate: ++stats_.dropped_duplicate; continue;
      case SampleKind::kLate: ++stats_.dropped_late; continue;
      case SampleKind::kRepairedAhead: ++stats_.stamps_repaired_ahead; break;
      case SampleKind::kRepairedBehind: ++stats_.stamps_repaired_behind; break;
      case SampleKind::kClockStep: ++stats_.clock_steps; break;
      case SampleKind::kFirst:
      case SampleKind::kInOrder: break;
    }
    if (d.restart) ++stats_.sequence_restarts;
    if (d.missing > 0) {
      ++stats_.gaps;
      stats_.samples_missing += static_cast<uint64_t>(d.missing);
    }
    tactile_common::to_stamp(d.stamp_ns, m.header.stamp);
    if (have_last_seq_ && !d.restart) {
      const uint32_t gap = m.sequence - (last_seq_ + 1u);  // modulo 2^32
      if (gap != 0 && gap < 0x80000000u) stats_.sequence_gaps += gap;
    }
    have_last_seq_ = true;
    last_seq_ = m.sequence;
    out.pressure.push_back(std::move(m));
  }
  stats_.published += out.pressure.size();
  if (!out.pressure.empty()) last_output_ns_ = now_ns;
  return out;
}

WhiskerDriverLogic::Stats WhiskerDriverLogic::stats() const {
  Stats s = stats_;
  s.parse = source_->parse_stats();
  s.source_errors = source_->errors();
  return s;
}

}  // namespace whisker_driver
