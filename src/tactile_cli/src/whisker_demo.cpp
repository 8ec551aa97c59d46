#include "tactile_cli/whisker_demo.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/whisker_replay.hpp"
#include "tactile_common/time.hpp"
#include "tactile_msgs/msg/whisker_ground_truth.hpp"

namespace tactile_cli {

namespace fs = std::filesystem;

void record_sim_whisker_bag(const std::string& bag_dir, const std::string& config_dir, uint64_t seed,
                            double hover_s, const std::vector<double>& contact_start_s,
                            const std::vector<double>& contact_duration_s,
                            const std::vector<double>& contact_peak_nm) {
  Host host(config_dir);
  BagRecorder recorder(bag_dir, BagRecorder::Commit::kReproducible);
  host.bus().add_tap(&recorder);
  double end_s = 0.0;
  int64_t side_index = 0;
  for (const char* ns : {"whisker/left", "whisker/right"}) {
    // whisker_id, frame_id come from the per-whisker sections of
    // config/whisker_driver.yaml, as in the launch files.
    auto driver = add_whisker_driver(
        host, ns,
        overrides({{"source", std::string("sim")},
                   // Each whisker's barometers get their own noise stream.
                   {"sim_seed", static_cast<int64_t>(seed * 2) + side_index++},
                   // The recording starts at take-off, like the paper's
                   // free-flight logs (TDOC then fits right after take-off).
                   {"sim_takeoff_s", 0.0},
                   {"sim_hover_s", hover_s},
                   {"sim_contact_start_s", contact_start_s},
                   {"sim_contact_duration_s", contact_duration_s},
                   {"sim_contact_peak_nm", contact_peak_nm}}));
    // Ground truth of the scripted flight, stamped like the driver's samples.
    const auto& p = driver->params();
    whisker_driver::SimScenario scenario;
    scenario.takeoff_s = p.sim_takeoff_s;
    scenario.hover_s = p.sim_hover_s;
    for (size_t i = 0; i < p.sim_contact_start_s.size(); ++i) {
      scenario.contacts.push_back(
          {p.sim_contact_start_s[i], p.sim_contact_duration_s[i], p.sim_contact_peak_nm[i]});
    }
    end_s = std::max(end_s, p.sim_takeoff_s + p.sim_hover_s);
    const std::string topic = resolve_topic("/ground_truth", std::string(ns) + "/contact");
    Host* h = &host;
    const uint8_t id = static_cast<uint8_t>(p.whisker_id);
    const std::string frame = p.frame_id;
    host.executor().add_timer(driver->period_ns(), [h, scenario, topic, id, frame](int64_t now_ns) {
      tactile_msgs::msg::WhiskerGroundTruth gt;
      tactile_common::to_stamp(now_ns, gt.header.stamp);
      gt.header.frame_id = frame;
      gt.whisker_id = id;
      const double t = tactile_common::to_seconds(now_ns);
      gt.load = scenario.load(t);
      gt.contact = gt.load > 0.0;
      gt.depth = std::nan("");  // the signal model takes a load, not a geometry
      gt.motors_on = scenario.motors_on(t);
      h->bus().publish(topic, gt, now_ns);
    });
  }
  // The last sample is at end_s - one period (hover ends, motors stop).
  host.executor().run_until(tactile_common::from_seconds(end_s) - 1);
  recorder.close();
}

nlohmann::json run_whisker_demo(const DemoOptions& options) {
  fs::create_directories(options.out_dir);
  struct Case {
    const char* name;
    std::vector<double> start, duration, peak;
  };
  // One contact episode: 2 s on both whiskers (the 2 s sweep of the 000
  // data-collection protocol), a third of the way into the hover.
  const double contact_start_s = options.hover_s / 3.0;
  const Case cases[] = {
      {"free_flight", {}, {}, {}},
      {"contact", {contact_start_s}, {2.0}, {2e-4}},
  };
  nlohmann::json summary;
  for (const auto& c : cases) {
    const fs::path dir = fs::path(options.out_dir) / c.name;
    fs::create_directories(dir);
    const std::string raw = (dir / "raw_bag").string();
    std::printf("[demo] %s: simulating %.0f s of flight -> %s\n", c.name, options.hover_s, raw.c_str());
    std::fflush(stdout);
    record_sim_whisker_bag(raw, options.config_dir, options.seed, options.hover_s, c.start, c.duration, c.peak);
    std::printf("[demo] %s: replaying driver -> TDORC -> %s\n", c.name, dir.string().c_str());
    std::fflush(stdout);
    ReplayOptions ro;
    ro.bag = raw;
    ro.out_dir = dir.string();
    ro.config_dir = options.config_dir;
    const auto m = run_replay(ro);
    summary[c.name] = {{"fpr_bandpass", m["fpr_bandpass"]}, {"fpr_tdoc", m["fpr_tdoc"]},
                       {"fpr_tdorc", m["fpr_tdorc"]}, {"contact_detected", m["contact_detected"]},
                       {"ground_truth_contact", m["ground_truth_contact"]},
                       {"metrics", (dir / "metrics.json").string()},
                       {"plot", (dir / "signals.png").string()}};
  }
  std::ofstream out(fs::path(options.out_dir) / "summary.json");
  out << summary.dump(2) << "\n";
  return summary;
}

}  // namespace tactile_cli
