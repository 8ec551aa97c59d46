// Graph `xplorer` (paper 001): xplorer_force_est -> xplorer_fsm (admittance,
// exploration FSM, static wrench, ricocheting or waypoint flight) ->
// position setpoints, and xplorer_mapping building the contact map. Metrics:
// force estimate vs the simulated contact force (static wrench), the map's
// dimensions and area (exploration), rise and settling times (ricochet,
// waypoint). Outputs: map.ply (ASCII, as 001) and map_binary.ply.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

#include "graphs.hpp"
#include "tactile_common/time.hpp"
#include "xplorer_area.hpp"
#include "xplorer_nodes.hpp"

namespace tactile_cli::graphs {

namespace {

using tactile_fsm::XplorerMission;
using tactile_fsm::XplorerState;

struct ForceSample {
  double t;
  Eigen::Vector3d fused, com;
};
struct TruthSample {
  double t;
  Eigen::Vector3d f;
};

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

class XplorerGraph : public SimGraph {
 public:
  explicit XplorerGraph(GraphContext& ctx) : sim_(ctx.sim), scenario_(ctx.scenario) {
    force_ = add_xplorer_force_est(ctx.host, ctx.overrides("xplorer_force_est"));
    tactile_common::ParamMap extra;
    if (auto g = ctx.target("goal")) extra.set("goal", std::vector<double>{g->x(), g->y()});
    fsm_ = add_xplorer_fsm(ctx.host, ctx.overrides("xplorer_fsm", extra));
    tactile_common::ParamMap map_extra;
    map_extra.set("floor_z", sim_->arena().floor_z());
    map_extra.set("publish_rate_hz", 0.1);  // the whole map every 10 s: keeps recorded bags small
    map_ = add_xplorer_mapping(ctx.host, ctx.overrides("xplorer_mapping", map_extra));
    area_goal_ = XplorerAreaGoal::from(ctx.scenario);
    auto it = ctx.scenario.metrics.find("min_traversed_m");
    if (it != ctx.scenario.metrics.end()) {
      const double* d = std::get_if<double>(&it->second);
      if (!d || !(*d > 0)) throw std::runtime_error(ctx.scenario.source + ": metrics.min_traversed_m: must be a number > 0 [m]");
      min_traversed_m_ = *d;
    }
    Host* h = &ctx.host;
    ctx.host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
        "/ground_truth/external_force", [this, h](const geometry_msgs::msg::WrenchStamped& m) {
          truth_.push_back({tactile_common::to_seconds(h->executor().now_ns()),
                            Eigen::Vector3d(m.wrench.force.x, m.wrench.force.y, m.wrench.force.z)});
        });
    ctx.host.bus().subscribe<geometry_msgs::msg::WrenchStamped>(
        xplorer_force_est::XplorerForceEstLogic::kWrenchWorldTopic,
        [this, h](const geometry_msgs::msg::WrenchStamped& m) {
          forces_.push_back({tactile_common::to_seconds(h->executor().now_ns()),
                             Eigen::Vector3d(m.wrench.force.x, m.wrench.force.y, m.wrench.force.z),
                             force_->estimate().com_world});
        });
    ctx.host.bus().subscribe<tactile_msgs::msg::ThrustCommand>(
        xplorer_force_est::XplorerForceEstLogic::kThrustTopic,
        [this](const tactile_msgs::msg::ThrustCommand& t) { last_thrust_ = t.total_thrust; });
    ctx.host.bus().subscribe<tactile_msgs::msg::FsmState>(
        tactile_fsm::XplorerFsmLogic::kStateTopic, [this, h](const tactile_msgs::msg::FsmState& m) {
          if (states_.empty() || states_.back().second != m.state)
            states_.emplace_back(tactile_common::to_seconds(h->executor().now_ns()), m.state);
        });
  }

  nlohmann::json metrics() const override {
    nlohmann::json m;
    const auto& f = fsm_->fsm();
    const auto mission = fsm_->params().fsm.mission;
    m["mission"] = tactile_fsm::to_string(mission);
    m["final_state"] = tactile_fsm::to_string(f.state());
    m["transitions"] = f.transitions();
    // The shared fail-safe (NOMINAL unless an input went stale) and the vehicle's last
    // reported collective thrust: below hover once a FAILSAFE_LAND rests on the floor.
    m["failsafe_state"] = tactile_fsm::to_string(fsm_->safety().state());
    m["final_thrust_n"] = num(last_thrust_);
    for (const auto& [t, s] : states_) m["state_log"].push_back({{"t", t}, {"state", s}});
    if (mission == XplorerMission::kStaticWrench) static_wrench_metrics(m);
    if (mission == XplorerMission::kExplore) explore_metrics(m);
    if (mission == XplorerMission::kRicochet || mission == XplorerMission::kWaypoint) goal_metrics(m);
    return m;
  }

  std::optional<bool> reached_goal() const override {
    const auto mission = fsm_->params().fsm.mission;
    const auto s = fsm_->fsm().state();
    if (mission == XplorerMission::kExplore) {
      if (min_traversed_m_) return fsm_->fsm().traversed_path() >= *min_traversed_m_;
      if (!fsm_->fsm().loop_closed()) return false;
      if (!area_goal_.min_accuracy) return true;
      const auto acc = map_area().accuracy;
      return acc && *acc >= *area_goal_.min_accuracy;
    }
    if (mission == XplorerMission::kStaticWrench) return s == XplorerState::kStaticWrench;
    return s == XplorerState::kGoTo;
  }

  void decorate(TopView& view) const override {
    const auto& c = map_->map().cloud();
    const size_t step = std::max<size_t>(1, c.size() / 20000);
    for (size_t i = 0; i < c.size(); i += step) view.map_points.emplace_back(c[i].x, c[i].y);
    const auto mission = fsm_->params().fsm.mission;
    if (mission == XplorerMission::kRicochet || mission == XplorerMission::kWaypoint)
      view.targets.push_back(fsm_->params().fsm.goal);
  }

  void write_outputs(const std::filesystem::path& dir) const override {
    {
      // Force estimates next to the simulated truth (latest truth sample at each estimate).
      std::ofstream f(dir / "forces.csv");
      f << "t,fused_x,fused_y,fused_z,com_x,com_y,com_z,true_x,true_y,true_z\n";
      size_t j = 0;
      for (const auto& s : forces_) {
        while (j + 1 < truth_.size() && truth_[j + 1].t <= s.t) ++j;
        const Eigen::Vector3d t = truth_.empty() ? Eigen::Vector3d::Zero() : truth_[j].f;
        f << s.t << ',' << s.fused.x() << ',' << s.fused.y() << ',' << s.fused.z() << ',' << s.com.x() << ','
          << s.com.y() << ',' << s.com.z() << ',' << t.x() << ',' << t.y() << ',' << t.z() << '\n';
      }
    }
    if (map_->map().size() == 0) return;
    mapping_pcl::PlyInfo info;
    info.frame = map_->params().frame_id;
    info.comment = "XPLORER contact map, scenario " + scenario_.name + " (paper 001 Sec. IV-B)";
    mapping_pcl::write_ply((dir / "map.ply").string(), map_->map().cloud(), mapping_pcl::PlyFormat::kAscii, info);
    mapping_pcl::write_ply((dir / "map_binary.ply").string(), map_->map().cloud(),
                           mapping_pcl::PlyFormat::kBinaryLittleEndian, info);
  }

 private:
  /// 001 Sec. V-B: steady-state estimate vs the true contact force; settling of
  /// the fused and the CoM-only estimates; collision peaks.
  void static_wrench_metrics(nlohmann::json& m) const {
    double t_contact = -1;
    for (const auto& s : truth_) {
      if (s.f.head<2>().norm() > 0.05) {
        t_contact = s.t;
        break;
      }
    }
    m["contact_time_s"] = t_contact >= 0 ? nlohmann::json(t_contact) : nlohmann::json(nullptr);
    if (t_contact < 0 || forces_.empty()) return;
    const double t_end = forces_.back().t, window = 3.0;
    Eigen::Vector3d fused = Eigen::Vector3d::Zero(), com = Eigen::Vector3d::Zero(), truth = Eigen::Vector3d::Zero();
    int nf = 0, nt = 0;
    for (const auto& s : forces_) {
      if (s.t >= t_end - window) {
        fused += s.fused;
        com += s.com;
        ++nf;
      }
    }
    for (const auto& s : truth_) {
      if (s.t >= t_end - window) {
        truth += s.f;
        ++nt;
      }
    }
    if (nf == 0 || nt == 0) return;
    fused /= nf;
    com /= nf;
    truth /= nt;
    m["force_estimate_n"] = fused.head<2>().norm();
    m["force_true_n"] = truth.head<2>().norm();
    m["force_reference_n"] = fsm_->params().fsm.static_force;
    m["force_error_n"] = (fused - truth).head<2>().norm();
    m["force_error_com_only_n"] = (com - truth).head<2>().norm();
    // Settling of the estimator: time from the first contact after which the
    // estimate stays within 10 % of the reference (0.1 N) of the true force.
    const double band = 0.1 * fsm_->params().fsm.static_force;
    double out_fused = t_contact, out_com = t_contact;
    size_t j = 0;
    for (const auto& s : forces_) {
      if (s.t < t_contact) continue;
      while (j + 1 < truth_.size() && truth_[j + 1].t <= s.t) ++j;
      const Eigen::Vector2d tr = truth_[j].f.head<2>();
      if ((s.fused.head<2>() - tr).norm() > band) out_fused = s.t;
      if ((s.com.head<2>() - tr).norm() > band) out_com = s.t;
    }
    const double ts_fused = out_fused - t_contact, ts_com = out_com - t_contact;
    m["force_settle_s"] = num(ts_fused);
    m["force_settle_com_only_s"] = num(ts_com);
    m["fusion_faster_than_com"] = ts_fused < ts_com;
    double peak_f = 0, peak_c = 0, peak_t = 0;
    for (const auto& s : forces_) {
      if (s.t >= t_contact && s.t <= t_contact + 1.0) {
        peak_f = std::max(peak_f, s.fused.head<2>().norm());
        peak_c = std::max(peak_c, s.com.head<2>().norm());
      }
    }
    for (const auto& s : truth_) {
      if (s.t >= t_contact && s.t <= t_contact + 1.0) peak_t = std::max(peak_t, s.f.head<2>().norm());
    }
    m["collision_peak_fused_n"] = peak_f;
    m["collision_peak_com_n"] = peak_c;
    m["collision_peak_true_n"] = peak_t;
    m["fusion_keeps_peak"] = peak_f >= 0.9 * peak_c;
  }

  /// 001 Sec. V-C/V-D: loop closure, the mapped obstacle's dimensions and area.
  void explore_metrics(nlohmann::json& m) const {
    const auto& f = fsm_->fsm();
    m["loop_closed"] = f.loop_closed();
    m["loop_closure_time_s"] = f.loop_closed() ? nlohmann::json(f.loop_closure_time()) : nlohmann::json(nullptr);
    m["first_contact_time_s"] = f.first_contact_time() >= 0 ? nlohmann::json(f.first_contact_time()) : nlohmann::json(nullptr);
    m["traversed_path_m"] = f.traversed_path();
    m["turns"] = f.turns();
    m["contact_backoffs"] = f.backoffs();
    add_turn_outcomes(states_, m);
    const auto& ms = map_->mapper().stats();
    m["slabs"] = ms.slabs;
    m["map_raw_points"] = map_->map().size();  // as written to map.ply
    m["corner_slabs"] = ms.corner_slabs;
    m["corner_fills"] = ms.corner_fills;  // mapping_pcl README "Corner fill"
    // The map as exported against the object's footprint: the bounding
    // rectangle (box_size, 001 Sec. V-D) and the convex hull of the arena's
    // walls and cylinders (polygons and cylinders, whose map has no meaningful
    // bounding rectangle; issue 17).
    m.update(map_area().metrics);
  }

  /// The map's area measured once after the flight for reached_goal() and metrics()
  /// (the voxel filter and outlier removal of the whole map); measured again if the map
  /// changed since (its size or the mapper's slab and clip counts).
  struct MapArea {
    std::array<uint64_t, 3> key{};
    nlohmann::json metrics;
    std::optional<double> accuracy;
  };
  const MapArea& map_area() const {
    const auto& st = map_->mapper().stats();
    const std::array<uint64_t, 3> key{map_->map().size(), st.slabs, st.clipped_points};
    if (!area_ || area_->key != key) {
      MapArea a;
      a.key = key;
      a.accuracy = measure_map_area(map_->map(), area_goal_, object_hull_area(sim_->arena()), a.metrics);
      area_ = std::move(a);
    }
    return *area_;
  }

  /// 001 Sec. V-E: rise time (90 % of the start -> goal distance) and settling
  /// time (stays within 5 % of it) from the moment the goal is commanded.
  void goal_metrics(nlohmann::json& m) const {
    double t0 = -1;
    for (const auto& [t, s] : states_) {
      if (s != "takeoff") {
        t0 = t;
        break;
      }
    }
    m["collisions_detected"] = fsm_->fsm().collisions();
    m["collision_peak_n"] = fsm_->fsm().collision_peak();
    if (t0 < 0) return;
    const auto& traj = sim_->trajectory();
    const Eigen::Vector2d goal = fsm_->params().fsm.goal;
    Eigen::Vector2d start = traj.front().truth.position.head<2>();
    for (const auto& p : traj) {
      if (p.t >= t0) {
        start = p.truth.position.head<2>();
        break;
      }
    }
    const double d0 = (goal - start).norm();
    const Eigen::Vector2d dir = (goal - start) / std::max(d0, 1e-9);
    const double band = std::max(0.05 * d0, 0.02);
    double rise = -1, last_out = t0;
    double sq = 0;
    int n = 0;
    for (const auto& p : traj) {
      if (p.t < t0) continue;
      const Eigen::Vector2d x = p.truth.position.head<2>();
      if (rise < 0 && (x - start).dot(dir) >= 0.9 * d0) rise = p.t - t0;
      if ((x - goal).norm() > band) last_out = p.t;
    }
    for (const auto& p : traj) {
      if (p.t >= last_out) {
        sq += (p.truth.position.head<2>() - goal).squaredNorm();
        ++n;
      }
    }
    m["goal"] = {goal.x(), goal.y()};
    m["start"] = {start.x(), start.y()};
    m["distance_m"] = d0;
    m["settling_band_m"] = band;
    m["rise_time_s"] = rise >= 0 ? nlohmann::json(rise) : nlohmann::json(nullptr);
    const bool settled = last_out < traj.back().t - 1.0;
    m["settling_time_s"] = settled ? nlohmann::json(last_out - t0) : nlohmann::json(nullptr);
    m["rmse_after_settling_m"] = n > 0 ? nlohmann::json(std::sqrt(sq / n)) : nlohmann::json(nullptr);
  }

  std::shared_ptr<tactile_sim::SimLogic> sim_;
  const tactile_sim::Scenario& scenario_;
  std::shared_ptr<xplorer_force_est::XplorerForceEstLogic> force_;
  std::shared_ptr<tactile_fsm::XplorerFsmLogic> fsm_;
  std::shared_ptr<mapping_pcl::XplorerMapLogic> map_;
  XplorerAreaGoal area_goal_;
  mutable std::optional<MapArea> area_;
  std::optional<double> min_traversed_m_;
  std::vector<ForceSample> forces_;
  std::vector<TruthSample> truth_;
  std::vector<std::pair<double, std::string>> states_;
  double last_thrust_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace

GraphInfo xplorer_graph() {
  GraphInfo g;
  g.name = "xplorer";
  g.description = "xplorer_force_est -> xplorer_fsm (explore / static_wrench / ricochet / waypoint) + xplorer_mapping (001)";
  g.vehicles = {tactile_sim::VehicleType::kXplorer};
  g.nodes = {"xplorer_force_est", "xplorer_fsm", "xplorer_mapping"};
  g.metrics_key = "xplorer";
  g.build = [](GraphContext& ctx) { return std::make_unique<XplorerGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
