// The `tactile` command: standalone host of the workspace's node logic.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "tactile_cli/evaluate.hpp"
#include "tactile_cli/hardware.hpp"
#include "tactile_cli/host.hpp"
#include "tactile_cli/interrupt.hpp"
#include "tactile_cli/output_dir.hpp"
#include "tactile_cli/parallel.hpp"
#include "tactile_cli/param_schema.hpp"

#include "tactile_cli/scenario_family.hpp"
#include "tactile_cli/sim_run.hpp"
#include "tactile_cli/sweep.hpp"
#include "tactile_cli/xplorer_export.hpp"
#include "tactile_cli/whisker_demo.hpp"
#include "tactile_cli/whisker_replay.hpp"
#include "whisker_localization/protocols.hpp"

namespace {

void check_config_dir(const std::string& dir) {
  if (!std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir + ": configuration directory not found (pass --config DIR, e.g. the "
                                   "repository's config/)");
  }
}

void print_fpr(const nlohmann::json& m) {
  std::printf("  FPR band-pass %.2f %%, TDOC %.2f %%, TDORC %.2f %%; contact detected: %s\n",
              100.0 * m["fpr_bandpass"].get<double>(), 100.0 * m["fpr_tdoc"].get<double>(),
              100.0 * m["fpr_tdorc"].get<double>(), m["contact_detected"].get<bool>() ? "yes" : "no");
}

// Numbers on the command line are checked before they are converted: CLI11 reads "-1" into
// a uint64_t as 2^64 - 1, and a Range check lets NaN through (every comparison is false).
const CLI::Validator kWholeNumber(
    [](std::string& s) -> std::string {
      if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos) {
        return "expected a whole number >= 0, got '" + s + "'";
      }
      return {};
    },
    "UINT", "whole number");
CLI::Validator finite_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        double v = 0.0;
        try {
          size_t pos = 0;
          v = std::stod(s, &pos);
          if (pos != s.size()) throw std::invalid_argument(s);
        } catch (const std::exception&) {
          return "expected a number, got '" + s + "'";
        }
        if (!std::isfinite(v) || v < lo || v > hi) {
          return "must be a finite number in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) +
                 "], got '" + s + "'";
        }
        return {};
      },
      "[" + CLI::detail::to_string(lo) + " - " + CLI::detail::to_string(hi) + "]");
}
// Longest wall-clock run of fly / bench: one day [s] (our choice).
constexpr double kMaxWallDurationS = 86400.0;
// Most trials of one `tactile sim` (each keeps its directory in memory and on disk).
constexpr int kMaxTrials = 100000;

// --storage, --bag-distro, --bag-compression of the commands that record bags.
void add_bag_options(CLI::App* cmd, tactile_bag::WriterOptions& o) {
  cmd->add_option("--storage", o.storage, "bag storage (mcap: what ros2 bag record writes since Iron)")
      ->check(CLI::IsMember({"mcap", "sqlite3"}))
      ->capture_default_str();
  cmd->add_option("--bag-distro", o.ros_distro,
                  "ROS 2 distro the bag is for: message layouts, metadata version, type hashes")
      ->check(CLI::IsMember({"humble", "iron", "jazzy", "kilted"}))
      ->capture_default_str();
  cmd->add_option("--bag-compression", o.compression, "mcap chunk compression (default: none, as rosbag2)")
      ->check(CLI::IsMember({"zstd", "lz4"}));
}

}  // namespace

int main(int argc, char** argv) {
  // OpenBLAS's pool would spin ~0.1 s of CPU beside the trials (parallel.hpp).
  tactile_cli::release_blas_threads();
  CLI::App app{"tactile: standalone host of the tactile flight workspace (no ROS needed)"};
  app.require_subcommand(1);
  app.fallthrough();  // --config may follow the subcommand

  std::string config_dir = "config";
  app.add_option("--config", config_dir, "directory of the <node>.yaml parameter files")
      ->capture_default_str();
  std::vector<std::string> profiles;
  app.add_option("--profile", profiles,
                 "sim, sweep: apply the parameter profile <config>/profiles/NAME.yaml (e.g. paper: the papers' "
                 "values where the workspace ships others) after each node's file; repeatable, later ones win");

  tactile_cli::ReplayOptions replay;
  auto* replay_cmd = app.add_subcommand(
      "replay", "run whisker_driver -> tdorc_filter over a bag of raw whisker pressures");
  replay_cmd->add_option("bag", replay.bag, "input rosbag2 directory")->required();
  replay_cmd->add_option("--out", replay.out_dir, "output directory (bag/, metrics.json, signals.png)")
      ->required();
  replay_cmd->add_flag("!--no-png", replay.write_png, "do not draw signals.png");
  auto& bag_options = tactile_cli::BagRecorder::default_options();
  add_bag_options(replay_cmd, bag_options);

  tactile_cli::DemoOptions demo;
  auto* demo_cmd = app.add_subcommand(
      "demo", "whisker signal demo: simulate free flight and a contact, record bags, replay them");
  demo_cmd->add_option("--out", demo.out_dir, "output directory")->required();
  demo_cmd->add_option("--seed", demo.seed, "seed of the simulated barometers")->check(kWholeNumber)->capture_default_str();
  demo_cmd->add_option("--hover", demo.hover_s, "free-flight duration after take-off [s]")
      ->check(finite_in(0.1, 3600.0))
      ->capture_default_str();
  add_bag_options(demo_cmd, bag_options);

  tactile_cli::SimOptions sim;
  uint64_t sim_seed = 0;
  auto* sim_cmd = app.add_subcommand("sim", "fly a SITL scenario (config/scenarios/*.yaml)");
  sim_cmd->add_option("scenario", sim.scenario, "scenario file")->required();
  sim_cmd->add_option("--out", sim.out_dir, "output directory (bag/, trajectory.csv, metrics.json, topview.png)")
      ->required();
  auto* seed_opt = sim_cmd->add_option("--seed", sim_seed, "seed (default: the scenario's)")->check(kWholeNumber);
  sim_cmd->add_option("--trials", sim.trials, "number of seeded trials (seed, seed+1, ...)")
      ->check(CLI::Range(1, kMaxTrials))
      ->capture_default_str();
  sim_cmd->add_option("--jobs,-j", sim.jobs, "trials run at once on worker threads (0: all cores); outputs as a serial run")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sim_cmd->add_flag("!--no-bag", sim.write_bag, "do not record the bag");
  add_bag_options(sim_cmd, bag_options);
  sim_cmd->add_flag("!--no-png", sim.write_png, "do not draw topview.png");
  sim_cmd->add_flag("!--quiet", sim.progress, "no progress line");

  tactile_cli::FlyOptions fly;
  auto* fly_cmd = app.add_subcommand("fly", "whisker pipeline against a real or simulated Crazyflie (records a bag)");
  fly_cmd->add_option("--uri", fly.uri, "radio://0/80/2M/E7E7E7E7E7, usb://0, udp://127.0.0.1:19850 (default: crazyflie_bridge.yaml)");
  fly_cmd->add_option("--out", fly.out_dir, "output directory (bag/, metrics.json)")->required();
  fly_cmd->add_option("--duration", fly.duration_s, "pipeline run time before the bridge lands [s]")
      ->check(finite_in(0.0, kMaxWallDurationS))
      ->capture_default_str();
  auto* fly_scenario_opt =
      fly_cmd->add_option("--scenario", fly.scenario, "take node parameters and metrics.target from a scenario file");
  // --sim flies its own scenario's node parameters and target: a second scenario was ignored.
  fly_cmd->add_option("--sim", fly.sim_scenario, "fly the simulated Crazyflie of this scenario (in-process UDP server)")
      ->excludes(fly_scenario_opt);
  fly_cmd->add_option("--sim-loss", fly.sim_loss, "injected UDP packet loss of the simulated Crazyflie [0, 1)")
      ->check(finite_in(0.0, 0.99));
  fly_cmd->add_flag("--takeoff", fly.takeoff,
                    "take off (crazyflie_bridge.yaml takeoff_height) and hand over to the behaviour; without it "
                    "nothing flies: the link is checked and the sensors recorded");
  fly_cmd->add_option("--takeoff-height", fly.takeoff_height, "take-off height [m] (default: crazyflie_bridge.yaml)")
      ->check(finite_in(0.0, 3.0));
  fly_cmd->add_flag("--arm", fly.arm, "send the arming request before take-off (a Crazyflie that requires arming)");
  fly_cmd->add_flag("--autostart", fly.autostart,
                    "the behaviour flies as soon as the link is up, no take-off step (simulated Crazyflie tests)");
  fly.teleop = true;
  fly_cmd->add_flag("!--no-teleop", fly.teleop,
                    "no keystrokes (default when stdin is a terminal: t take off, l land, space emergency stop, a arm)");
  fly_cmd->add_flag("!--no-bag", fly.write_bag, "do not record the bag");
  add_bag_options(fly_cmd, bag_options);
  tactile_cli::BenchOptions bench;
  auto* bench_cmd = app.add_subcommand("bench", "whisker bench rig over serial: whisker_driver -> TDORC (records a bag)");
  bench_cmd->add_option("--port", bench.left_port, "serial device of whisker 1 (text protocol)")->capture_default_str();
  bench_cmd->add_option("--port2", bench.right_port, "serial device of whisker 2 (CSV protocol)");
  bench_cmd->add_option("--out", bench.out_dir, "output directory (bag/, metrics.json)")->required();
  bench_cmd->add_option("--duration", bench.duration_s, "[s]")
      ->check(finite_in(0.0, kMaxWallDurationS))
      ->capture_default_str();
  add_bag_options(bench_cmd, bag_options);
  std::string scan_host = "127.0.0.1";
  auto* scan_cmd = app.add_subcommand("scan", "list Crazyradios, Crazyflies on USB and simulated Crazyflies on UDP");
  scan_cmd->add_option("--udp-host", scan_host, "host of simulated Crazyflies (ports 19850-19859)")->capture_default_str();
  std::string stage_scenario, stage_out;
  uint64_t stage_seed = 0;
  auto* stage_cmd = app.add_subcommand(
      "stage", "paper 002 linear-stage bench protocol (config/scenarios/bench/*.yaml): Table I contact "
               "estimation or Table II sweep localization -> metrics.json");
  stage_cmd->add_option("scenario", stage_scenario, "bench scenario file")->required();
  stage_cmd->add_option("--out", stage_out, "output directory (metrics.json)")->required();
  auto* stage_seed_opt = stage_cmd->add_option("--seed", stage_seed, "seed (default: the scenario's)")->check(kWholeNumber);
  tactile_cli::ExportOptions exp;
  auto* export_cmd = app.add_subcommand("export", "rebuild the XPLORER contact map from a bag and write it as PLY (001)");
  export_cmd->add_option("bag", exp.bag, "input rosbag2 directory")->required();
  export_cmd->add_option("--ply", exp.ply, "output PLY file (frame: xplorer_mapping frame_id, odom by default; metres)")->required();
  export_cmd->add_flag("--binary", exp.binary, "binary little endian instead of ASCII");
  export_cmd->add_option("--namespace", exp.ns,
                         "the vehicle's namespace in the bag (a launch with namespace:=cf1 records /cf1/odom, ...); "
                         "default: the root names tactile records");
  export_cmd->add_option("--metrics", exp.metrics,
                         "summary JSON with its warnings (default: the PLY's name with .metrics.json)");
  std::string export_time = "header";
  export_cmd
      ->add_option("--time", export_time,
                   "replay clock: header (the messages' stamps, in stamp order) or receive (the bag's timestamps, in "
                   "bag order)")
      ->check(CLI::IsMember({"header", "receive"}))
      ->capture_default_str();

  tactile_cli::EvaluateOptions evaluate;
  uint64_t evaluate_seed = 0;
  auto* evaluate_cmd = app.add_subcommand(
      "evaluate", "metrics of `tactile sim` from a bag of the scenario flown elsewhere (e.g. the SITL launch under ROS 2)");
  evaluate_cmd->add_option("bag", evaluate.bag, "input rosbag2 directory")->required();
  evaluate_cmd->add_option("--scenario", evaluate.scenario, "the scenario file that was flown")->required();
  evaluate_cmd->add_option("--out", evaluate.out_dir, "output directory (metrics.json)")->required();
  auto* evaluate_seed_opt = evaluate_cmd->add_option("--seed", evaluate_seed, "the flight's seed (default: the scenario's)")->check(kWholeNumber);

  auto* scenarios_cmd = app.add_subcommand("scenarios", "procedural scenario families (issue 17): list, generate");
  scenarios_cmd->require_subcommand(1);
  auto* scenarios_list = scenarios_cmd->add_subcommand("list", "the families and their distributions");
  std::string gen_family, gen_out;
  int gen_count = 10;
  uint64_t gen_seed = 1;
  auto* scenarios_gen = scenarios_cmd->add_subcommand(
      "generate", "draw N seeded, validated environments of a family as standalone scenario files");
  scenarios_gen->add_option("family", gen_family, "family (tactile scenarios list)")->required();
  scenarios_gen->add_option("--count", gen_count, "environments (seeds S .. S+N-1)")->check(CLI::PositiveNumber)
      ->capture_default_str();
  scenarios_gen->add_option("--seed", gen_seed, "first generator seed")->check(kWholeNumber)->capture_default_str();
  scenarios_gen->add_option("--out", gen_out, "output directory (<family>_<seed>.yaml, index.json)")->required();

  tactile_cli::SweepOptions sweep;
  auto* sweep_cmd = app.add_subcommand(
      "sweep", "fly a scenario family (or a directory of scenarios) and write a table and a summary");
  sweep_cmd->add_option("what", sweep.what, "family name or directory of scenario files");
  sweep_cmd->add_option("--count", sweep.count, "environments (family; with a directory: at most N, 0 = all)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  sweep_cmd->add_option("--seed", sweep.seed, "first generator seed (family)")->check(kWholeNumber)->capture_default_str();
  sweep_cmd->add_option("--out", sweep.out_dir, "output directory (table.csv/md, summary.json/md, runs/, failures/)");
  sweep_cmd->add_option("--jobs,-j", sweep.jobs, "environments flown at once on worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sweep_cmd->add_flag("!--no-bag", sweep.write_bags, "do not record bags (failures keep theirs otherwise)");
  sweep_cmd->add_flag("--keep-bags", sweep.keep_bags, "keep the bags of successes too");
  sweep_cmd->add_flag("--keep-success-files", sweep.keep_success_files,
                      "keep every file of successes too (trajectory.csv, maps; bags: --keep-bags)");
  sweep_cmd->add_flag("!--quiet", sweep.progress, "no line per environment");
  std::string sweep_shard;
  sweep_cmd->add_option("--shard", sweep_shard,
                        "K/M: fly only shard K of M (environments i with i % M == K-1) and write shard.json "
                        "for `tactile sweep merge` (one per cluster array task: scripts/slurm/)");
  tactile_cli::SweepMergeOptions sweep_merge;
  auto* sweep_merge_cmd = sweep_cmd->add_subcommand(
      "merge", "build the table, summary, runs/ and failures/ of a sharded sweep from its shards' directories");
  sweep_merge_cmd->add_option("--out", sweep_merge.out_dir, "output directory of the whole sweep")->required();
  sweep_merge_cmd->add_option("shard_dirs", sweep_merge.shard_dirs, "the --out of every shard (K = 1..M)")
      ->required()
      ->check(CLI::ExistingDirectory);
  sweep_cmd->require_subcommand(0, 1);

  std::vector<std::string> params_nodes;
  std::string params_format = "markdown";
  std::string params_readme_dir;
  auto* params_cmd = app.add_subcommand(
      "params", "the parameter schema of each node (key, type, default, range, unit, live, description); "
                "without NODE: the nodes");
  params_cmd->add_option("node", params_nodes, "node names (tactile params lists them)");
  params_cmd->add_option("--format", params_format,
                         "markdown (a table, as in the package READMEs) or yaml (a ROS 2 parameter file at "
                         "the defaults, each key's description as a comment)")
      ->check(CLI::IsMember({"markdown", "yaml"}))
      ->capture_default_str();
  params_cmd->add_option("--write-readme", params_readme_dir,
                         "regenerate the tables between <!-- BEGIN params NODE --> and <!-- END params NODE --> "
                         "in DIR/*/README.md and DIR/*/docs/*.md (DIR: the workspace's src/)")
      ->check(CLI::ExistingDirectory);

  CLI11_PARSE(app, argc, argv);
  if (!bag_options.compression.empty() && bag_options.storage != "mcap") {
    std::fprintf(stderr, "tactile: error: --bag-compression %s needs --storage mcap (sqlite3 bags are written uncompressed)\n",
                 bag_options.compression.c_str());
    return 1;
  }

  if (*scenarios_cmd) {  // needs no node parameter files
    try {
      if (*scenarios_list) {
        for (const auto& f : tactile_cli::scenario_families()) {
          std::printf("%s: %s\n    %s\n", f.name.c_str(), f.description.c_str(), f.distribution.c_str());
        }
      } else {
        const auto& family = tactile_cli::scenario_family(gen_family);
        const tactile_cli::OutputDir out_dir(gen_out, "scenarios generate");
        const auto paths = tactile_cli::generate_family(family, gen_count, gen_seed, gen_out);
        std::printf("tactile scenarios: %zu %s environments (seeds %llu-%llu) -> %s (index.json)\n", paths.size(),
                    family.name.c_str(), static_cast<unsigned long long>(gen_seed),
                    static_cast<unsigned long long>(gen_seed + gen_count - 1), gen_out.c_str());
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tactile: error: %s\n", e.what());
      return 1;
    }
    return 0;
  }

  if (*params_cmd) {  // needs no node parameter files
    try {
      if (!params_readme_dir.empty()) {
        if (!params_nodes.empty()) {
          std::fprintf(stderr, "tactile params: error: --write-readme regenerates every block; give no NODE\n");
          return 2;
        }
        for (const auto& line : tactile_cli::write_param_tables(params_readme_dir)) std::printf("%s\n", line.c_str());
        return 0;
      }
      if (params_nodes.empty()) {
        for (const auto& s : tactile_cli::node_schemas()) {
          std::string files;
          for (const auto& f : s.config_files) files += (files.empty() ? "config/" : ", config/") + f;
          std::printf("%-22s %3zu parameters  package %-21s %s\n", s.name.c_str(), s.parameters().values().size(),
                      s.package.c_str(), files.empty() ? "(launch arguments)" : files.c_str());
        }
        return 0;
      }
      std::vector<const tactile_cli::NodeSchema*> chosen;
      for (const auto& n : params_nodes) chosen.push_back(&tactile_cli::node_schema(n));  // all known before output
      for (size_t i = 0; i < chosen.size(); ++i) {
        if (i) std::printf("\n");
        const std::string text =
            params_format == "yaml" ? tactile_cli::schema_yaml(*chosen[i]) : tactile_cli::schema_markdown(*chosen[i]);
        std::fputs(text.c_str(), stdout);
      }
    } catch (const tactile_cli::UnknownNode& e) {
      std::fprintf(stderr, "tactile params: error: %s\n", e.what());
      return 2;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tactile params: error: %s\n", e.what());
      return 1;
    }
    return 0;
  }

  if (*stage_cmd) {  // needs no node parameter files
    try {
      const tactile_cli::OutputDir out_dir(stage_out, "stage");
      const auto m = whisker_localization::run_bench_protocol_to(
          stage_scenario, stage_out, *stage_seed_opt ? std::optional<uint64_t>(stage_seed) : std::nullopt);
      std::printf("tactile stage: %s (%s, seed %llu) -> %s/metrics.json\n", m["scenario"].get<std::string>().c_str(),
                  m["protocol"].get<std::string>().c_str(), static_cast<unsigned long long>(m["seed"].get<uint64_t>()),
                  stage_out.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tactile: error: %s\n", e.what());
      return 1;
    }
    return 0;
  }

  try {
    check_config_dir(config_dir);
    if (*sim_cmd) {
      sim.config_dir = config_dir;
      sim.profiles = profiles;
      if (*seed_opt) sim.seed = sim_seed;
      const tactile_cli::InterruptScope signals;  // Ctrl-C: stop, write what was flown, exit 130
      const tactile_cli::OutputDir out_dir(sim.out_dir, "sim");
      const auto m = tactile_cli::run_sim(sim);
      if (m["interrupted"].get<bool>()) {
        std::fprintf(stderr, "tactile sim: interrupted (signal %d): partial outputs in %s (metrics.json: "
                     "\"interrupted\": true)\n", tactile_cli::interrupt_signal(), sim.out_dir.c_str());
        return tactile_cli::interrupted_exit_status();
      }
      if (sim.trials == 1) {
        std::printf("tactile sim: %s seed %llu: %.1f s simulated in %.2f s (%.0fx real time), %zu collisions, %s\n",
                    m["scenario"].get<std::string>().c_str(), static_cast<unsigned long long>(m["seed"].get<uint64_t>()),
                    m["sim_time_s"].get<double>(), m["wall_time_s"].get<double>(),
                    m["real_time_factor"].get<double>(), m["collisions"].get<size_t>(),
                    m["success"].get<bool>() ? "success" : "no success");
      } else {
        std::printf("tactile sim: %s, %d trials: %d successes, %zu collisions, %.1f s in %.2f s on %d jobs "
                    "(%.0fx real time)\n",
                    m["scenario"].get<std::string>().c_str(), sim.trials, m["success_count"].get<int>(),
                    m["collisions"].get<size_t>(), m["sim_time_s"].get<double>(), m["wall_time_s"].get<double>(),
                    tactile_cli::resolve_jobs(sim.jobs, static_cast<size_t>(sim.trials)),
                    m["real_time_factor"].get<double>());
      }
      std::printf("outputs in %s\n", sim.out_dir.c_str());
    } else if (*sweep_cmd && *sweep_merge_cmd) {
      const tactile_cli::OutputDir out_dir(sweep_merge.out_dir, "sweep merge");
      const auto m = tactile_cli::merge_sweep(sweep_merge);
      std::printf("tactile sweep merge: %s, %zu shards: %d / %d successes (%.1f %%), %zu collisions -> %s "
                  "(summary.md, table.md)\n",
                  m["what"].get<std::string>().c_str(), m["merged_shards"].size(), m["successes"].get<int>(),
                  m["flown"].get<int>(), 100.0 * m["success_rate"].get<double>(), m["collisions"].get<size_t>(),
                  sweep_merge.out_dir.c_str());
    } else if (*sweep_cmd) {
      if (sweep.what.empty() || sweep.out_dir.empty()) {
        std::fprintf(stderr, "tactile sweep: error: %s is required (tactile sweep FAMILY|DIR --out DIR, or "
                     "tactile sweep merge --out DIR SHARD_DIR...)\n", sweep.what.empty() ? "FAMILY or DIR" : "--out");
        return 1;
      }
      if (!sweep_shard.empty()) tactile_cli::parse_shard(sweep_shard, sweep.shard, sweep.shards);
      sweep.config_dir = config_dir;
      sweep.profiles = profiles;
      const tactile_cli::InterruptScope signals;  // Ctrl-C: no new environment, table/summary kept, exit 130
      const tactile_cli::OutputDir out_dir(sweep.out_dir, "sweep");
      const auto m = tactile_cli::run_sweep(sweep);
      if (m["interrupted"].get<bool>()) {
        std::fprintf(stderr, "tactile sweep: interrupted (signal %d): %d of %d environments flown -> %s "
                     "(summary.md, table.md)\n", tactile_cli::interrupt_signal(), m["flown"].get<int>(),
                     m["environments"].get<int>(), sweep.out_dir.c_str());
        return tactile_cli::interrupted_exit_status();
      }
      std::printf("tactile sweep: %s: %d / %d successes (%.1f %%), %zu collisions -> %s (summary.md, table.md)\n",
                  sweep.what.c_str(), m["successes"].get<int>(), m["flown"].get<int>(),
                  100.0 * m["success_rate"].get<double>(), m["collisions"].get<size_t>(), sweep.out_dir.c_str());
    } else if (*fly_cmd || *bench_cmd || *scan_cmd) {
      if (*scan_cmd) {
        for (const auto& line : tactile_cli::run_scan(scan_host)) std::printf("%s\n", line.c_str());
      } else if (*fly_cmd) {
        fly.config_dir = config_dir;
        const tactile_cli::OutputDir out_dir(fly.out_dir, "fly");
        const auto m = tactile_cli::run_fly(fly);
        std::printf("tactile fly: %s, %.1f s, ended: %s, bridge %s, %llu log samples, link packets sent %llu lost %llu -> %s\n",
                    m["uri"].get<std::string>().c_str(), m["wall_time_s"].get<double>(),
                    m["end_reason"].get<std::string>().c_str(),
                    m["bridge_mode"].get<std::string>().c_str(), m["log_samples"].get<unsigned long long>(),
                    m["link_packets_sent"].get<unsigned long long>(), m["link_packets_lost"].get<unsigned long long>(),
                    fly.out_dir.c_str());
      } else {
        bench.config_dir = config_dir;
        const tactile_cli::OutputDir out_dir(bench.out_dir, "bench");
        const auto m = tactile_cli::run_bench(bench);
        std::printf("tactile bench: %.1f s, %llu messages -> %s\n", m["wall_time_s"].get<double>(),
                    m["bag_messages"].get<unsigned long long>(), bench.out_dir.c_str());
      }
    } else if (*evaluate_cmd) {
      evaluate.config_dir = config_dir;
      const tactile_cli::OutputDir out_dir(evaluate.out_dir, "evaluate");
      if (*evaluate_seed_opt) evaluate.seed = evaluate_seed;
      const auto m = tactile_cli::run_evaluate(evaluate);
      std::printf("tactile evaluate: %s (%s, seed %llu) from %s: %zu collisions, %s -> %s/metrics.json\n",
                  m["scenario"].get<std::string>().c_str(), m["graph"].get<std::string>().c_str(),
                  static_cast<unsigned long long>(m["seed"].get<uint64_t>()), evaluate.bag.c_str(),
                  m["collisions"].get<size_t>(), m["success"].get<bool>() ? "success" : "no success",
                  evaluate.out_dir.c_str());
    } else if (*export_cmd) {
      exp.config_dir = config_dir;
      exp.time = export_time == "receive" ? tactile_cli::ExportOptions::Time::kReceive
                                          : tactile_cli::ExportOptions::Time::kHeader;
      const auto m = tactile_cli::run_export(exp);
      std::printf("tactile export: %s -> %s (%llu points, %.3f x %.3f m; summary %s)\n", exp.bag.c_str(),
                  exp.ply.c_str(), static_cast<unsigned long long>(m["points"].get<uint64_t>()),
                  m["map_length_m"].get<double>(), m["map_width_m"].get<double>(),
                  m["metrics_file"].get<std::string>().c_str());
    } else if (*replay_cmd) {
      replay.config_dir = config_dir;
      const tactile_cli::OutputDir out_dir(replay.out_dir, "replay");
      const auto m = tactile_cli::run_replay(replay);
      std::printf("tactile replay: %s -> %s (%.0f messages/s)\n", replay.bag.c_str(),
                  replay.out_dir.c_str(), m["messages_per_second"].get<double>());
      print_fpr(m);
    } else if (*demo_cmd) {
      demo.config_dir = config_dir;
      const tactile_cli::OutputDir out_dir(demo.out_dir, "demo");
      const auto summary = tactile_cli::run_whisker_demo(demo);
      for (const auto& [name, m] : summary.items()) {
        std::printf("%s:\n", name.c_str());
        print_fpr(m);
      }
      std::printf("outputs in %s (summary.json, */metrics.json, */signals.png, */bag/)\n",
                  demo.out_dir.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tactile: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
