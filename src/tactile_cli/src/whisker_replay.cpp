#include "tactile_cli/whisker_replay.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "tactile_bag/typed.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/plot.hpp"
#include "tactile_cli/warnings.hpp"
#include "tactile_common/time.hpp"
#include "tactile_msgs/msg/whisker_ground_truth.hpp"

namespace tactile_cli {

namespace {

namespace fs = std::filesystem;
using tactile_msgs::msg::WhiskerGroundTruth;
using tactile_msgs::msg::WhiskerPressure;
using tactile_msgs::msg::WhiskerSignal;

constexpr std::array<const char*, 3> kModes = {"bandpass", "tdoc", "tdorc"};

struct Counts {
  uint64_t fp = 0, tn = 0;
  bool detected = false;           ///< contact flagged during true contact (or anywhere w/o truth)
  uint64_t true_contact_samples = 0;
  uint64_t detected_contact_samples = 0;
  double fpr() const { return fp + tn ? static_cast<double>(fp) / static_cast<double>(fp + tn) : 0.0; }
};

/// Ground truth of one whisker: stamps and contact flags, in time order.
struct Truth {
  std::vector<int64_t> stamp;
  std::vector<bool> contact;
  /// Contact at time t: the latest truth sample at or before t (false before the first).
  bool at(int64_t t) const {
    auto it = std::upper_bound(stamp.begin(), stamp.end(), t);
    if (it == stamp.begin()) return false;
    return contact[static_cast<size_t>(it - stamp.begin() - 1)];
  }
  std::vector<std::pair<double, double>> spans(int64_t t0) const {
    std::vector<std::pair<double, double>> out;
    for (size_t i = 0; i < stamp.size(); ++i) {
      const double t = tactile_common::to_seconds(stamp[i] - t0);
      if (contact[i] && (i == 0 || !contact[i - 1])) out.emplace_back(t, t);
      if (contact[i] && !out.empty()) out.back().second = t;
    }
    return out;
  }
};

/// Per-whisker evaluation: the three modes fed the same samples.
struct WhiskerEval {
  std::string ns;
  std::array<std::shared_ptr<tdorc_filter::TdorcFilterLogic>, 3> filters;
  std::array<Counts, 3> counts;
  const Truth* truth = nullptr;
  // Plot series.
  std::vector<double> t;
  std::array<std::vector<double>, 3> raw;
  std::array<std::array<std::vector<double>, 3>, 3> sp;  // [mode][channel]
  std::array<double, 3> raw0{};
  bool have_raw0 = false;
};

std::string namespace_of(const std::string& topic, const std::string& leaf) {
  const std::string suffix = "/" + leaf;
  if (topic.size() > suffix.size() && topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) == 0) {
    return topic.substr(0, topic.size() - suffix.size());
  }
  return "";
}

void write_json(const fs::path& path, const nlohmann::json& j) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace

nlohmann::json run_replay(const ReplayOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  tactile_bag::Reader in(options.bag);

  // Raw pressure topics (one namespace per whisker) and optional ground truth.
  std::vector<std::pair<std::string, std::string>> whiskers;  // (topic, namespace)
  std::map<std::string, std::string> truth_topics;            // namespace -> topic
  Warnings warnings;
  warnings.add_bag_metadata(options.bag, in);
  const std::string pressure_type = tactile_msgs::cdr::MessageTraits<WhiskerPressure>::type_name;
  const std::string truth_type = tactile_msgs::cdr::MessageTraits<WhiskerGroundTruth>::type_name;
  std::vector<std::string> skipped;  // "topic (type)"
  for (const auto& t : in.topics()) {
    // A whisker's pressure topic (<namespace>/pressure) or a ground-truth
    // contact topic of another type is skipped, and said so.
    if (t.type != pressure_type && !namespace_of(t.name, "pressure").empty()) {
      skipped.push_back(t.name + " (type " + t.type + ", expected " + pressure_type + ")");
    } else if (t.type != truth_type && t.name.find("/ground_truth/") != std::string::npos &&
               !namespace_of(t.name, "contact").empty()) {
      skipped.push_back(t.name + " (type " + t.type + ", expected " + truth_type + ")");
    }
    if (t.type == pressure_type) {
      std::string ns = namespace_of(t.name, "pressure");
      if (ns.empty()) {
        throw std::runtime_error(options.bag + ": topic " + t.name +
                                 " holds WhiskerPressure but is not named <namespace>/pressure");
      }
      whiskers.emplace_back(t.name, ns);
    } else if (t.type == tactile_msgs::cdr::MessageTraits<WhiskerGroundTruth>::type_name) {
      // /ground_truth/whisker/left/contact -> /whisker/left; in a vehicle namespace (a
      // launch's bag) /cf1/ground_truth/whisker/left/contact -> /cf1/whisker/left.
      std::string ns = namespace_of(t.name, "contact");
      const std::string segment = "/ground_truth";
      const size_t at = (ns + "/").find(segment + "/");
      if (at != std::string::npos) {
        truth_topics[ns.substr(0, at) + ns.substr(at + segment.size())] = t.name;
      } else {
        skipped.push_back(t.name + " (" + truth_type + " not named [/<vehicle>]/ground_truth/<namespace>/contact)");
      }
    }
  }
  if (whiskers.empty()) {
    std::string what = options.bag + ": no topic of type tactile_msgs/msg/WhiskerPressure";
    for (const auto& s : skipped) what += "; skipped " + s;
    throw std::runtime_error(what);
  }
  if (!skipped.empty()) {
    std::string what = "skipped " + std::to_string(skipped.size()) + " topic(s): ";
    for (size_t i = 0; i < skipped.size(); ++i) what += (i ? "; " : "") + skipped[i];
    what += "; replaying only";
    for (const auto& w : whiskers) what += " " + w.first;
    warnings.add("skipped_topic", skipped.size(), what);
  }

  std::map<std::string, Truth> truths;
  for (const auto& [ns, topic] : truth_topics) {
    tactile_bag::Reader tr(options.bag);
    tr.set_topic_filter({topic});
    tactile_bag::SerializedMessage m;
    Truth& truth = truths[ns];
    while (tr.read_next(m)) {
      const auto gt = tactile_bag::decode<WhiskerGroundTruth>(m);
      truth.stamp.push_back(tactile_common::from_stamp(gt.header.stamp));
      truth.contact.push_back(gt.contact);
    }
  }

  fs::create_directories(options.out_dir);
  Host host(options.config_dir);
  host.executor().set_time(in.start_time_ns());
  BagRecorder recorder((fs::path(options.out_dir) / "bag").string(), BagRecorder::Commit::kReproducible);
  host.bus().add_tap(&recorder);

  std::vector<std::shared_ptr<whisker_driver::WhiskerDriverLogic>> drivers;
  std::vector<std::unique_ptr<WhiskerEval>> evals;
  double contact_threshold = 0.0;
  bool absolute_threshold = false;
  for (const auto& [topic, ns] : whiskers) {
    drivers.push_back(add_whisker_driver(
        host, ns,
        overrides({{"source", std::string("bag")}, {"bag_path", options.bag}, {"bag_topic", topic}})));
    add_tdorc_filter(host, ns, {});

    // Evaluation: the three modes side by side on the same raw samples.
    auto eval = std::make_unique<WhiskerEval>();
    eval->ns = ns;
    auto it = truths.find(ns);
    eval->truth = it == truths.end() ? nullptr : &it->second;
    using Logic = tdorc_filter::TdorcFilterLogic;
    for (size_t m = 0; m < kModes.size(); ++m) {
      auto params = host.load_parameters(ns, Logic::kNodeName, Logic::default_parameters(),
                                         overrides({{"mode", std::string(kModes[m])}}));
      auto p = Logic::params_from(params);
      contact_threshold = p.tdorc.contact_threshold;
      absolute_threshold = p.tdorc.absolute_threshold;
      eval->filters[m] = std::make_shared<Logic>(p);
    }
    WhiskerEval* e = eval.get();
    Host* h = &host;
    host.bus().subscribe<WhiskerPressure>(topic, [e, h, &in](const WhiskerPressure& msg) {
      std::array<std::optional<WhiskerSignal>, 3> out;
      const int64_t now = h->executor().now_ns();  // receive time, as tdorc_filter gets it
      for (size_t m = 0; m < 3; ++m) out[m] = e->filters[m]->on_pressure(msg, now);
      if (!out[0] || !out[1] || !out[2]) return;  // dropped (counted by the filters)
      const int64_t stamp = tactile_common::from_stamp(out[2]->header.stamp);
      const bool truth_contact = e->truth ? e->truth->at(stamp) : false;
      const bool all_ready = out[0]->calibrated_ready && out[1]->calibrated_ready && out[2]->calibrated_ready;
      for (size_t m = 0; m < 3; ++m) {
        Counts& c = e->counts[m];
        if (truth_contact) {
          ++c.true_contact_samples;
          if (out[m]->contact) {
            ++c.detected_contact_samples;
            c.detected = true;
          }
        } else if (all_ready) {
          for (size_t ch = 0; ch < 3; ++ch) (out[m]->channel_contact[ch] ? c.fp : c.tn)++;
          if (!e->truth && out[m]->contact) c.detected = true;
        }
      }
      if (!e->have_raw0) {
        for (size_t ch = 0; ch < 3; ++ch) e->raw0[ch] = msg.pressure[ch];
        e->have_raw0 = true;
      }
      e->t.push_back(tactile_common::to_seconds(stamp - in.start_time_ns()));
      for (size_t ch = 0; ch < 3; ++ch) {
        e->raw[ch].push_back(msg.pressure[ch] - e->raw0[ch]);
        for (size_t m = 0; m < 3; ++m) {
          e->sp[m][ch].push_back(out[m]->calibrated_ready ? out[m]->compensated[ch] : std::nan(""));
        }
      }
    });
    evals.push_back(std::move(eval));
  }

  // Stop when every bag source is drained (checked at the driver rate).
  Executor& ex = host.executor();
  ex.add_timer(
      tactile_common::from_seconds(0.02),
      [&drivers, &ex](int64_t) {
        if (std::all_of(drivers.begin(), drivers.end(), [](const auto& d) { return d->finished(); })) ex.stop();
      },
      ex.now_ns());
  ex.run_until(in.end_time_ns() + tactile_common::kNanosPerSecond);
  recorder.close();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  // Metrics.
  nlohmann::json metrics;
  metrics["input_bag"] = options.bag;
  metrics["contact_threshold"] = contact_threshold;
  metrics["absolute_threshold"] = absolute_threshold;
  metrics["fpr_basis"] = truths.empty()
                             ? "every (sample, channel) pair: the bag has no ground truth and is taken as free flight"
                             : "(sample, channel) pairs where the bag's ground truth says no contact";
  uint64_t raw_messages = 0;
  for (const auto& [topic, ns] : whiskers) raw_messages += in.message_count(topic);
  metrics["raw_messages"] = raw_messages;
  metrics["sim_time_s"] = tactile_common::to_seconds(in.duration_ns());
  metrics["wall_time_s"] = wall_s;
  metrics["messages_per_second"] = wall_s > 0 ? static_cast<double>(raw_messages) / wall_s : 0.0;
  bool any_truth_contact = false;
  for (size_t m = 0; m < kModes.size(); ++m) {
    Counts total;
    nlohmann::json per;
    for (const auto& e : evals) {
      const Counts& c = e->counts[m];
      total.fp += c.fp;
      total.tn += c.tn;
      total.detected |= c.detected;
      total.true_contact_samples += c.true_contact_samples;
      total.detected_contact_samples += c.detected_contact_samples;
      per[e->ns] = {{"false_positives", c.fp}, {"true_negatives", c.tn}, {"fpr", c.fpr()},
                    {"contact_detected", c.detected},
                    {"true_contact_samples", c.true_contact_samples},
                    {"detected_contact_samples", c.detected_contact_samples}};
    }
    any_truth_contact |= total.true_contact_samples > 0;
    metrics[std::string("fpr_") + kModes[m]] = total.fpr();
    metrics["modes"][kModes[m]] = {{"false_positives", total.fp}, {"true_negatives", total.tn},
                                   {"fpr", total.fpr()}, {"contact_detected", total.detected},
                                   {"whiskers", per}};
  }
  metrics["ground_truth"] = !truths.empty();
  metrics["ground_truth_contact"] = any_truth_contact;
  metrics["contact_detected"] = metrics["modes"]["tdorc"]["contact_detected"];
  for (const auto& r : host.reports()) {
    for (const auto& [k, v] : r.counters) metrics["nodes"][r.name][k] = v;
  }
  for (const auto& [topic, n] : host.bus().published_counts()) metrics["output_topics"][topic] = n;
  warnings.add_node_counters(host.reports());
  metrics["warnings"] = warnings.to_json();
  warnings.print("replay");
  write_json(fs::path(options.out_dir) / "metrics.json", metrics);

  if (options.write_png) {
    static const Rgb colors[6] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},
                                  {148, 103, 189}, {140, 86, 75}, {227, 119, 194}};
    std::vector<Panel> panels(4);
    panels[0].title = "raw pressure minus first sample";
    panels[0].y_label = "Pa";
    const char* titles[3] = {"band-pass only (000 eq. 9-11)", "TDOC: drift fitted once, then band-pass",
                             "TDORC: drift re-fitted in free flight (000 eq. 4-11)"};
    for (size_t m = 0; m < 3; ++m) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s   FPR = %.2f %%", titles[m], 100.0 * metrics["modes"][kModes[m]]["fpr"].get<double>());
      panels[m + 1].title = buf;
      panels[m + 1].y_label = "S_p [Pa]";
      panels[m + 1].horizontal_lines = {contact_threshold};
      if (absolute_threshold) panels[m + 1].horizontal_lines.push_back(-contact_threshold);
    }
    size_t color = 0;
    for (const auto& e : evals) {
      const std::string side = e->ns.substr(e->ns.rfind('/') + 1);
      for (size_t ch = 0; ch < 3; ++ch, ++color) {
        const std::string label = side + " ch" + std::to_string(ch + 1);
        panels[0].series.push_back({label, e->t, e->raw[ch], colors[color % 6]});
        for (size_t m = 0; m < 3; ++m) panels[m + 1].series.push_back({label, e->t, e->sp[m][ch], colors[color % 6]});
      }
      if (e->truth) {
        for (auto& p : panels) {
          for (const auto& s : e->truth->spans(in.start_time_ns())) p.spans.push_back(s);
        }
      }
    }
    write_plot_png((fs::path(options.out_dir) / "signals.png").string(), panels, "time [s]");
  }
  return metrics;
}

}  // namespace tactile_cli
