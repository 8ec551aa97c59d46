#include "tactile_sim/scenario.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace tactile_sim {

namespace {

constexpr double kDeg = M_PI / 180.0;

/// Walks a YAML map with the file name and key path for error messages.
class Node {
 public:
  Node(YAML::Node node, std::string source, std::string path)
      : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& reason) const {
    throw ScenarioError(source_ + ": " + (path_.empty() ? std::string("(top level)") : path_) + ": " +
                        reason);
  }
  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  std::string index_path(size_t i) const { return path_ + "[" + std::to_string(i) + "]"; }

  bool has(const std::string& key) const { return node_.IsMap() && node_[key]; }
  /// A map key as text; a key that is itself a map or list (YAML's `? [a, b]`) is an error
  /// here, not a yaml-cpp conversion exception escaping the loader.
  std::string key_of(const YAML::Node& key) const {
    if (!key.IsScalar()) fail("a key must be a plain name, not a " + std::string(key.IsMap() ? "map" : key.IsSequence() ? "list" : "null"));
    return key.Scalar();
  }
  Node at(const std::string& key) const {
    if (!has(key)) Node(node_, source_, key_path(key)).fail("missing");
    return Node(node_[key], source_, key_path(key));
  }
  void require_map() const {
    if (!node_.IsMap()) fail("expected a map");
  }
  void allow_only(std::initializer_list<const char*> keys) const {
    require_map();
    std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& kv : node_) {
      const std::string k = key_of(kv.first);
      if (!allowed.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        Node(kv.second, source_, key_path(k)).fail("unknown key (allowed: " + list + ")");
      }
    }
  }
  size_t size() const {
    if (!node_.IsSequence()) fail("expected a list");
    return node_.size();
  }
  Node operator[](size_t i) const { return Node(node_[i], source_, index_path(i)); }

  double number() const {
    if (!node_.IsScalar()) fail("expected a number");
    try {
      const double v = node_.as<double>();
      if (!std::isfinite(v)) fail("must be finite, got " + node_.Scalar());
      return v;
    } catch (const YAML::Exception&) {
      fail("expected a number, got '" + node_.Scalar() + "'");
    }
  }
  double positive() const {
    const double v = number();
    if (v <= 0) fail("must be > 0, got " + node_.Scalar());
    return v;
  }
  double non_negative() const {
    const double v = number();
    if (v < 0) fail("must be >= 0, got " + node_.Scalar());
    return v;
  }
  /// A whole number in [lo, hi], read exactly from its digits (a 64-bit seed is not rounded
  /// through a double; "-1", "2.5" and "1e3" are refused, never cast).
  uint64_t whole(uint64_t lo, uint64_t hi) const {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!node_.IsScalar()) fail("expected a whole number in " + range);
    const std::string& s = node_.Scalar();
    bool ok = !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
    unsigned long long v = 0;
    if (ok) {
      try {
        size_t pos = 0;
        v = std::stoull(s, &pos);
        ok = pos == s.size();
      } catch (const std::exception&) {
        ok = false;  // out of range of 64 bits
      }
    }
    if (!ok) fail("expected a whole number in " + range + ", got '" + s + "'");
    if (v < lo || v > hi) fail("must be in " + range + ", got " + s);
    return v;
  }
  std::string text() const {
    if (!node_.IsScalar()) fail("expected a string");
    return node_.Scalar();
  }
  bool boolean() const {
    if (!node_.IsScalar()) fail("expected true or false");
    try {
      return node_.as<bool>();
    } catch (const YAML::Exception&) {
      fail("expected true or false, got '" + node_.Scalar() + "'");
    }
  }
  std::vector<double> numbers(size_t n) const {
    if (!node_.IsSequence() || node_.size() != n) fail("expected a list of " + std::to_string(n) + " numbers");
    std::vector<double> out;
    for (size_t i = 0; i < n; ++i) out.push_back((*this)[i].number());
    return out;
  }
  tactile_common::ParamValue param_value() const {
    if (node_.IsScalar()) {
      const std::string& s = node_.Scalar();
      if (s == "true" || s == "false") return s == "true";
      try {
        size_t pos = 0;
        const long long i = std::stoll(s, &pos);
        if (pos == s.size()) return static_cast<int64_t>(i);
      } catch (...) {
      }
      try {
        size_t pos = 0;
        const double d = std::stod(s, &pos);
        if (pos == s.size()) return d;
      } catch (...) {
      }
      return s;
    }
    if (node_.IsSequence()) {
      std::vector<double> v;
      for (size_t i = 0; i < node_.size(); ++i) v.push_back((*this)[i].number());
      return v;
    }
    fail("expected a scalar or a list of numbers");
  }
  const YAML::Node& raw() const { return node_; }
  const std::string& source() const { return source_; }
  const std::string& path() const { return path_; }

 private:
  YAML::Node node_;
  std::string source_;
  std::string path_;
};

PilotStep parse_step(const Node& n) {
  n.allow_only({"takeoff", "hover", "velocity", "yaw_rate", "position", "yaw_deg", "land", "duration",
                "until", "timeout"});
  PilotStep s;
  int kinds = 0;
  if (n.has("takeoff")) {
    s.kind = PilotStep::Kind::kTakeoff;
    s.height = n.at("takeoff").positive();
    ++kinds;
  }
  if (n.has("hover")) {
    s.kind = PilotStep::Kind::kHover;
    s.duration_s = n.at("hover").positive();
    ++kinds;
  }
  if (n.has("velocity")) {
    s.kind = PilotStep::Kind::kVelocity;
    const auto v = n.at("velocity").numbers(2);
    s.velocity = Vec2(v[0], v[1]);
    if (n.has("yaw_rate")) s.yaw_rate = n.at("yaw_rate").number();
    ++kinds;
  } else if (n.has("yaw_rate")) {
    s.kind = PilotStep::Kind::kVelocity;
    s.yaw_rate = n.at("yaw_rate").number();
    ++kinds;
  }
  if (n.has("position")) {
    s.kind = PilotStep::Kind::kPosition;
    const auto p = n.at("position").numbers(3);
    s.position = Vec3(p[0], p[1], p[2]);
    if (n.has("yaw_deg")) s.yaw = n.at("yaw_deg").number() * kDeg;
    ++kinds;
  }
  if (n.has("land")) {
    if (!n.at("land").boolean()) n.at("land").fail("must be true (omit the step otherwise)");
    s.kind = PilotStep::Kind::kLand;
    ++kinds;
  }
  if (kinds != 1) n.fail("a pilot step needs exactly one of takeoff, hover, velocity/yaw_rate, position, land");
  if (n.has("duration")) {
    if (s.kind == PilotStep::Kind::kHover) n.at("duration").fail("hover takes its duration as its value");
    s.duration_s = n.at("duration").positive();
  }
  if (n.has("until")) {
    s.until = n.at("until").text();
    if (s.until != "contact") n.at("until").fail("must be 'contact', got '" + s.until + "'");
    s.timeout_s = n.has("timeout") ? n.at("timeout").positive() : std::numeric_limits<double>::infinity();
  } else if (n.has("timeout")) {
    n.at("timeout").fail("only valid together with 'until'");
  }
  if ((s.kind == PilotStep::Kind::kVelocity) && !std::isfinite(s.duration_s) && s.until.empty()) {
    n.fail("a velocity step needs a duration or an 'until' condition");
  }
  return s;
}

FaultSpec parse_fault(const Node& n) {
  n.allow_only({"type", "topic", "channel", "start_s", "duration_s", "probability", "magnitude", "delay_s"});
  FaultSpec f;
  const std::string type = n.at("type").text();
  static const std::map<std::string, FaultSpec::Type> types = {
      {"dropout", FaultSpec::Type::kDropout}, {"nan", FaultSpec::Type::kNan},
      {"out_of_range", FaultSpec::Type::kOutOfRange}, {"stuck", FaultSpec::Type::kStuck},
      {"spike", FaultSpec::Type::kSpike}, {"latency", FaultSpec::Type::kLatency},
      {"loss", FaultSpec::Type::kLoss}};
  auto it = types.find(type);
  if (it == types.end()) {
    n.at("type").fail("unknown fault '" + type +
                      "' (dropout, nan, out_of_range, stuck, spike, latency, loss)");
  }
  f.type = it->second;
  // Stored relative, as the simulator publishes it: a leading '/' (the root namespace, the
  // names the standalone host records in its bags) is accepted and dropped.
  f.topic = n.at("topic").text();
  if (!f.topic.empty() && f.topic.front() == '/') f.topic.erase(0, 1);
  if (f.topic.empty() || f.topic.front() == '/' || f.topic.back() == '/') {
    n.at("topic").fail("must name a topic of the simulator's, e.g. whisker/left/pressure");
  }
  // The channel's upper bound depends on the topic's message type: SimLogic checks it.
  if (n.has("channel")) f.channel = static_cast<int>(n.at("channel").whole(0, kMaxFaultChannel));
  if (n.has("start_s")) f.start_s = n.at("start_s").non_negative();
  if (n.has("duration_s")) f.duration_s = n.at("duration_s").positive();
  if (n.has("probability")) {
    f.probability = n.at("probability").number();
    if (f.probability < 0 || f.probability > 1) n.at("probability").fail("must be in [0, 1]");
  }
  if (n.has("magnitude")) f.magnitude = n.at("magnitude").number();
  if (n.has("delay_s")) f.delay_s = n.at("delay_s").positive();
  if (f.type == FaultSpec::Type::kLatency && !n.has("delay_s")) n.fail("a latency fault needs delay_s");
  if (f.type == FaultSpec::Type::kSpike && !n.has("magnitude")) n.fail("a spike fault needs magnitude");
  if (f.type == FaultSpec::Type::kDropout && !n.has("duration_s")) n.fail("a dropout fault needs duration_s");
  if (f.type == FaultSpec::Type::kStuck && !n.has("duration_s")) n.fail("a stuck fault needs duration_s");
  return f;
}

std::string read_file(const std::string& path, const std::string& who) {
  // An ifstream opens a directory and reads nothing, which then parsed as an empty map.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ScenarioError(who + ": '" + path + "' is a directory, not a file (a directory of scenarios is flown by "
                              "`tactile sweep DIR`)");
  }
  std::ifstream in(path);
  if (!in) throw ScenarioError(who + ": cannot open '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

const char* to_string(VehicleType type) {
  switch (type) {
    case VehicleType::kWhiskerCrazyflie: return "whisker_crazyflie";
    case VehicleType::kXplorer: return "xplorer";
    case VehicleType::kDuctedQuadrotor: return "ducted_quadrotor";
    case VehicleType::kWhiskerStage: return "whisker_stage";
  }
  return "?";
}

const char* to_string(FaultSpec::Type type) {
  switch (type) {
    case FaultSpec::Type::kDropout: return "dropout";
    case FaultSpec::Type::kNan: return "nan";
    case FaultSpec::Type::kOutOfRange: return "out_of_range";
    case FaultSpec::Type::kStuck: return "stuck";
    case FaultSpec::Type::kSpike: return "spike";
    case FaultSpec::Type::kLatency: return "latency";
    case FaultSpec::Type::kLoss: return "loss";
  }
  return "?";
}

Scenario load_scenario_from_string(const std::string& yaml, const std::string& source,
                                   const std::string& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ScenarioError(source + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                        ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  const Node top(root, source, "");
  top.allow_only({"name", "description", "duration_s", "physics_rate_hz", "seed", "arena", "arena_file",
                  "arena_transform", "randomize", "vehicle", "graph", "pilot", "faults", "node_parameters",
                  "metrics"});
  Scenario s;
  s.source = source;
  s.name = top.at("name").text();
  if (top.has("description")) s.description = top.at("description").text();
  s.duration_s = top.at("duration_s").positive();
  if (s.duration_s > kMaxDurationS) {
    top.at("duration_s").fail("must be <= " + std::to_string(static_cast<int>(kMaxDurationS)) +
                              " s (one simulated day), got " + top.at("duration_s").raw().Scalar());
  }
  if (top.has("physics_rate_hz")) {
    s.physics_rate_hz = top.at("physics_rate_hz").positive();
    if (s.physics_rate_hz < 500.0) top.at("physics_rate_hz").fail("must be >= 500 Hz");
    if (s.physics_rate_hz > kMaxPhysicsRateHz) {
      top.at("physics_rate_hz").fail("must be <= " + std::to_string(static_cast<int>(kMaxPhysicsRateHz)) +
                                     " Hz, got " + top.at("physics_rate_hz").raw().Scalar());
    }
    const double per_500hz = s.physics_rate_hz / 500.0;
    if (std::abs(per_500hz - std::round(per_500hz)) > 1e-9) {
      top.at("physics_rate_hz").fail("must be a multiple of 500 Hz (every sensor rate divides it)");
    }
  }
  if (top.has("seed")) s.seed = top.at("seed").whole(0, std::numeric_limits<uint64_t>::max());

  // Arena: inline or a file relative to the scenario.
  if (top.has("arena") == top.has("arena_file")) top.fail("needs exactly one of 'arena' or 'arena_file'");
  if (top.has("arena")) {
    top.at("arena").require_map();
    YAML::Emitter out;
    out << root["arena"];
    s.arena_yaml = out.c_str();
    s.arena_source = source;
    s.arena_key = "arena.";
  } else {
    const std::string rel = top.at("arena_file").text();
    const std::filesystem::path p = std::filesystem::path(rel).is_absolute()
                                        ? std::filesystem::path(rel)
                                        : std::filesystem::path(base_dir) / rel;
    if (!std::filesystem::exists(p)) top.at("arena_file").fail("file '" + p.string() + "' not found");
    s.arena_yaml = read_file(p.string(), source);
    s.arena_source = p.string();
    s.arena_key = "";
  }
  if (top.has("arena_transform")) {
    const Node t = top.at("arena_transform");
    t.allow_only({"x", "y", "yaw_deg"});
    if (t.has("x")) s.arena_x = t.at("x").number();
    if (t.has("y")) s.arena_y = t.at("y").number();
    if (t.has("yaw_deg")) s.arena_yaw = t.at("yaw_deg").number() * kDeg;
  }
  if (top.has("randomize")) {
    const Node r = top.at("randomize");
    r.allow_only({"arena_yaw_deg"});
    if (r.has("arena_yaw_deg")) {
      const auto v = r.at("arena_yaw_deg").numbers(2);
      if (v[1] < v[0]) r.at("arena_yaw_deg").fail("expected [min, max] with min <= max");
      s.randomize_arena_yaw = std::make_pair(v[0] * kDeg, v[1] * kDeg);
    }
  }

  const Node v = top.at("vehicle");
  v.allow_only({"type", "initial", "state_estimate", "params"});
  const std::string type = v.at("type").text();
  if (type == "whisker_crazyflie") {
    s.vehicle = VehicleType::kWhiskerCrazyflie;
  } else if (type == "xplorer") {
    s.vehicle = VehicleType::kXplorer;
  } else if (type == "ducted_quadrotor") {
    s.vehicle = VehicleType::kDuctedQuadrotor;
  } else if (type == "whisker_stage") {
    s.vehicle = VehicleType::kWhiskerStage;
  } else {
    v.at("type").fail("unknown vehicle '" + type + "' (whisker_crazyflie, xplorer, ducted_quadrotor, whisker_stage)");
  }
  if (v.has("initial")) {
    const Node i = v.at("initial");
    i.allow_only({"x", "y", "z", "yaw_deg"});
    if (i.has("x")) s.initial_position.x() = i.at("x").number();
    if (i.has("y")) s.initial_position.y() = i.at("y").number();
    if (i.has("z")) s.initial_position.z() = i.at("z").non_negative();
    if (i.has("yaw_deg")) s.initial_yaw = i.at("yaw_deg").number() * kDeg;
  }
  if (v.has("state_estimate")) {
    s.state_estimate = v.at("state_estimate").text();
    if (s.state_estimate != "mocap" && s.state_estimate != "flow_deck" && s.state_estimate != "imu_tof") {
      v.at("state_estimate").fail("must be 'mocap', 'flow_deck' or 'imu_tof', got '" + s.state_estimate + "'");
    }
    if (s.state_estimate != "mocap" && s.vehicle != VehicleType::kWhiskerCrazyflie) {
      v.at("state_estimate").fail(s.state_estimate + " is the whiskered Crazyflie's estimator");
    }
  }
  if (v.has("params")) {
    const Node p = v.at("params");
    p.require_map();
    for (const auto& kv : p.raw()) {
      const std::string key = p.key_of(kv.first);
      s.vehicle_params[key] = Node(kv.second, source, p.key_path(key)).param_value();
    }
  }

  if (top.has("graph")) {
    s.graph = top.at("graph").text();
    // The graphs themselves are the host's (tactile sim's graph registry),
    // which checks the name and the vehicle; here only the form.
    if (s.graph.empty() || s.graph.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos) {
      top.at("graph").fail("expected a graph name of lower-case letters, digits and '_', got '" + s.graph + "'");
    }
  }
  if (top.has("pilot")) {
    const Node p = top.at("pilot");
    for (size_t i = 0; i < p.size(); ++i) s.pilot.push_back(parse_step(p[i]));
  }
  if (s.graph == "pilot" && s.pilot.empty()) top.fail("graph 'pilot' needs a non-empty 'pilot' script");
  if (s.graph != "pilot" && !s.pilot.empty()) top.at("pilot").fail("only used with graph: pilot (graph is '" + s.graph + "')");
  if (top.has("faults")) {
    const Node f = top.at("faults");
    for (size_t i = 0; i < f.size(); ++i) s.faults.push_back(parse_fault(f[i]));
  }
  if (top.has("node_parameters")) {
    const Node np = top.at("node_parameters");
    np.require_map();
    for (const auto& node : np.raw()) {
      const std::string name = np.key_of(node.first);
      const Node params(node.second, source, np.key_path(name));
      params.require_map();
      for (const auto& kv : params.raw()) {
        const std::string key = params.key_of(kv.first);
        s.node_parameters[name][key] = Node(kv.second, source, params.key_path(key)).param_value();
      }
    }
  }
  if (top.has("metrics")) {
    const Node m = top.at("metrics");
    // The keys the graphs read (tactile_cli: sim_graph.cpp, graphs/, evaluate.cpp); a
    // misspelt key (`alow_collisions`) is an error, never ignored.
    m.allow_only({"target", "goal", "allow_collisions", "depth_evaluation", "box_size", "area_accuracy_of",
                  "min_area_accuracy", "min_traversed_m"});
    for (const auto& kv : m.raw()) {
      const std::string key = m.key_of(kv.first);
      s.metrics[key] = Node(kv.second, source, m.key_path(key)).param_value();
    }
  }
  return s;
}

Scenario load_scenario(const std::string& path) {
  const std::string text = read_file(path, path);
  return load_scenario_from_string(text, path, std::filesystem::path(path).parent_path().string());
}

}  // namespace tactile_sim
