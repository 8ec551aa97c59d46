#include "tactile_cli/sim_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <algorithm>

#include "tactile_cli/host.hpp"
#include "tactile_cli/host_nodes.hpp"
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
  std::ostringstream os;
  os << "t,x,y,z,yaw,vx,vy,vz,est_x,est_y,est_z,est_yaw\n";
  os << std::setprecision(9);
  for (const auto& p : sim.trajectory()) {
    const auto& x = p.truth;
    const auto& e = p.estimate;
    os << p.t << ',' << x.position.x() << ',' << x.position.y() << ',' << x.position.z() << ',' << x.yaw()
       << ',' << x.velocity.x() << ',' << x.velocity.y() << ',' << x.velocity.z() << ',' << e.position.x()
       << ',' << e.position.y() << ',' << e.position.z() << ',' << e.yaw() << '\n';
  }
  write_text(path, os.str());
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

/// The scenario's parameter overrides of node `name` (node_parameters.<name>),
/// plus `extra`; the source names the scenario file so errors point at it.
tactile_common::ParamMap node_overrides(const Scenario& scenario, const std::string& name,
                                        const tactile_common::ParamMap& extra = {}) {
  tactile_common::ParamMap m(name, scenario.source + " (node_parameters." + name + ")");
  if (auto it = scenario.node_parameters.find(name); it != scenario.node_parameters.end()) {
    for (const auto& [k, v] : it->second) m.set(k, v);
  }
  for (const auto& [k, v] : extra.values()) m.set(k, v);
  return m;
}

/// A boolean setting of the scenario's metrics section (false if absent).
bool metric_flag(const Scenario& scenario, const char* key) {
  auto it = scenario.metrics.find(key);
  if (it == scenario.metrics.end()) return false;
  const bool* b = std::get_if<bool>(&it->second);
  if (!b) throw std::runtime_error(scenario.source + ": metrics." + key + ": expected true or false");
  return *b;
}

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
  fs::create_directories(dir);
  Host host(options.config_dir);
  std::unique_ptr<BagRecorder> recorder;
  if (options.write_bag) {
    recorder = std::make_unique<BagRecorder>((dir / "bag").string());
    host.bus().add_tap(recorder.get());
  }
  add_tactile_sim(host, sim);
  for (const auto& [name, params] : scenario.node_parameters) {
    static const char* kNodes[] = {"tdorc_filter", "tactile_depth", "whisker_fsm"};
    if (std::none_of(std::begin(kNodes), std::end(kNodes), [&](const char* n) { return name == n; })) {
      throw std::runtime_error(scenario.source + ": node_parameters." + name +
                               ": no such node in the graphs of tactile sim (tdorc_filter, tactile_depth, whisker_fsm)");
    }
  }
  const bool whisker = scenario.vehicle == tactile_sim::VehicleType::kWhiskerCrazyflie;
  const bool depth_evaluation = metric_flag(scenario, "depth_evaluation");
  if (whisker && scenario.graph != "none") {
    // The whisker signal chain (the pilot's 'until: contact' and the FSM listen to it).
    add_tdorc_filter(host, "whisker/left", node_overrides(scenario, "tdorc_filter"));
    add_tdorc_filter(host, "whisker/right", node_overrides(scenario, "tdorc_filter"));
  }
  std::unique_ptr<WhiskerTruth> truth;
  if (whisker) truth = std::make_unique<WhiskerTruth>(host);
  std::unique_ptr<DepthEvaluation> depth_eval;
  if (depth_evaluation) {
    if (!whisker) throw std::runtime_error(scenario.source + ": metrics.depth_evaluation: needs the whiskered Crazyflie");
    depth_eval = std::make_unique<DepthEvaluation>(host, *truth, sim->arena(), node_overrides(scenario, "tactile_depth"));
  }
  std::shared_ptr<tactile_sim::ScriptedPilotLogic> pilot;
  if (scenario.graph == "pilot") {
    pilot = std::make_shared<tactile_sim::ScriptedPilotLogic>(scenario.pilot, scenario.vehicle,
                                                               scenario.initial_position, scenario.initial_yaw);
    add_scenario_pilot(host, pilot);
  }
  std::shared_ptr<tactile_fsm::WhiskerFsmLogic> fsm;
  std::unique_ptr<WallFollowingEvaluation> wall_eval;
  if (scenario.graph == "whisker_fsm") {
    add_tactile_depth(host, node_overrides(scenario, "tactile_depth"));
    // The scenario's target (metrics.target: [x, y] in the arena frame, moved
    // with the arena's transform and trial rotation) is the FSM's landing target.
    tactile_common::ParamMap fsm_over;
    if (auto it = scenario.metrics.find("target"); it != scenario.metrics.end()) {
      const auto* xy = std::get_if<std::vector<double>>(&it->second);
      if (!xy || xy->size() != 2) throw std::runtime_error(scenario.source + ": metrics.target: expected [x, y]");
      const double c0 = std::cos(arena_yaw), s0 = std::sin(arena_yaw);
      tactile_sim::Vec2 t(c0 * (*xy)[0] - s0 * (*xy)[1], s0 * (*xy)[0] + c0 * (*xy)[1]);
      const double c1 = std::cos(scenario.arena_yaw), s1 = std::sin(scenario.arena_yaw);
      t = tactile_sim::Vec2(c1 * t.x() - s1 * t.y() + scenario.arena_x, s1 * t.x() + c1 * t.y() + scenario.arena_y);
      fsm_over.set("target_x", t.x());
      fsm_over.set("target_y", t.y());
    }
    fsm = add_whisker_fsm(host, node_overrides(scenario, "whisker_fsm", fsm_over));
    const auto& fp = fsm->params().fsm;
    wall_eval = std::make_unique<WallFollowingEvaluation>(host, *truth, fp.t_min, fp.t_max, fp.whisker_spacing);
  }

  Progress progress{options.progress, label, scenario.duration_s};
  host.executor().add_timer(tactile_common::from_seconds(0.1),
                            [&progress](int64_t now) { progress.update(tactile_common::to_seconds(now)); });
  host.executor().run_until(tactile_common::from_seconds(scenario.duration_s) + sim->period_ns());
  progress.done();
  if (recorder) recorder->close();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double sim_s = tactile_common::to_seconds(host.executor().now_ns());

  nlohmann::json m;
  m["scenario"] = scenario.name;
  m["scenario_file"] = scenario.source;
  m["vehicle"] = tactile_sim::to_string(scenario.vehicle);
  m["seed"] = seed;
  m["arena_yaw_deg"] = (scenario.arena_yaw + arena_yaw) * 180.0 / M_PI;
  m["sim_time_s"] = sim_s;
  m["wall_time_s"] = wall_s;
  m["real_time_factor"] = wall_s > 0 ? sim_s / wall_s : 0.0;
  m["physics_rate_hz"] = scenario.physics_rate_hz;
  m["collisions"] = sim->collisions().size();
  for (const auto& c : sim->collisions()) {
    m["collision_events"].push_back({{"t", c.time_s}, {"part", c.part}, {"x", c.point.x()}, {"y", c.point.y()},
                                     {"impact_speed", c.impact_speed}, {"obstacle_id", c.obstacle_id}});
  }
  for (const auto& [k, v] : sim->summary()) {
    m["ground_truth"][k] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  }
  if (pilot) {
    const auto& ps = pilot->stats();
    m["pilot"] = {{"finished", ps.finished},
                  {"steps", scenario.pilot.size()},
                  {"steps_completed", ps.steps_completed},
                  {"steps_timed_out", ps.steps_timed_out},
                  {"contact_time_s", std::isfinite(ps.contact_time_s) ? nlohmann::json(ps.contact_time_s)
                                                                      : nlohmann::json(nullptr)}};
  }
  // Success: the pilot flew its whole script (no 'until' timed out) without
  // impacts, unless the scenario flies a collision-resilient vehicle into
  // contact on purpose (metrics: {allow_collisions: true}, XPLORER).
  const bool allow_collisions = metric_flag(scenario, "allow_collisions");
  bool flew = !pilot || (pilot->stats().finished && pilot->stats().steps_timed_out == 0);
  if (fsm) {
    // The FSM reached its target (000 Methods: land when the target is reached).
    const auto state = fsm->fsm().state();
    flew = state == tactile_fsm::FsmState::kLanding || state == tactile_fsm::FsmState::kLanded;
    m["fsm"] = wall_eval->metrics();
    m["fsm"]["target"] = {fsm->params().target_x, fsm->params().target_y};
    m["fsm"]["reached_target"] = flew;
  }
  if (depth_eval) m["depth"] = depth_eval->metrics();
  m["success"] = flew && (allow_collisions || sim->collisions().empty());
  for (const auto& [k, v] : sim->fault_counts()) m["faults_injected"][k] = v;
  for (const auto& r : host.reports()) {
    for (const auto& [k, v] : r.counters) m["nodes"][r.name][k] = v;
  }
  for (const auto& [topic, n] : host.bus().published_counts()) m["topics"][topic] = n;

  write_trajectory_csv(dir / "trajectory.csv", *sim);
  write_text(dir / "metrics.json", m.dump(2) + "\n");
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
  std::vector<nlohmann::json> runs;
  const auto wall_start = std::chrono::steady_clock::now();
  for (int k = 0; k < options.trials; ++k) {
    const uint64_t seed = seed0 + static_cast<uint64_t>(k);
    const std::string label = scenario.name + " trial " + std::to_string(k + 1) + "/" + std::to_string(options.trials);
    runs.push_back(run_once(scenario, options, seed, fs::path(options.out_dir) / ("trial_" + std::to_string(k)), label));
  }
  nlohmann::json agg;
  agg["scenario"] = scenario.name;
  agg["trials"] = options.trials;
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
  agg["statistics"] = stats;
  agg["per_trial"] = runs;
  write_text(fs::path(options.out_dir) / "metrics.json", agg.dump(2) + "\n");
  return agg;
}

}  // namespace tactile_cli
