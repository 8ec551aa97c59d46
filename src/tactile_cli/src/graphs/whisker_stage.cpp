// Graph `whisker_stage` (paper 002): the nitinol whisker on the simulated
// linear stage (vehicle whisker_stage, base moments from the elastica model
// with Hall noise) driven through a bench protocol by the stage controller
// of this graph:
// - table2 (002 Table II): five sweeps with tip contact along the arena's
//   concave boundary, each from its known start (Sec. VII-D); the
//   whisker_localization node localizes the stage from /whisker/base_wrench
//   and /odom in the known map (the arena's walls, written to known_map.yaml
//   in the run directory); scored per sweep against the stage's truth with
//   whisker_localization::SweepScore (the same score as the protocol runner);
// - table1 (002 Table I): the arena's pin at p_x on the whisker axis, the
//   stage moved laterally by t_y from the first touch, the contact distance
//   by temporal filtering (002 eq. 21) and by eq. 5, per sample.
// The sweep geometry, the protocol defaults and the score are
// whisker_localization's (stage_sim.hpp); this file only sequences the stage.
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "graphs.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/geometry.hpp"
#include "tactile_common/time.hpp"
#include "tactile_sim/whisker_stage.hpp"
#include "whisker_localization/contact_estimation.hpp"
#include "whisker_localization/stage_sim.hpp"

namespace tactile_cli::graphs {

namespace {

namespace wl = whisker_localization;
using nlohmann::json;

json finite_or_null(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

/// Parameters of the stage controller (node_parameters.whisker_stage_protocol),
/// defaults from whisker_localization's protocol structs.
tactile_common::ParamMap protocol_defaults() {
  const wl::Table1Params t1;
  const wl::Table2Params t2;
  auto mm = [](std::vector<double> v) {
    for (auto& x : v) x *= 1e3;
    return v;
  };
  tactile_common::ParamMap m("whisker_stage_protocol", "defaults");
  m.set("protocol", std::string("table2"));
  m.set("sweep_starts_mm", mm(t2.sweep_starts));
  m.set("steps", static_cast<int64_t>(t2.steps));
  m.set("step_mm", t2.step * 1e3);
  m.set("fillet_radius_mm", t2.fillet_radius * 1e3);
  m.set("attack_deg", t2.attack_deg);
  m.set("penetration_mm", t2.penetration * 1e3);
  m.set("retract_mm", 20.0);  // back off along the whisker between sweeps / rows; choice
  m.set("contacts_mm", mm(t1.contacts));
  m.set("displacements_mm", mm(t1.displacements));
  m.set("trials", static_cast<int64_t>(t1.trials));
  return m;
}

geometry_msgs::msg::PoseStamped setpoint(const wl::Pose2& p, double z, int64_t now_ns) {
  geometry_msgs::msg::PoseStamped m;
  tactile_common::to_stamp(now_ns, m.header.stamp);
  m.header.frame_id = "odom";  // the stage's encoders: its odometry frame (REP 105; was map)
  m.pose.position.x = p.x;
  m.pose.position.y = p.y;
  m.pose.position.z = z;
  m.pose.orientation.z = std::sin(0.5 * p.theta);
  m.pose.orientation.w = std::cos(0.5 * p.theta);
  return m;
}

wl::Pose2 planar(const geometry_msgs::msg::Pose& p) {
  return {p.position.x, p.position.y, tactile_common::yaw_of(p.orientation)};
}

/// Base pose moved by (dx, dy) in its own frame.
wl::Pose2 offset(const wl::Pose2& p, double dx, double dy) { return wl::compose(p, wl::Pose2{dx, dy, 0.0}); }

class WhiskerStageGraph : public SimGraph {
 public:
  explicit WhiskerStageGraph(GraphContext& ctx) : source_(ctx.scenario.source), z_(ctx.scenario.initial_position.z()) {
    tactile_common::ParamMap p = protocol_defaults();
    p.merge_from(ctx.overrides("whisker_stage_protocol"));
    protocol_ = p.get_string("protocol");
    t2_.sweep_starts = p.get_double_array("sweep_starts_mm");
    for (auto& x : t2_.sweep_starts) x *= 1e-3;
    // The protocols' own bounds (Table2Params/Table1Params::validate): an out-of-range
    // value names this node's key and range here, whichever table the scenario runs.
    t2_.steps = p.get_int("steps", 4, std::numeric_limits<int>::max());
    t2_.step = p.get_double("step_mm") * 1e-3;
    t2_.fillet_radius = p.get_double("fillet_radius_mm") * 1e-3;
    t2_.attack_deg = p.get_double("attack_deg");
    t2_.penetration = p.get_double("penetration_mm") * 1e-3;
    retract_ = p.get_double("retract_mm") * 1e-3;
    t1_.contacts = p.get_double_array("contacts_mm");
    for (auto& x : t1_.contacts) x *= 1e-3;
    t1_.displacements = p.get_double_array("displacements_mm");
    for (auto& x : t1_.displacements) x *= 1e-3;
    t1_.trials = p.get_int("trials", 1, std::numeric_limits<int>::max());
    const auto& arena = ctx.sim->arena();
    try {
      if (protocol_ == "table2") {
        t2_.validate();
      } else if (protocol_ == "table1") {
        t1_.validate();
      } else {
        throw p.error("protocol", "must be \"table1\" or \"table2\", got \"" + protocol_ + "\"");
      }
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(source_ + ": node_parameters.whisker_stage_protocol: " + e.what());
    }
    auto& bus = ctx.host.bus();
    bus.subscribe<nav_msgs::msg::Odometry>("/ground_truth/odom", [this](const nav_msgs::msg::Odometry& m) {
      truth_ = planar(m.pose.pose);
      have_truth_ = true;
    });
    if (protocol_ == "table2") {
      build_table2(ctx, arena);
    } else {
      build_table1(ctx, arena);
    }
    ctx.host.executor().add_timer(
        tactile_common::from_seconds(0.01), [this, h = &ctx.host](int64_t now_ns) { tick(*h, now_ns); },
        ctx.host.executor().now_ns());
  }

  json metrics() const override {
    json m;
    m["protocol"] = protocol_;
    m["finished"] = done_;
    if (protocol_ == "table2") {
      json sweeps = json::array();
      double sum = 0.0, worst = 0.0;
      for (const auto& s : sweeps_) {
        sweeps.push_back({{"sweep_id", s.id},
                          {"mean_localization_error_mm", finite_or_null(s.mean_error_mm)},
                          {"std_localization_error_mm", finite_or_null(s.std_error_mm)},
                          {"localizing_steps", s.localizing_steps},
                          {"final_error_mm", finite_or_null(s.final_error_mm)},
                          {"final_spread_mm", finite_or_null(s.final_spread_mm)},
                          {"final_set_size", s.final_set_size},
                          {"truth_kept_fraction", s.truth_kept_fraction},
                          {"resets", s.resets},
                          {"profile_points", s.profile_points},
                          {"profile_mean_error_mm", s.profile_mean_error_mm},
                          {"profile_max_error_mm", s.profile_max_error_mm}});
        sum += s.mean_error_mm;
        worst = std::max(worst, s.mean_error_mm);
      }
      m["variant"] = loc_->params().localizer.possibilistic ? "possibilistic" : "deterministic";
      m["sweeps"] = sweeps;
      m["mean_localization_error_mm"] = sweeps_.empty() ? json(nullptr) : finite_or_null(sum / static_cast<double>(sweeps_.size()));
      m["max_sweep_localization_error_mm"] = sweeps_.empty() ? json(nullptr) : finite_or_null(worst);
      double kept = 0.0;
      for (const auto& s : sweeps_) kept += s.truth_kept_fraction / static_cast<double>(sweeps_.size());
      m["truth_kept_fraction"] = sweeps_.empty() ? json(nullptr) : json(kept);
      m["samples_skipped_small_motion"] = loc_->stats().skipped_small_motion;
    } else {
      json rows = json::array();
      double worst = 0.0, worst_base = 0.0;
      for (const auto& r : rows_) {
        rows.push_back({{"p_x_mm", r.p_x * 1e3},
                        {"t_y_mm", r.t_y * 1e3},
                        {"m0_mNm", r.m0 * 1e3},
                        {"ours_distance_mm", finite_or_null(r.ours_mean * 1e3)},
                        {"ours_error_pct", finite_or_null(r.ours_error_pct)},
                        {"baseline_distance_mm", r.baseline_mean * 1e3},
                        {"baseline_error_pct", r.baseline_error_pct},
                        {"ours_failures", r.ours_failures}});
        worst = std::max(worst, std::isfinite(r.ours_error_pct) ? r.ours_error_pct : 1e9);
        worst_base = std::max(worst_base, r.baseline_error_pct);
      }
      m["table1"] = rows;
      m["max_ours_error_pct"] = rows_.empty() ? json(nullptr) : json(worst);
      m["max_baseline_error_pct"] = rows_.empty() ? json(nullptr) : json(worst_base);
    }
    return m;
  }

  std::optional<bool> reached_goal() const override { return done_; }

 private:
  struct Leg {
    wl::Pose2 target;
    int kind = 0;  ///< 0 travel, 1 sweep start (restart the localizer), 2 sweep, 3 touch, 4 measure
    int index = 0;
  };

  void build_table2(GraphContext& ctx, const tactile_sim::Arena& arena) {
    // The known map: the arena's walls (002 Sec. VII-B), as a map file.
    const auto lines = tactile_sim::wall_polylines(arena);
    if (lines.empty()) throw std::runtime_error(source_ + ": arena: the table2 protocol needs the concave boundary as walls");
    std::filesystem::create_directories(ctx.out_dir);
    const auto map_path = ctx.out_dir / "known_map.yaml";
    {
      std::ofstream f(map_path);
      f.precision(9);
      f << "# The whisker_stage arena's walls: the known map of the localization (002 Sec. VII-B).\npolylines:\n";
      for (const auto& l : lines) {
        f << "  - [";
        for (std::size_t i = 0; i < l.size(); ++i) f << (i ? ", " : "") << "[" << l[i][0] << ", " << l[i][1] << "]";
        f << "]\n";
      }
      if (!f) throw std::runtime_error(map_path.string() + ": cannot write");
    }
    world_ = std::make_unique<wl::BoundaryMap>(lines, 0.001);
    tactile_common::ParamMap extra;
    extra.set("map_file", map_path.string());
    loc_ = add_whisker_localization(ctx.host, ctx.overrides("whisker_localization", extra));
    // The protocol's boundary must be the arena's: every sweep starts on it.
    for (std::size_t i = 0; i < t2_.sweep_starts.size(); ++i) {
      double x, y, t;
      wl::concave_corner_point(t2_.fillet_radius, t2_.sweep_starts[i], x, y, t);
      if (std::fabs(world_->signed_distance(x, y)) > 5e-4) {
        throw std::runtime_error(source_ + ": arena: sweep " + std::to_string(i + 1) + " starts at (" + std::to_string(x) +
                                 ", " + std::to_string(y) + "), not on the arena's walls (the protocol's concave "
                                 "corner with fillet_radius_mm must be the arena's boundary)");
      }
      wl::Pose2 start, motion;
      wl::table2_sweep(t2_, i, start, motion);
      legs_.push_back({offset(start, -retract_, 0.0), 0, static_cast<int>(i)});
      legs_.push_back({start, 1, static_cast<int>(i)});
      wl::Pose2 end = start;
      for (int k = 1; k < t2_.steps; ++k) end = wl::compose(end, motion);
      legs_.push_back({end, 2, static_cast<int>(i)});
      legs_.push_back({offset(end, -retract_, 0.0), 0, static_cast<int>(i)});
    }
    ctx.host.bus().subscribe<tactile_msgs::msg::LocalizationResult>(
        wl::WhiskerLocalizationLogic::kResultTopic,
        [this](const tactile_msgs::msg::LocalizationResult& r) { on_result(r); });
  }

  void build_table1(GraphContext& ctx, const tactile_sim::Arena& arena) {
    (void)ctx;
    const tactile_sim::Cylinder* pin = nullptr;
    for (const auto& c : arena.cylinders()) {
      if (c.radius <= tactile_sim::WhiskerStageParams{}.pin_radius) {
        pin = &c;
        break;
      }
    }
    if (!pin) throw std::runtime_error(source_ + ": arena: the table1 protocol needs a pin (a cylinder of radius <= 2 mm)");
    pin_ = wl::Pose2{pin->center.x(), pin->center.y(), 0.0};
    solver_ = std::make_unique<wl::ElasticaSolver>(t1_.beam);
    sensors_ = std::make_unique<wl::VirtualSensors>(*solver_, t1_.sets);
    wl::TemporalFilterParams tf;
    tf.contact_threshold = 0.0;
    filter_ = std::make_unique<wl::TemporalContactFilter>(*sensors_, tf);
    // Whisker along +x; the pin approaches from the whisker's right (-y).
    int row = 0;
    for (double t : t1_.displacements) {
      for (double px : t1_.contacts) {
        const wl::Pose2 touch{pin_.x - px, pin_.y, 0.0};
        legs_.push_back({offset(touch, 0.0, retract_), 0, row});
        legs_.push_back({touch, 3, row});
        legs_.push_back({offset(touch, 0.0, -t), 4, row});
        legs_.push_back({offset(touch, 0.0, retract_), 0, row});
        rows_.push_back(wl::Table1Row{});
        rows_.back().p_x = px;
        rows_.back().t_y = t;
        ++row;
      }
    }
    ctx.host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
        wl::WhiskerLocalizationLogic::kMomentTopic, [this](const geometry_msgs::msg::WrenchStamped& w) { on_moment(w); });
    ctx.host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
        "/ground_truth/whisker/base_wrench", [this](const geometry_msgs::msg::WrenchStamped& w) { true_m0_ = w.wrench.torque.z; });
  }

  bool arrived(const wl::Pose2& target) const {
    return have_truth_ && std::hypot(truth_.x - target.x, truth_.y - target.y) < 1e-6 &&
           std::fabs(wl::wrap_angle(truth_.theta - target.theta)) < 1e-6;
  }

  void tick(Host& host, int64_t now_ns) {
    if (done_) return;
    if (leg_ >= legs_.size()) {
      finish_sweep();
      done_ = true;
      host.executor().stop();
      return;
    }
    Leg& leg = legs_[leg_];
    if (leg.kind == 4 && measuring_) {
      if (samples_ >= t1_.trials) {  // enough samples at the displaced pose
        measuring_ = false;
        finish_row(leg.index);
        ++leg_;
      }
    } else if (arrived(leg.target) && !(leg.kind == 3 && !touched_)) {
      if (leg.kind == 1) {  // at the sweep's known start (002 Sec. VII-D)
        finish_sweep();
        sweep_ = leg.index;
        score_ = std::make_unique<wl::SweepScore>(sweep_ + 1, t2_);
        sweep_start_ = leg.target;
        resets0_ = loc_->stats().resets;
        loc_->restart(&leg.target);
        sweeping_ = true;
      } else if (leg.kind == 2) {
        sweeping_ = false;
      } else if (leg.kind == 4) {
        measuring_ = true;
        samples_ = 0;
        return;
      }
      ++leg_;
    }
    if (leg_ < legs_.size()) host.bus().publish(tactile_sim::SimLogic::kPositionSetpointTopic, setpoint(legs_[leg_].target, z_, now_ns), now_ns);
  }

  // Table II: score every localization result of the sweep against the truth.
  void on_result(const tactile_msgs::msg::LocalizationResult& r) {
    if (!sweeping_ || !score_ || !have_truth_) return;
    if (r.pose_set.poses.empty()) return;  // not localizing yet (>= slope_samples observations)
    std::vector<wl::Pose2> set;
    set.reserve(r.pose_set.poses.size());
    for (const auto& q : r.pose_set.poses) set.push_back(planar(q));
    const wl::Pose2 best = planar(r.best_estimate);
    const double along = std::hypot(truth_.x - sweep_start_.x, truth_.y - sweep_start_.y);
    const double length = t2_.step * (t2_.steps - 1);
    score_->add(truth_, set, best, r.spread, steps_++, along >= 0.5 * length);
    if (r.contact_valid) score_->add_profile_point(*world_, truth_, r.contact_point.x, r.contact_point.y);
  }

  void finish_sweep() {
    if (!score_) return;
    sweeps_.push_back(score_->finish(steps_, loc_->stats().resets - resets0_));
    score_.reset();
    steps_ = 0;
  }

  // Table I: the touch sample (undeformed axis, eq. 21's first set), then
  // `trials` samples after the lateral move, each one estimate.
  void on_moment(const geometry_msgs::msg::WrenchStamped& w) {
    if (leg_ >= legs_.size()) return;
    const Leg& leg = legs_[leg_];
    if (leg.kind == 3 && arrived(leg.target)) {
      touched_ = true;
      touch_ = truth_;
      return;
    }
    if (leg.kind != 4 || !measuring_ || samples_ >= t1_.trials) return;
    // Base motion since the touch, in the touch frame (pure translation).
    const double c = std::cos(touch_.theta), s = std::sin(touch_.theta);
    const double dx = truth_.x - touch_.x, dy = truth_.y - touch_.y;
    const double mx = c * dx + s * dy, my = -s * dx + c * dy;
    const double m0 = w.wrench.torque.z;
    auto& row = rows_[static_cast<std::size_t>(leg.index)];
    filter_->reset();
    filter_->start_from_touch();
    const wl::ContactEstimate e = filter_->update(m0, mx, my);
    if (e.status == wl::ContactEstimate::Status::kEstimated) {
      ++ok_;
      sum_ += e.x;
      sum_err_ += std::fabs(e.x - row.p_x) / row.p_x * 100.0;
    }
    const double d = wl::baseline_distance(t1_.beam.ei_base(), std::fabs(my), std::fabs(m0));  // 002 eq. 5
    sum_base_ += d;
    sum_berr_ += std::fabs(d - row.p_x) / row.p_x * 100.0;
    m0_sum_ += true_m0_;
    ++samples_;
  }

  void finish_row(int index) {
    auto& row = rows_[static_cast<std::size_t>(index)];
    const int n = std::max(1, samples_);
    row.m0 = m0_sum_ / n;
    row.ours_failures = samples_ - ok_;
    row.ours_mean = ok_ > 0 ? sum_ / ok_ : std::nan("");
    row.ours_error_pct = ok_ > 0 ? sum_err_ / ok_ : std::nan("");
    row.baseline_mean = sum_base_ / n;
    row.baseline_error_pct = sum_berr_ / n;
    ok_ = 0;
    sum_ = sum_err_ = sum_base_ = sum_berr_ = m0_sum_ = 0.0;
    touched_ = false;
  }

  std::string source_;
  double z_ = 0.0;
  std::string protocol_;
  wl::Table1Params t1_;
  wl::Table2Params t2_;
  double retract_ = 0.02;
  std::vector<Leg> legs_;
  std::size_t leg_ = 0;
  bool done_ = false;
  wl::Pose2 truth_;
  bool have_truth_ = false;
  // table2
  std::shared_ptr<wl::WhiskerLocalizationLogic> loc_;
  std::unique_ptr<wl::BoundaryMap> world_;
  std::unique_ptr<wl::SweepScore> score_;
  std::vector<wl::Table2Sweep> sweeps_;
  wl::Pose2 sweep_start_;
  int sweep_ = -1, steps_ = 0;
  uint64_t resets0_ = 0;
  bool sweeping_ = false;
  // table1
  wl::Pose2 pin_, touch_;
  std::unique_ptr<wl::ElasticaSolver> solver_;
  std::unique_ptr<wl::VirtualSensors> sensors_;
  std::unique_ptr<wl::TemporalContactFilter> filter_;
  std::vector<wl::Table1Row> rows_;
  bool touched_ = false, measuring_ = false;
  int samples_ = 0, ok_ = 0;
  double sum_ = 0.0, sum_err_ = 0.0, sum_base_ = 0.0, sum_berr_ = 0.0, m0_sum_ = 0.0, true_m0_ = 0.0;
};

}  // namespace

GraphInfo whisker_stage_graph() {
  GraphInfo g;
  g.name = "whisker_stage";
  g.description = "whisker on a linear stage: 002 Table I contact estimation or Table II sweeps with whisker_localization";
  g.vehicles = {tactile_sim::VehicleType::kWhiskerStage};
  g.nodes = {"whisker_localization", "whisker_stage_protocol"};
  g.metrics_key = "whisker_localization";
  g.summary_metrics = {"whisker_localization.mean_localization_error_mm",
                       "whisker_localization.max_sweep_localization_error_mm",
                       "whisker_localization.max_ours_error_pct"};
  g.build = [](GraphContext& ctx) { return std::make_unique<WhiskerStageGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
