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
  std::string name, file, state_estimate, graph, outcome;
  uint64_t seed = 0;
  bool success = false;
  size_t collisions = 0, guard_collisions = 0, body_collisions = 0;
  double sim_time_s = 0.0, wall_time_s = 0.0;
  bool interrupted = false;       // stopped by a signal: discarded, not a row of the table
  json metrics = json::object();  // table metric path -> value
  std::string topview;            // failures/<name>.png (failures only)
};

Row fly_one(const std::string& file, const SweepOptions& options, const fs::path& runs_dir,
            const fs::path& failures_dir, const std::vector<std::string>& table_metrics) {
  Row row;
  row.file = file;
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
                   const std::string& started, double load_at_start, double wall_s, bool interrupted,
                   json& summary) {
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
                                                   {"topview", r.topview}, {"scenario", r.file}});
  }
  summary["date"] = started;
  summary["machine"] = machine();
  summary["load_average_at_start"] = load_at_start;
  summary["jobs"] = options.jobs;
  summary["wall_time_s"] = wall_s;
  write_text(out / "summary.json", summary.dump(2) + "\n");

  std::ostringstream s;
  s << "# Sweep: " << what << "\n\n";
  if (summary.contains("seeds")) {
    s << "Seeds " << options.seed << "-" << options.seed + static_cast<uint64_t>(options.count) - 1 << ", ";
  }
  s << rows.size() << " of " << total << " environments flown; " << started << ", " << machine() << ", load "
    << load_at_start << " at start, " << options.jobs << " job(s), " << static_cast<long>(wall_s) << " s.\n\n";
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

}  // namespace

json run_sweep(const SweepOptions& options) {
  if (options.jobs < 0) throw std::invalid_argument("--jobs must be >= 0 (0: all cores)");
  const fs::path out(options.out_dir);
  fs::create_directories(out);
  const std::string started = utc_now();
  const double load0 = load_average();
  const auto wall_start = std::chrono::steady_clock::now();

  std::vector<std::string> files;
  std::vector<std::string> table_metrics;
  if (const ScenarioFamily* family = find_scenario_family(options.what)) {
    if (options.count < 1) throw std::invalid_argument("--count must be >= 1");
    files = generate_family(*family, options.count, options.seed, (out / "scenarios").string());
    table_metrics = family->table_metrics;
  } else if (fs::is_directory(options.what)) {
    for (const auto& e : fs::directory_iterator(options.what)) {
      if (e.is_regular_file() && e.path().extension() == ".yaml") files.push_back(e.path().string());
    }
    std::sort(files.begin(), files.end());
    if (options.count > 0 && files.size() > static_cast<size_t>(options.count)) files.resize(options.count);
    if (files.empty()) throw std::runtime_error(options.what + ": no scenario files (*.yaml)");
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
    slots[i] = std::move(r);
    std::vector<Row> done;
    for (const auto& s : slots) {
      if (s) done.push_back(*s);
    }
    write_outputs(out, options.what, options, table_metrics, done, total, started, load0, elapsed(), false, summary);
  };
  parallel_for(files.size(), workers, [&](size_t i) {
    if (interrupt_requested()) return;
    record(i, fly_one(files[i], options, out / "runs", out / "failures", table_metrics));
  });
  for (const auto& s : slots) {
    if (s) rows.push_back(*s);
  }
  const bool interrupted = rows.size() < files.size();
  write_outputs(out, options.what, options, table_metrics, rows, total, started, load0, elapsed(), interrupted,
                summary);
  return summary;
}

}  // namespace tactile_cli
