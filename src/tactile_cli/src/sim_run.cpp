#include "tactile_cli/sim_run.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <random>
#include <sstream>
#include <algorithm>

#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/interrupt.hpp"
#include "tactile_cli/parallel.hpp"
#include "tactile_cli/sim_graph.hpp"
#include "tactile_cli/topview.hpp"
#include "tactile_cli/whisker_eval.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

namespace {

namespace fs = std::filesystem;
using tactile_sim::Scenario;

constexpr uint64_t kStreamTrialYaw = 30;  // tactile_sim stream id of the trial's arena rotation

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

void write_trajectory_csv(const fs::path& path, const tactile_sim::SimLogic& sim) {
  // std::to_chars with a precision formats as printf's %.9g, which is what an ostream with
  // setprecision(9) writes, at a fraction of the cost (7,500 rows per 75 s run).
  std::string text = "t,x,y,z,yaw,vx,vy,vz,est_x,est_y,est_z,est_yaw\n";
  text.reserve(sim.trajectory().size() * 160 + text.size());
  char buf[32];
  auto field = [&](double v, char sep) {
    const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9);
    text.append(buf, r.ptr);
    text.push_back(sep);
  };
  for (const auto& p : sim.trajectory()) {
    const auto& x = p.truth;
    const auto& e = p.estimate;
    field(p.t, ',');
    field(x.position.x(), ',');
    field(x.position.y(), ',');
    field(x.position.z(), ',');
    field(x.yaw(), ',');
    field(x.velocity.x(), ',');
    field(x.velocity.y(), ',');
    field(x.velocity.z(), ',');
    field(e.position.x(), ',');
    field(e.position.y(), ',');
    field(e.position.z(), ',');
    field(e.yaw(), '\n');
  }
  write_text(path, text);
}

struct Progress {
  bool enabled;
  std::string label;
  double duration_s;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  int last_percent = -1;
  void update(double sim_s) {
    if (!enabled) return;
    const int percent = static_cast<int>(100.0 * sim_s / duration_s);
    if (percent == last_percent || percent % 5 != 0) return;
    last_percent = percent;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "\r[sim] %s: %3d %% (%.1f / %.1f s simulated, %.0fx real time)   ", label.c_str(),
                 percent, sim_s, duration_s, wall > 0 ? sim_s / wall : 0.0);
    std::fflush(stderr);
  }
  void done() {
    if (enabled) std::fprintf(stderr, "\n");
  }
};

/// One run of the scenario into `dir`.
nlohmann::json run_once(const Scenario& scenario, const SimOptions& options, uint64_t seed, const fs::path& dir,
                        const std::string& label) {
  const auto wall_start = std::chrono::steady_clock::now();
  double arena_yaw = 0.0;
  if (scenario.randomize_arena_yaw) {
    tactile_sim::Rng rng(tactile_sim::stream_seed(seed, kStreamTrialYaw));
    arena_yaw = std::uniform_real_distribution<double>(scenario.randomize_arena_yaw->first,
                                                       scenario.randomize_arena_yaw->second)(rng);
  }
  // The world first: a bad arena, vehicle parameter or fault stops the run
  // before anything is written.
  auto sim = std::make_shared<tactile_sim::SimLogic>(scenario, seed, arena_yaw);
  const GraphInfo& info = find_sim_graph(scenario.graph, scenario.source);
  if (!info.vehicles.empty() &&
      std::find(info.vehicles.begin(), info.vehicles.end(), scenario.vehicle) == info.vehicles.end()) {
    throw std::runtime_error(scenario.source + ": graph: '" + info.name + "' cannot fly the " +
                             tactile_sim::to_string(scenario.vehicle) + " (" + info.description + ")");
  }
  for (const auto& [name, params] : scenario.node_parameters) {
    if (std::find(info.nodes.begin(), info.nodes.end(), name) == info.nodes.end()) {
      std::string known;
      for (const auto& n : info.nodes) known += (known.empty() ? "" : ", ") + n;
      throw std::runtime_error(scenario.source + ": node_parameters." + name + ": no such node in graph '" +
                               info.name + "' (" + (known.empty() ? "it has no configurable nodes" : known) + ")");
    }
  }
  fs::create_directories(dir);
  Host host(options.config_dir);
  for (const auto& profile : options.profiles) host.use_profile(profile);
  std::unique_ptr<BagRecorder> recorder;
  if (options.write_bag) {
    recorder = std::make_unique<BagRecorder>((dir / "bag").string(), BagRecorder::Commit::kReproducible);
    host.bus().add_tap(recorder.get());
  }
  add_tactile_sim(host, sim);
  const bool whisker = scenario.vehicle == tactile_sim::VehicleType::kWhiskerCrazyflie;
  std::unique_ptr<WhiskerTruth> truth;
  if (whisker) truth = std::make_unique<WhiskerTruth>(host);
  GraphContext ctx{scenario, host, sim, seed, arena_yaw, dir, truth.get()};
  std::unique_ptr<DepthEvaluation> depth_eval;
  std::unique_ptr<SimGraph> graph;
  try {
    if (ctx.flag("depth_evaluation")) {
      if (!whisker) throw std::runtime_error(scenario.source + ": metrics.depth_evaluation: needs the whiskered Crazyflie");
      depth_eval = std::make_unique<DepthEvaluation>(host, *truth, sim->arena(), ctx.overrides("tactile_depth"));
    }
    graph = info.build(ctx);  // a bad node parameter stops here
  } catch (...) {
    // Nothing was flown: take back the bag this run opened (it holds no message), so
    // the same command with the scenario mended does not stop on "bag directory
    // exists and is not empty".
    if (recorder) {
      recorder->close();
      std::error_code ec;
      fs::remove_all(dir / "bag", ec);
    }
    throw;
  }

  Progress progress{options.progress, label, scenario.duration_s};
  // The progress tick also checks for Ctrl-C / SIGTERM (one timer, so the schedule of the
  // graph's own timers is the same with or without a signal scope).
  host.executor().add_timer(tactile_common::from_seconds(0.1), [&progress, &host](int64_t now) {
    progress.update(tactile_common::to_seconds(now));
    if (interrupt_requested()) host.executor().stop();
  });
  host.executor().run_until(tactile_common::from_seconds(scenario.duration_s) + sim->period_ns());
  const bool interrupted = interrupt_requested();
  progress.done();
  if (recorder) recorder->close();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double sim_s = tactile_common::to_seconds(host.executor().now_ns());

  nlohmann::json m;
  m["scenario"] = scenario.name;
  m["profiles"] = host.profiles();  // the parameter profiles applied (files), the graph's first
  m["scenario_file"] = scenario.source;
  m["vehicle"] = tactile_sim::to_string(scenario.vehicle);
  m["seed"] = seed;
  m["arena_yaw_deg"] = (scenario.arena_yaw + arena_yaw) * 180.0 / M_PI;
  m["sim_time_s"] = sim_s;
  m["wall_time_s"] = wall_s;
  // A signal stopped the flight before duration_s: the metrics describe it up to sim_time_s.
  m["interrupted"] = interrupted;
  m["real_time_factor"] = wall_s > 0 ? sim_s / wall_s : 0.0;
  m["physics_rate_hz"] = scenario.physics_rate_hz;
  m["collisions"] = sim->collisions().size();
  m["collision_events"] = nlohmann::json::array();  // present (empty) without collisions too
  for (const auto& c : sim->collisions()) {
    m["collision_events"].push_back({{"t", c.time_s}, {"part", c.part}, {"x", c.point.x()}, {"y", c.point.y()},
                                     {"impact_speed", c.impact_speed}, {"obstacle_id", c.obstacle_id}});
  }
  for (const auto& [k, v] : sim->summary()) {
    m["ground_truth"][k] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  }
  // Success: the graph reached its goal (or has none) without impacts, unless
  // the scenario flies a collision-resilient vehicle into contact on purpose
  // (metrics: {allow_collisions: true}, XPLORER).
  const bool allow_collisions = ctx.flag("allow_collisions");
  const bool reached = graph->reached_goal().value_or(true);
  if (auto gm = graph->metrics(); !gm.is_null()) m[info.metrics_key] = gm;
  if (depth_eval) m["depth"] = depth_eval->metrics();
  m["graph"] = info.name;
  m["success"] = !interrupted && reached && (allow_collisions || sim->collisions().empty());
  for (const auto& [k, v] : sim->fault_counts()) m["faults_injected"][k] = v;
  for (const auto& r : host.reports()) {
    for (const auto& [k, v] : r.counters) m["nodes"][r.name][k] = v;
  }
  for (const auto& [topic, n] : host.bus().published_counts()) m["topics"][topic] = n;

  write_trajectory_csv(dir / "trajectory.csv", *sim);
  write_text(dir / "metrics.json", m.dump(2) + "\n");
  graph->write_outputs(dir);
  if (options.write_png) {
    TopView view;
    view.arena = &sim->arena();
    for (const auto& p : sim->trajectory()) {
      view.trajectory.push_back(p.truth.position.head<2>());
      view.estimate_trajectory.push_back(p.estimate.position.head<2>());
    }
    view.whisker_contacts = sim->whisker_contacts();
    for (const auto& c : sim->collisions()) view.collisions.push_back(c.point);
    const auto& traj = sim->trajectory();
    for (size_t i = 0; i < traj.size(); i += std::max<size_t>(1, traj.size() / 6)) {
      view.poses.emplace_back(traj[i].truth.position.head<2>(), traj[i].truth.yaw());
    }
    if (!traj.empty()) view.poses.emplace_back(traj.back().truth.position.head<2>(), traj.back().truth.yaw());
    char title[200];
    std::snprintf(title, sizeof title, "%s (%s, seed %llu): %zu collisions", scenario.name.c_str(),
                  tactile_sim::to_string(scenario.vehicle), static_cast<unsigned long long>(seed),
                  sim->collisions().size());
    view.title = title;
    graph->decorate(view);
    write_topview_png((dir / "topview.png").string(), view);
  }
  return m;
}

/// Mean / std / min / max of every numeric leaf over the trials.
void aggregate(const std::vector<nlohmann::json>& runs, const std::string& prefix, const nlohmann::json& first,
               nlohmann::json& out) {
  for (const auto& [key, value] : first.items()) {
    const std::string path = prefix.empty() ? key : prefix + "." + key;
    if (value.is_object()) {
      aggregate(runs, path, value, out);
      continue;
    }
    if (!value.is_number() && !value.is_boolean()) continue;
    std::vector<double> xs;
    for (const auto& r : runs) {
      const auto ptr = nlohmann::json::json_pointer("/" + [&] {
        std::string p = path;
        for (auto& c : p) if (c == '.') c = '/';
        return p;
      }());
      if (!r.contains(ptr)) continue;
      const auto& v = r.at(ptr);
      if (v.is_number()) xs.push_back(v.get<double>());
      if (v.is_boolean()) xs.push_back(v.get<bool>() ? 1.0 : 0.0);
    }
    if (xs.empty()) continue;
    double mean = 0.0;
    for (double x : xs) mean += x;
    mean /= static_cast<double>(xs.size());
    double var = 0.0;
    for (double x : xs) var += (x - mean) * (x - mean);
    const double sd = xs.size() > 1 ? std::sqrt(var / static_cast<double>(xs.size() - 1)) : 0.0;
    out[path] = {{"mean", mean}, {"std", sd}, {"min", *std::min_element(xs.begin(), xs.end())},
                 {"max", *std::max_element(xs.begin(), xs.end())}, {"n", xs.size()}};
  }
}

}  // namespace

nlohmann::json run_sim(const SimOptions& options) {
  if (options.trials < 1) throw std::invalid_argument("--trials must be >= 1");
  const Scenario scenario = tactile_sim::load_scenario(options.scenario);
  const uint64_t seed0 = options.seed.value_or(scenario.seed);
  fs::create_directories(options.out_dir);
  if (options.trials == 1) {
    return run_once(scenario, options, seed0, options.out_dir, scenario.name);
  }
  // Trials are independent (each its own host, simulator, seed streams and
  // directory): run them on the parallel runner, collected in seed order, so
  // every per-trial file and the aggregate equal those of a serial run.
  const auto wall_start = std::chrono::steady_clock::now();
  const size_t n = static_cast<size_t>(options.trials);
  const int workers = resolve_jobs(options.jobs, n);
  std::mutex progress_mu;
  size_t finished = 0;
  // After Ctrl-C / SIGTERM no trial starts; the running ones stop within 0.1 s of simulated
  // time and keep their directories (metrics marked interrupted); the aggregate is written
  // over the trials that finished, marked interrupted.
  const std::vector<nlohmann::json> all = parallel_map(n, workers, [&](size_t k) -> nlohmann::json {
    if (interrupt_requested()) return nullptr;
    const uint64_t seed = seed0 + static_cast<uint64_t>(k);
    const std::string label = scenario.name + " trial " + std::to_string(k + 1) + "/" + std::to_string(options.trials);
    SimOptions trial = options;
    trial.progress = options.progress && workers == 1;  // one live progress line at a time
    nlohmann::json m = run_once(scenario, trial, seed, fs::path(options.out_dir) / ("trial_" + std::to_string(k)), label);
    if (options.progress && workers > 1) {
      std::lock_guard<std::mutex> lk(progress_mu);
      ++finished;
      std::fprintf(stderr, "[sim] %s (seed %llu): %s, %.1f s simulated in %.2f s; %zu/%zu trials done (%d jobs)\n",
                   label.c_str(), static_cast<unsigned long long>(seed),
                   m["success"].get<bool>() ? "success" : "no success", m["sim_time_s"].get<double>(),
                   m["wall_time_s"].get<double>(), finished, n, workers);
    }
    return m;
  });
  std::vector<nlohmann::json> runs;
  for (const auto& r : all) {
    if (!r.is_null() && !r["interrupted"].get<bool>()) runs.push_back(r);
  }
  const bool interrupted = runs.size() < n;
  if (runs.empty()) {
    nlohmann::json agg = {{"scenario", scenario.name}, {"trials", options.trials}, {"trials_completed", 0},
                          {"interrupted", true}};
    write_text(fs::path(options.out_dir) / "metrics.json", agg.dump(2) + "\n");
    return agg;
  }
  nlohmann::json agg;
  agg["scenario"] = scenario.name;
  agg["trials"] = options.trials;
  agg["trials_completed"] = runs.size();
  agg["interrupted"] = interrupted;
  agg["seeds"] = nlohmann::json::array();
  int success = 0;
  double sim_total = 0.0;
  size_t collisions = 0;
  for (const auto& r : runs) {
    agg["seeds"].push_back(r["seed"]);
    success += r["success"].get<bool>() ? 1 : 0;
    sim_total += r["sim_time_s"].get<double>();
    collisions += r["collisions"].get<size_t>();
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  agg["success_count"] = success;
  agg["sim_time_s"] = sim_total;
  agg["wall_time_s"] = wall_s;
  agg["real_time_factor"] = wall_s > 0 ? sim_total / wall_s : 0.0;
  agg["collisions"] = collisions;
  nlohmann::json stats;
  aggregate(runs, "", runs.front(), stats);
  stats.erase("seed");
  stats.erase("interrupted");
  for (const std::string& path : find_sim_graph(scenario.graph, scenario.source).summary_metrics) {
    if (!stats.contains(path)) continue;  // no trial reported it
    const std::string leaf = path.substr(path.rfind('.') + 1);
    agg["mean_" + leaf] = stats[path]["mean"];
    agg["std_" + leaf] = stats[path]["std"];
  }
  agg["statistics"] = stats;
  agg["per_trial"] = runs;
  write_text(fs::path(options.out_dir) / "metrics.json", agg.dump(2) + "\n");
  return agg;
}

}  // namespace tactile_cli
