#include "tactile_cli/sweep.hpp"

#include <mutex>

#include "tactile_cli/interrupt.hpp"
#include "tactile_cli/parallel.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "tactile_cli/scenario_family.hpp"
#include "tactile_cli/sim_run.hpp"
#include "tactile_common/parameters.hpp"
#include "tactile_sim/scenario.hpp"

namespace tactile_cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return buf;
}

std::string machine() {
  struct utsname u {};
  std::string s;
  if (uname(&u) == 0) s = std::string(u.sysname) + " " + u.release + " " + u.machine;
  s += ", " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " cores";
  std::ifstream pretty("/etc/os-release");
  for (std::string line; std::getline(pretty, line);) {
    if (line.rfind("PRETTY_NAME=", 0) == 0) {
      std::string v = line.substr(12);
      v.erase(std::remove(v.begin(), v.end(), '"'), v.end());
      s = v + ", " + s;
    }
  }
  return s;
}

double load_average() {
  double l[1] = {0.0};
  return getloadavg(l, 1) == 1 ? l[0] : -1.0;
}

/// metrics.json value at a dotted path (null if absent).
json at_path(const json& m, const std::string& path) {
  std::string p = "/" + path;
  std::replace(p.begin(), p.end(), '.', '/');
  const auto ptr = json::json_pointer(p);
  return m.contains(ptr) ? m.at(ptr) : json(nullptr);
}

std::string cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number()) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v.get<double>());
    return buf;
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

/// Default metric columns by graph, for a directory without a family.
std::vector<std::string> metrics_for_graph(const std::string& graph) {
  for (const auto& f : scenario_families()) {
    if (f.table_metrics.empty()) continue;
    const std::string key = f.table_metrics.front().substr(0, f.table_metrics.front().find('.'));
    if ((graph == "whisker_fsm" && key == "fsm") || (graph == "gpis_explore" && key == "gpis") ||
        (graph == "xplorer" && key == "xplorer")) {
      return f.table_metrics;
    }
  }
  return {};
}

struct Row {
  size_t index = 0;      // position in the whole sweep (seed order / file order)
  std::string name, file, state_estimate, graph, outcome;
  std::string listed;    // the scenario as the summary names it: relative to OUT for generated ones
  uint64_t seed = 0;
  bool success = false;
  size_t collisions = 0, guard_collisions = 0, body_collisions = 0;
  double sim_time_s = 0.0, wall_time_s = 0.0;
  bool interrupted = false;       // stopped by a signal: discarded, not a row of the table
  json metrics = json::object();  // table metric path -> value
  std::string topview;            // failures/<name>.png (failures only)
};

json row_to_json(const Row& r) {
  return {{"index", r.index},          {"name", r.name},
          {"file", r.file},            {"listed", r.listed},
          {"state_estimate", r.state_estimate}, {"graph", r.graph},
          {"outcome", r.outcome},      {"seed", r.seed},
          {"success", r.success},      {"collisions", r.collisions},
          {"guard_collisions", r.guard_collisions}, {"body_collisions", r.body_collisions},
          {"sim_time_s", r.sim_time_s}, {"wall_time_s", r.wall_time_s},
          {"metrics", r.metrics},      {"topview", r.topview}};
}

Row row_from_json(const json& j) {
  Row r;
  r.index = j.at("index").get<size_t>();
  r.name = j.at("name").get<std::string>();
  r.file = j.at("file").get<std::string>();
  r.listed = j.at("listed").get<std::string>();
  r.state_estimate = j.at("state_estimate").get<std::string>();
  r.graph = j.at("graph").get<std::string>();
  r.outcome = j.at("outcome").get<std::string>();
  r.seed = j.at("seed").get<uint64_t>();
  r.success = j.at("success").get<bool>();
  r.collisions = j.at("collisions").get<size_t>();
  r.guard_collisions = j.at("guard_collisions").get<size_t>();
  r.body_collisions = j.at("body_collisions").get<size_t>();
  r.sim_time_s = j.at("sim_time_s").get<double>();
  r.wall_time_s = j.at("wall_time_s").get<double>();
  r.metrics = j.at("metrics");
  if (!r.metrics.is_object()) throw std::runtime_error("metrics: not an object");
  r.topview = j.at("topview").get<std::string>();
  return r;
}

/// When and where a sweep (or the shards of a merged one) ran: the summary's
/// provenance, the only part a merge does not reproduce.
struct Provenance {
  std::string started;   // UTC
  std::string machine;
  double load_at_start = -1.0;
  int jobs = 0;
  double wall_s = 0.0;
  std::string shard;     // "K/M" for a shard
  json merged = nullptr; // a merge: one entry per shard
};

Row fly_one(const std::string& file, const SweepOptions& options, const fs::path& runs_dir,
            const fs::path& failures_dir, const std::vector<std::string>& table_metrics) {
  Row row;
  row.file = file;
  row.listed = file;
  row.name = fs::path(file).stem().string();
  const fs::path dir = runs_dir / row.name;
  try {
    const auto sc = tactile_sim::load_scenario(file);
    row.name = sc.name;
    row.seed = sc.seed;
    row.graph = sc.graph;
    row.state_estimate = sc.vehicle == tactile_sim::VehicleType::kWhiskerCrazyflie ? sc.state_estimate : "";
    SimOptions so;
    so.scenario = file;
    so.out_dir = dir.string();
    so.config_dir = options.config_dir;
    so.profiles = options.profiles;
    so.trials = 1;
    so.progress = false;
    so.write_bag = options.write_bags;
    so.write_png = true;
    const json m = run_sim(so);
    if (m["interrupted"].get<bool>()) {
      // Stopped part-way by Ctrl-C / SIGTERM: a partial flight is no result; its files go.
      row.interrupted = true;
      std::error_code ec;
      fs::remove_all(dir, ec);
      return row;
    }
    row.success = m["success"].get<bool>();
    row.collisions = m["collisions"].get<size_t>();
    for (const auto& c : m["collision_events"]) {
      const std::string part = c["part"].get<std::string>();
      if (part == "guard") ++row.guard_collisions;
      if (part == "body") ++row.body_collisions;
    }
    row.sim_time_s = m["sim_time_s"].get<double>();
    row.wall_time_s = m["wall_time_s"].get<double>();
    for (const auto& p : table_metrics) row.metrics[p] = at_path(m, p);
    if (row.success) {
      row.outcome = "success";
    } else {
      std::string why;
      bool goal = true;
      if (m.contains("fsm") && m["fsm"].contains("reached_target")) goal = m["fsm"]["reached_target"].get<bool>();
      if (m.contains("gpis")) goal = m["gpis"].value("exit_found", false) && m["gpis"].value("outside_room", false);
      if (m.contains("xplorer") && m["xplorer"].contains("loop_closed")) goal = m["xplorer"]["loop_closed"].get<bool>();
      if (!goal) why = "goal not reached";
      if (goal && m.contains("xplorer") && m["xplorer"].value("min_area_accuracy", json()).is_number()) {
        const json& a = m["xplorer"]["area_accuracy"];
        const double min = m["xplorer"]["min_area_accuracy"].get<double>();
        if (!a.is_number() || a.get<double>() < min) {
          char b[96];
          std::snprintf(b, sizeof b, "area accuracy %.3f < %.2f", a.is_number() ? a.get<double>() : 0.0, min);
          why = b;
        }
      }
      if (row.collisions > 0) {
        why += std::string(why.empty() ? "" : ", ") + std::to_string(row.collisions) + " collision" +
               (row.collisions == 1 ? "" : "s");
      }
      row.outcome = "failure: " + (why.empty() ? std::string("no success") : why);
    }
  } catch (const tactile_common::ParamError&) {
    // A node parameter file (missing, empty, not a file, no section for the
    // node) or value is wrong for every environment alike: the sweep stops
    // with that error (exit 1), not a table of N "error" rows and exit 0.
    throw;
  } catch (const std::exception& e) {
    row.success = false;
    row.outcome = std::string("error: ") + e.what();
  }
  if (!row.success) {
    const fs::path png = dir / "topview.png";
    if (fs::exists(png)) {
      fs::create_directories(failures_dir);
      fs::copy_file(png, failures_dir / (row.name + ".png"), fs::copy_options::overwrite_existing);
      row.topview = (fs::path("failures") / (row.name + ".png")).string();
    }
  } else {
    // A success keeps its metrics and top view; its bag and its other files
    // (trajectory.csv ~1 MB per simulated minute; XPLORER's map.ply,
    // map_binary.ply and forces.csv ~10 MB) only on request: a sweep of
    // hundreds would fill a disk with files nobody reads.
    std::error_code ec;
    if (!options.keep_bags) fs::remove_all(dir / "bag", ec);
    if (!options.keep_success_files) {
      for (const auto& entry : fs::directory_iterator(dir, ec)) {
        const auto base = entry.path().filename();
        if (entry.is_regular_file() && base != "metrics.json" && base != "topview.png") fs::remove(entry.path(), ec);
      }
    }
  }
  return row;
}

void write_outputs(const fs::path& out, const std::string& what, const SweepOptions& options,
                   const std::vector<std::string>& table_metrics, const std::vector<Row>& rows, int total,
                   const Provenance& pv, bool interrupted, json& summary) {
  // table.csv / table.md
  std::ostringstream csv, md;
  csv << "name,seed,state_estimate,outcome,success,collisions,guard_collisions,body_collisions";
  md << "| environment | seed | estimate | outcome | collisions (guard/body) |";
  for (const auto& p : table_metrics) {
    csv << ',' << p;
    md << ' ' << p << " |";
  }
  csv << ",sim_time_s,wall_time_s,topview\n";
  md << " top view |\n|---|---|---|---|---|";
  for (size_t i = 0; i < table_metrics.size(); ++i) md << "---|";
  md << "---|\n";
  for (const auto& r : rows) {
    csv << csv_escape(r.name) << ',' << r.seed << ',' << r.state_estimate << ',' << csv_escape(r.outcome) << ','
        << (r.success ? "true" : "false") << ',' << r.collisions << ',' << r.guard_collisions << ','
        << r.body_collisions;
    md << "| " << r.name << " | " << r.seed << " | " << r.state_estimate << " | " << r.outcome << " | " << r.collisions
       << " (" << r.guard_collisions << "/" << r.body_collisions << ") |";
    for (const auto& p : table_metrics) {
      const json v = r.metrics.contains(p) ? r.metrics[p] : json(nullptr);
      csv << ',' << csv_escape(cell(v));
      md << ' ' << cell(v) << " |";
    }
    char t[64];
    std::snprintf(t, sizeof t, ",%.1f,%.1f,", r.sim_time_s, r.wall_time_s);
    csv << t << r.topview << '\n';
    md << ' ' << (r.topview.empty() ? "" : "[png](" + r.topview + ")") << " |\n";
  }
  write_text(out / "table.csv", csv.str());
  write_text(out / "table.md", md.str());

  // summary
  summary = json::object();
  summary["what"] = what;
  summary["family"] = find_scenario_family(what) ? json(what) : json(nullptr);
  if (find_scenario_family(what)) {
    summary["seeds"] = {options.seed, options.seed + static_cast<uint64_t>(options.count) - 1};
  }
  if (!pv.shard.empty()) summary["shard"] = pv.shard;
  summary["environments"] = total;
  summary["flown"] = rows.size();
  // Ctrl-C / SIGTERM: the environments not flown (or stopped part-way) are not in the table.
  summary["interrupted"] = interrupted;
  int successes = 0, collision_free = 0, errors = 0;
  size_t collisions = 0, guard = 0;
  std::map<std::string, std::pair<int, int>> by_estimate;  // n, successes
  for (const auto& r : rows) {
    successes += r.success;
    collision_free += r.collisions == 0 && r.outcome.rfind("error", 0) != 0;
    errors += r.outcome.rfind("error", 0) == 0;
    collisions += r.collisions;
    guard += r.guard_collisions;
    if (!r.state_estimate.empty()) {
      auto& e = by_estimate[r.state_estimate];
      ++e.first;
      e.second += r.success;
    }
  }
  const double n = static_cast<double>(std::max<size_t>(1, rows.size()));
  summary["successes"] = successes;
  summary["success_rate"] = successes / n;
  summary["collision_free"] = collision_free;
  summary["collisions"] = collisions;
  summary["guard_collisions"] = guard;
  summary["errors"] = errors;
  for (const auto& [est, e] : by_estimate) {
    summary["by_state_estimate"][est] = {{"environments", e.first}, {"successes", e.second},
                                         {"success_rate", static_cast<double>(e.second) / std::max(1, e.first)}};
  }
  for (const auto& p : table_metrics) {
    double sum = 0.0;
    int k = 0;
    for (const auto& r : rows) {
      const json v = r.metrics.contains(p) ? r.metrics[p] : json(nullptr);
      if (v.is_number()) sum += v.get<double>(), ++k;
      if (v.is_boolean()) sum += v.get<bool>() ? 1.0 : 0.0, ++k;
    }
    if (k > 0) summary["mean"][p] = sum / k;
  }
  summary["failures"] = json::array();
  for (const auto& r : rows) {
    if (!r.success) summary["failures"].push_back({{"name", r.name}, {"seed", r.seed}, {"outcome", r.outcome},
                                                   {"topview", r.topview}, {"scenario", r.listed}});
  }
  summary["date"] = pv.started;
  summary["machine"] = pv.machine;
  summary["load_average_at_start"] = pv.load_at_start;
  summary["jobs"] = pv.jobs;
  summary["wall_time_s"] = pv.wall_s;
  if (!pv.merged.is_null()) summary["merged_shards"] = pv.merged;
  write_text(out / "summary.json", summary.dump(2) + "\n");

  std::ostringstream s;
  s << "# Sweep: " << what << "\n\n";
  if (summary.contains("seeds")) {
    s << "Seeds " << options.seed << "-" << options.seed + static_cast<uint64_t>(options.count) - 1 << ", ";
  }
  s << rows.size() << " of " << total << " environments flown";
  if (!pv.shard.empty()) s << " (shard " << pv.shard << ")";
  if (pv.merged.is_null()) {
    s << "; " << pv.started << ", " << pv.machine << ", load " << pv.load_at_start << " at start, " << pv.jobs
      << " job(s), " << static_cast<long>(pv.wall_s) << " s.\n\n";
  } else {
    s << "; merged from " << pv.merged.size() << " shards, the first started " << pv.started << " (" << pv.machine
      << "), " << static_cast<long>(pv.wall_s) << " s of shard wall time in all.\n\n";
  }
  if (interrupted) s << "**Interrupted** (Ctrl-C / SIGTERM): " << rows.size() << " of " << total << " flown.\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "**%d / %zu successes (%.1f %%)**, %d collision-free, %zu collisions (%zu guard)",
                successes, rows.size(), 100.0 * successes / n, collision_free, collisions, guard);
  s << line << (errors ? ", " + std::to_string(errors) + " errors" : std::string()) << ".\n\n";
  if (!by_estimate.empty()) {
    s << "| state estimate | environments | successes | rate |\n|---|---|---|---|\n";
    for (const auto& [est, e] : by_estimate) {
      std::snprintf(line, sizeof line, "| %s | %d | %d | %.1f %% |\n", est.c_str(), e.first, e.second,
                    100.0 * e.second / std::max(1, e.first));
      s << line;
    }
    s << "\n";
  }
  if (summary.contains("mean")) {
    s << "| metric | mean over environments |\n|---|---|\n";
    for (const auto& [k, v] : summary["mean"].items()) s << "| " << k << " | " << cell(v) << " |\n";
    s << "\n";
  }
  if (!summary["failures"].empty()) {
    s << "Failures:\n\n";
    for (const auto& f : summary["failures"]) {
      s << "- " << f["name"].get<std::string>() << ": " << f["outcome"].get<std::string>();
      if (!f["topview"].get<std::string>().empty()) s << " ([top view](" << f["topview"].get<std::string>() << "))";
      s << "\n";
    }
  }
  write_text(out / "summary.md", s.str());
}


/// OUT/shard.json of a `--shard K/M` sweep: what `merge_sweep` needs to rebuild the
/// whole sweep's table and summary (every row in full, the sweep's identity).
void write_shard_record(const fs::path& out, const SweepOptions& options, const std::vector<std::string>& table_metrics,
                        const std::vector<size_t>& share, size_t total_all, const std::vector<Row>& rows,
                        const Provenance& pv, bool interrupted) {
  json j;
  j["format"] = "tactile sweep shard 1";
  j["what"] = options.what;
  j["family"] = find_scenario_family(options.what) != nullptr;
  j["seed"] = options.seed;
  j["count"] = options.count;
  j["environments_all"] = total_all;
  j["shard"] = options.shard;
  j["shards"] = options.shards;
  j["indices"] = share;
  j["table_metrics"] = table_metrics;
  j["interrupted"] = interrupted;
  j["rows"] = json::array();
  for (const auto& r : rows) j["rows"].push_back(row_to_json(r));
  j["date"] = pv.started;
  j["machine"] = pv.machine;
  j["load_average_at_start"] = pv.load_at_start;
  j["jobs"] = pv.jobs;
  j["wall_time_s"] = pv.wall_s;
  // Written whole then renamed: a shard killed mid-write leaves the previous record.
  write_text(out / "shard.json.tmp", j.dump(1) + "\n");
  fs::rename(out / "shard.json.tmp", out / "shard.json");
}

}  // namespace

void parse_shard(const std::string& text, int& shard, int& shards) {
  const auto slash = text.find('/');
  auto number = [&](const std::string& t) {
    if (t.empty() || t.size() > 6 || t.find_first_not_of("0123456789") != std::string::npos) {
      throw std::invalid_argument("--shard " + text + ": expected K/M with whole numbers 1 <= K <= M <= 100000");
    }
    return std::stoi(t);
  };
  if (slash == std::string::npos) {
    throw std::invalid_argument("--shard " + text + ": expected K/M (e.g. 3/8: the third of eight shards)");
  }
  const int k = number(text.substr(0, slash));
  const int m = number(text.substr(slash + 1));
  if (m < 1 || m > 100000 || k < 1 || k > m) {
    throw std::invalid_argument("--shard " + text + ": expected 1 <= K <= M <= 100000");
  }
  shard = k;
  shards = m;
}

json run_sweep(const SweepOptions& options) {
  if (options.jobs < 0) throw std::invalid_argument("--jobs must be >= 0 (0: all cores)");
  const bool sharded = options.shards > 0;
  if (sharded && (options.shard < 1 || options.shard > options.shards)) {
    throw std::invalid_argument("--shard: K must be in 1..M");
  }
  const fs::path out(options.out_dir);
  fs::create_directories(out);
  Provenance pv;
  pv.started = utc_now();
  pv.machine = machine();
  pv.load_at_start = load_average();
  pv.jobs = options.jobs;
  if (sharded) pv.shard = std::to_string(options.shard) + "/" + std::to_string(options.shards);
  const auto wall_start = std::chrono::steady_clock::now();

  // The share of shard K of M: environments i with i % M == K - 1 (round robin, so
  // every shard gets easy and hard environments alike whatever their order).
  const auto share_of = [&](size_t n) {
    if (sharded && static_cast<size_t>(options.shards) > n) {
      throw std::invalid_argument("--shard " + pv.shard + ": more shards than environments (" + std::to_string(n) +
                                  "): shard " + std::to_string(options.shard) + " would fly nothing");
    }
    std::vector<size_t> share;
    for (size_t i = 0; i < n; ++i) {
      if (!sharded || i % static_cast<size_t>(options.shards) == static_cast<size_t>(options.shard - 1)) share.push_back(i);
    }
    return share;
  };
  std::vector<std::string> files;
  std::vector<size_t> share;  // indices in the whole sweep of files[0..]
  std::vector<std::string> table_metrics;
  size_t total_all = 0;
  const ScenarioFamily* family = find_scenario_family(options.what);
  if (family) {
    if (options.count < 1) throw std::invalid_argument("--count must be >= 1");
    total_all = static_cast<size_t>(options.count);
    share = share_of(total_all);
    std::vector<int> which;
    if (sharded) {
      for (const size_t i : share) which.push_back(static_cast<int>(i));
    }
    files = generate_family(*family, options.count, options.seed, (out / "scenarios").string(), which);
    table_metrics = family->table_metrics;
  } else if (fs::is_directory(options.what)) {
    for (const auto& e : fs::directory_iterator(options.what)) {
      if (e.is_regular_file() && e.path().extension() == ".yaml") files.push_back(e.path().string());
    }
    std::sort(files.begin(), files.end());
    if (options.count > 0 && files.size() > static_cast<size_t>(options.count)) files.resize(options.count);
    if (files.empty()) throw std::runtime_error(options.what + ": no scenario files (*.yaml)");
    total_all = files.size();
    share = share_of(total_all);
    std::ifstream idx(fs::path(options.what) / "index.json");
    if (idx) {
      try {
        const json j = json::parse(idx);
        if (const auto* f = find_scenario_family(j.value("family", ""))) table_metrics = f->table_metrics;
      } catch (const json::exception& e) {
        throw std::runtime_error((fs::path(options.what) / "index.json").string() + ": " + e.what());
      }
    }
    if (table_metrics.empty()) {
      try {
        table_metrics = metrics_for_graph(tactile_sim::load_scenario(files.front()).graph);
      } catch (const std::exception&) {
        // the row of that file reports the error
      }
    }
    std::vector<std::string> mine;
    for (const size_t i : share) mine.push_back(files[i]);
    files = std::move(mine);
  } else {
    std::string known;
    for (const auto& f : scenario_families()) known += (known.empty() ? "" : ", ") + f.name;
    throw std::runtime_error(options.what + ": neither a scenario family (" + known + ") nor a directory");
  }

  std::vector<Row> rows;
  json summary;
  const int total = static_cast<int>(files.size());
  const int workers = resolve_jobs(options.jobs, files.size());
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  const auto write_all = [&](const std::vector<Row>& done, bool interrupted) {
    pv.wall_s = elapsed();
    write_outputs(out, options.what, options, table_metrics, done, total, pv, interrupted, summary);
    if (sharded) write_shard_record(out, options, table_metrics, share, total_all, done, pv, interrupted);
  };
  // The table and summary are rewritten after every finished environment (in file order,
  // so a finished sweep's table equals a serial one's), so a sweep that is killed keeps what
  // it flew. After Ctrl-C / SIGTERM no environment starts, the running ones stop within
  // 0.1 s of simulated time and are discarded, and the outputs are written marked interrupted.
  std::vector<std::optional<Row>> slots(files.size());
  std::mutex mutex;
  int finished = 0;
  const auto record = [&](size_t i, Row r) {
    std::lock_guard<std::mutex> lock(mutex);
    if (r.interrupted) return;
    ++finished;
    if (options.progress) {
      std::fprintf(stderr, "[sweep] %d/%d %s: %s (%.0f s)\n", finished, total, r.name.c_str(), r.outcome.c_str(),
                   r.wall_time_s);
    }
    r.index = share[i];
    // A generated environment is named relative to OUT (scenarios/<name>.yaml): the same
    // in every shard and in the merged sweep, wherever each one's OUT is.
    if (family) r.listed = (fs::path("scenarios") / fs::path(r.file).filename()).string();
    slots[i] = std::move(r);
    std::vector<Row> done;
    for (const auto& s : slots) {
      if (s) done.push_back(*s);
    }
    write_all(done, false);
  };
  parallel_for(files.size(), workers, [&](size_t i) {
    if (interrupt_requested()) return;
    record(i, fly_one(files[i], options, out / "runs", out / "failures", table_metrics));
  });
  for (const auto& s : slots) {
    if (s) rows.push_back(*s);
  }
  const bool interrupted = rows.size() < files.size();
  write_all(rows, interrupted);
  return summary;
}

json merge_sweep(const SweepMergeOptions& options) {
  if (options.shard_dirs.empty()) throw std::invalid_argument("sweep merge: no shard directories given");
  struct Shard {
    fs::path dir;
    json record;
  };
  std::vector<Shard> shards;
  for (const auto& d : options.shard_dirs) {
    const fs::path file = fs::path(d) / "shard.json";
    std::ifstream in(file);
    if (!in) {
      throw std::runtime_error(file.string() + ": cannot read (not the output of `tactile sweep --shard K/M`, or "
                               "that shard has not written its first environment yet)");
    }
    json j;
    try {
      j = json::parse(in);
      if (j.value("format", "") != "tactile sweep shard 1") throw std::runtime_error("format: not \"tactile sweep shard 1\"");
      using Check = bool (json::*)() const noexcept;
      const std::vector<std::pair<const char*, Check>> fields = {
          {"what", &json::is_string},           {"seed", &json::is_number_unsigned},
          {"count", &json::is_number_integer},  {"environments_all", &json::is_number_unsigned},
          {"shard", &json::is_number_unsigned}, {"shards", &json::is_number_unsigned},
          {"indices", &json::is_array},         {"table_metrics", &json::is_array},
          {"interrupted", &json::is_boolean},   {"rows", &json::is_array},
          {"family", &json::is_boolean},        {"date", &json::is_string},
          {"machine", &json::is_string},        {"jobs", &json::is_number_integer},
          {"wall_time_s", &json::is_number},    {"load_average_at_start", &json::is_number}};
      for (const auto& [key, is] : fields) {
        if (!j.contains(key)) throw std::runtime_error(std::string(key) + ": missing");
        if (!(j[key].*is)()) throw std::runtime_error(std::string(key) + ": wrong type (" + j[key].type_name() + ")");
      }
      for (const auto& t : j["table_metrics"]) {
        if (!t.is_string()) throw std::runtime_error("table_metrics: not a list of strings");
      }
    } catch (const std::exception& e) {
      throw std::runtime_error(file.string() + ": " + e.what());
    }
    shards.push_back({d, std::move(j)});
  }
  const json& first = shards.front().record;
  // M and N size the merge's tables: bounded before anything is allocated from them.
  const auto bounded = [&](const char* key, uint64_t max) {
    const json& v = first[key];
    if (!v.is_number_unsigned() || v.get<uint64_t>() < 1 || v.get<uint64_t>() > max) {
      throw std::runtime_error((shards.front().dir / "shard.json").string() + ": " + key + " " + v.dump() +
                               ": expected a whole number in 1.." + std::to_string(max));
    }
    return v.get<uint64_t>();
  };
  const int m = static_cast<int>(bounded("shards", 100000));
  const size_t n = bounded("environments_all", 10000000);  // 10^7 environments (--count is an int)
  if (static_cast<size_t>(m) > n) {
    throw std::runtime_error((shards.front().dir / "shard.json").string() + ": more shards than environments");
  }
  std::vector<std::string> owner(static_cast<size_t>(m) + 1);
  std::vector<std::optional<Row>> rows(n);
  json merged = json::array();
  std::string started;
  std::vector<std::string> machines;
  double wall = 0.0, load0 = -1.0;
  int jobs = 0;
  for (const auto& sh : shards) {
    const json& j = sh.record;
    const std::string where = (sh.dir / "shard.json").string();
    for (const char* key : {"what", "seed", "count", "environments_all", "shards", "table_metrics", "family"}) {
      if (j[key] != first[key]) {
        throw std::runtime_error(where + ": " + key + " " + j[key].dump() + " differs from " +
                                 (shards.front().dir / "shard.json").string() + "'s " + first[key].dump() +
                                 ": not a shard of the same sweep");
      }
    }
    const uint64_t k64 = j["shard"].get<uint64_t>();
    if (k64 < 1 || k64 > static_cast<uint64_t>(m)) {
      throw std::runtime_error(where + ": shard " + std::to_string(k64) + " outside 1.." + std::to_string(m));
    }
    const int k = static_cast<int>(k64);
    if (!owner[k].empty()) {
      throw std::runtime_error(where + ": shard " + std::to_string(k) + "/" + std::to_string(m) + " given twice (also " +
                               owner[k] + ")");
    }
    owner[k] = sh.dir.string();
    const auto& idx = j["indices"];
    if (j["interrupted"].get<bool>() || j["rows"].size() != idx.size()) {
      throw std::runtime_error(where + ": shard " + std::to_string(k) + "/" + std::to_string(m) + " is incomplete (" +
                               std::to_string(j["rows"].size()) + " of " + std::to_string(idx.size()) +
                               " environments flown" + (j["interrupted"].get<bool>() ? ", interrupted" : "") +
                               "): fly it again");
    }
    for (const auto& rj : j["rows"]) {
      Row r;
      try {
        r = row_from_json(rj);
      } catch (const std::exception& e) {
        throw std::runtime_error(where + ": rows: " + e.what());
      }
      if (r.index >= n || static_cast<int>(r.index % static_cast<size_t>(m)) != k - 1) {
        throw std::runtime_error(where + ": rows: environment " + std::to_string(r.index) + " is not in shard " +
                                 std::to_string(k) + "/" + std::to_string(m) + "'s share");
      }
      if (rows[r.index]) throw std::runtime_error(where + ": rows: environment " + std::to_string(r.index) + " twice");
      rows[r.index] = std::move(r);
    }
    merged.push_back({{"shard", k}, {"dir", sh.dir.string()}, {"date", j.value("date", "")},
                      {"machine", j.value("machine", "")}, {"jobs", j.value("jobs", 0)},
                      {"wall_time_s", j.value("wall_time_s", 0.0)}});
    const std::string date = j.value("date", "");
    if (started.empty() || date < started) started = date;
    const std::string mach = j.value("machine", "");
    if (std::find(machines.begin(), machines.end(), mach) == machines.end()) machines.push_back(mach);
    wall += j.value("wall_time_s", 0.0);
    jobs = std::max(jobs, j.value("jobs", 0));
    if (load0 < 0) load0 = j.value("load_average_at_start", -1.0);
  }
  std::string missing;
  for (int k = 1; k <= m; ++k) {
    if (owner[k].empty()) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  }
  if (!missing.empty()) {
    throw std::runtime_error("sweep merge: shard(s) " + missing + " of " + std::to_string(m) + " not given");
  }
  for (size_t i = 0; i < n; ++i) {
    if (!rows[i]) throw std::runtime_error("sweep merge: environment " + std::to_string(i) + " is in no shard's rows");
  }

  // The merged OUT: scenarios/ (family sweeps, with the whole sweep's index.json), runs/,
  // failures/ copied from the shards, then table and summary from the rows.
  const bool is_family = first["family"].get<bool>();
  json index_envs = json::array();
  json index_head;
  if (is_family) {
    for (const auto& sh : shards) {
      const fs::path idx = sh.dir / "scenarios" / "index.json";
      std::ifstream in(idx);
      try {
        const json j = json::parse(in);
        index_head = j;
        for (const auto& e : j.at("environments")) index_envs.push_back(e);
      } catch (const std::exception& e) {
        throw std::runtime_error(idx.string() + ": " + e.what());
      }
    }
  }
  const fs::path out(options.out_dir);
  fs::create_directories(out);
  for (const auto& sh : shards) {
    for (const char* sub : {"runs", "failures", "scenarios"}) {
      const fs::path from = sh.dir / sub;
      if (!fs::is_directory(from)) continue;
      fs::create_directories(out / sub);
      for (const auto& e : fs::directory_iterator(from)) {
        if (std::string(sub) == "scenarios" && e.path().filename() == "index.json") continue;
        fs::copy(e.path(), out / sub / e.path().filename(),
                 fs::copy_options::recursive | fs::copy_options::overwrite_existing);
      }
    }
  }
  if (is_family) {
    std::sort(index_envs.begin(), index_envs.end(),
              [](const json& a, const json& b) { return a.at("seed").get<uint64_t>() < b.at("seed").get<uint64_t>(); });
    index_head["environments"] = index_envs;
    write_text(out / "scenarios" / "index.json", index_head.dump(2) + "\n");
  }
  SweepOptions so;
  so.what = first["what"].get<std::string>();
  so.seed = first["seed"].get<uint64_t>();
  so.count = first["count"].get<int>();
  std::vector<Row> all;
  for (auto& r : rows) all.push_back(std::move(*r));
  Provenance pv;
  pv.started = started;
  for (const auto& mach : machines) pv.machine += (pv.machine.empty() ? "" : "; ") + mach;
  pv.load_at_start = load0;
  pv.jobs = jobs;
  pv.wall_s = wall;
  pv.merged = merged;
  json summary;
  write_outputs(out, so.what, so, first["table_metrics"].get<std::vector<std::string>>(), all, static_cast<int>(n), pv,
                false, summary);
  return summary;
}

}  // namespace tactile_cli
