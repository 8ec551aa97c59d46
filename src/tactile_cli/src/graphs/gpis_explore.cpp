// Graph `gpis_explore` (paper 000, "Active aerial tactile exploration"): TDORC x2
// -> tactile_depth -> gpis_explorer (four probes, wall follow, retreat, GPIS
// refit with corner penalties, target, exit) flying the whiskered Crazyflie out
// of an unknown room. Success: the explorer reports the exit and the true final
// position is outside the room (most rays from it escape the arena).
#include "graphs.hpp"

#include <cmath>
#include <cstdio>

#include "gpis_explorer/gpis_plot.hpp"
#include "mapping_pcl/point_map.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/time.hpp"

namespace tactile_cli::graphs {

namespace {

using gpis_explorer::GpisExplorerLogic;

class GpisExploreGraph : public SimGraph {
 public:
  explicit GpisExploreGraph(GraphContext& ctx) : sim_(ctx.sim) {
    // The exploration's parameters against the nodes' files, written once
    // (config/profiles/exploration.yaml; launch/sitl_explore.launch.py passes the same file).
    ctx.host.use_profile("exploration", /*graph_default=*/true);
    add_whisker_front_end(ctx.host, ctx.overrides("tdorc_filter"), ctx.overrides("tactile_depth"));
    explorer_ = add_gpis_explorer(ctx.host, ctx.overrides("gpis_explorer"));
    GpisExplorerLogic* l = explorer_.get();
    ctx.host.bus().subscribe<tactile_msgs::msg::GpisMap>(
        GpisExplorerLogic::kMapTopic, [this, l](const tactile_msgs::msg::GpisMap& m) {
          const auto& seq = l->sequencer();
          gpis_explorer::GpisPicture pic;
          pic.map = m;
          pic.trajectory = seq.trajectory();
          if (seq.has_target()) pic.target = seq.target();
          if (!pic.trajectory.empty()) pic.drone = std::make_pair(pic.trajectory.back(), 0.0);
          for (const auto& c : seq.explorer().last().contours) {
            pic.curvature.insert(pic.curvature.end(), c.curvature.begin(), c.curvature.end());
          }
          char title[160];
          std::snprintf(title, sizeof title, "GPIS update %zu: %zu points, %zu corners, %s",
                        seq.explorer().updates(), seq.explorer().gpis().size(), m.corners.size(),
                        gpis_explorer::to_string(seq.explorer().last().status));
          pic.title = title;
          pictures_.push_back(std::move(pic));
        });
    // Phase log (transitions only) to name the exploration phase of every
    // guard collision in metrics.json (diagnosis of collisions).
    ctx.host.bus().subscribe<tactile_msgs::msg::FsmState>(
        GpisExplorerLogic::kStateTopic, [this](const tactile_msgs::msg::FsmState& s) {
          if (!phases_.empty() && phases_.back().state == s.state && phases_.back().transitions == s.transitions) return;
          phases_.push_back({tactile_common::to_seconds(tactile_common::from_stamp(s.header.stamp)), s.state, s.reason, s.transitions});
        });
  }

  /// Fraction of 72 rays from p that leave the arena without hitting anything.
  double escape_fraction(const tactile_sim::Vec2& p) const {
    int escaped = 0;
    for (int k = 0; k < 72; ++k) {
      const double a = 2.0 * M_PI * k / 72.0;
      if (!sim_->arena().raycast(p, tactile_sim::Vec2(std::cos(a), std::sin(a)), 50.0).hit) ++escaped;
    }
    return escaped / 72.0;
  }

  bool outside() const {
    const auto& traj = sim_->trajectory();
    return !traj.empty() && escape_fraction(traj.back().truth.position.head<2>()) > 0.6;
  }

  double wall_distance(const Eigen::Vector2d& p) const {
    const auto h = sim_->arena().closest(p, 100.0);
    return h.hit ? std::abs(h.distance) : NAN;
  }

  nlohmann::json metrics() const override {
    const auto& seq = explorer_->sequencer();
    const auto& ex = seq.explorer();
    nlohmann::json m;
    m["outcome"] = gpis_explorer::to_string(seq.outcome());
    m["exit_found"] = seq.exit_found();
    m["outside_room"] = outside();
    m["gpis_updates"] = ex.updates();
    m["training_points"] = ex.gpis().size();
    m["surface_points"] = ex.gpis().surface_count();
    m["points_rejected"] = seq.points_rejected();
    m["points_replaced"] = seq.points_replaced();
    m["budget_max_points"] = ex.params().gpis.max_points;
    m["budget_grid_cells"] = ex.params().grid_cells;
    m["state_bytes"] = ex.state_bytes();
    m["corner_aborts"] = seq.corner_aborts();
    m["side_stops"] = seq.side_stops();
    m["staged_targets"] = seq.staged_targets();
    m["unconfirmed_corner_targets"] = seq.unconfirmed_corner_targets();
    m["whisk_contacts"] = seq.whisk_contacts();
    m["whisk_walls"] = seq.whisk_walls();
    m["whisk_jambs"] = seq.whisk_jambs();
    m["beside_contacts"] = seq.beside_contacts();
    m["retreats_held"] = seq.retreats_held();
    m["failsafe_hovers"] = seq.failsafe_hovers();  // stale depth / odometry (FAILSAFE_HOVER entries)
    m["direct_targets"] = seq.direct_targets();
    m["last_update_status"] = gpis_explorer::to_string(ex.last().status);
    // Exploration phase (and why it was entered) at each guard collision.
    nlohmann::json cp = nlohmann::json::array();
    for (const auto& c : sim_->collisions()) {
      const PhaseEntry* e = nullptr;
      for (const auto& p : phases_) {
        if (p.t <= c.time_s + 1e-9) e = &p;
      }
      cp.push_back({{"t", c.time_s}, {"phase", e ? e->state : std::string()}, {"reason", e ? e->reason : std::string()},
                    {"phase_entered", e ? e->t : 0.0}});
    }
    m["collision_phases"] = cp;
    // Travel: true path length (100 Hz trajectory).
    double travel = 0.0;
    const auto& traj = sim_->trajectory();
    for (size_t i = 1; i < traj.size(); ++i) {
      travel += (traj[i].truth.position.head<2>() - traj[i - 1].truth.position.head<2>()).norm();
    }
    m["travel_distance_m"] = travel;
    // Reconstruction error: mean distance of the mapped whisker contact points
    // (odometry frame, as the drone mapped them) to the true walls.
    double sum = 0.0, sum2 = 0.0;
    size_t n = 0;
    for (const auto& c : seq.contacts()) {
      const double d = wall_distance(c.p);
      if (!std::isfinite(d)) continue;
      sum += d;
      sum2 += d * d;
      ++n;
    }
    m["contact_points"] = n;
    m["reconstruction_error_m"] = n ? nlohmann::json(sum / static_cast<double>(n)) : nlohmann::json(nullptr);
    // GPIS contour of the last update vs the true walls (the exit region and
    // unexplored bulges count too).
    double csum = 0.0;
    size_t cn = 0;
    for (const auto& info : ex.last().contours) {
      for (const auto& q : info.contour.points) {
        const double d = wall_distance(q);
        if (!std::isfinite(d)) continue;
        csum += d;
        ++cn;
      }
    }
    m["contour_error_m"] = cn ? nlohmann::json(csum / static_cast<double>(cn)) : nlohmann::json(nullptr);
    // The same contacts as a mapping_pcl map (1 cm voxel filter): points and error.
    const auto map = contact_map();
    double msum = 0.0;
    size_t mn = 0;
    for (const auto& q : map.cloud()) {
      const double d = wall_distance(Eigen::Vector2d(q.x, q.y));
      if (!std::isfinite(d)) continue;
      msum += d;
      ++mn;
    }
    m["map_points"] = mn;
    m["map_reconstruction_error_m"] = mn ? nlohmann::json(msum / static_cast<double>(mn)) : nlohmann::json(nullptr);
    (void)sum2;
    return m;
  }

  /// Whisker contact points in a mapping_pcl PointMap at the flight height,
  /// voxel-filtered (1 cm, MapParams default).
  mapping_pcl::PointMap contact_map() const {
    mapping_pcl::PointMap map;
    const double z = explorer_->params().sequencer.wall.flight_height;
    for (const auto& c : explorer_->sequencer().contacts()) map.insert(mapping_pcl::Vec3(c.p.x(), c.p.y(), z));
    if (map.size() > 0) map.voxel_filter();
    return map;
  }

  std::optional<bool> reached_goal() const override { return explorer_->sequencer().exit_found() && outside(); }

  void decorate(TopView& view) const override {
    const auto& seq = explorer_->sequencer();
    for (const auto& c : seq.contacts()) view.map_points.push_back(c.p);
    if (seq.has_target()) view.targets.push_back(seq.target());
  }

  void write_outputs(const std::filesystem::path& dir) const override {
    mapping_pcl::PlyInfo info;
    info.frame = "odom";
    info.comment = "whisker contact points of gpis_explore (voxel 1 cm)";
    mapping_pcl::write_ply((dir / "whisker_map.ply").string(), contact_map().cloud(),
                           mapping_pcl::PlyFormat::kBinaryLittleEndian, info);
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> walls;
    for (const auto& w : sim_->arena().walls()) walls.emplace_back(w.a, w.b);
    for (size_t k = 0; k < pictures_.size(); ++k) {
      gpis_explorer::GpisPicture pic = pictures_[k];
      pic.walls = walls;
      char name[64];
      std::snprintf(name, sizeof name, "gpis_update_%02zu.png", k + 1);
      gpis_explorer::write_gpis_png((dir / name).string(), pic);
    }
    if (!pictures_.empty()) {
      gpis_explorer::GpisPicture fin = pictures_.back();
      fin.walls = walls;
      fin.trajectory = explorer_->sequencer().trajectory();
      if (!fin.trajectory.empty()) fin.drone = std::make_pair(fin.trajectory.back(), 0.0);
      fin.title = std::string("final map: ") + gpis_explorer::to_string(explorer_->sequencer().outcome());
      gpis_explorer::write_gpis_png((dir / "gpis_final.png").string(), fin);
    }
  }

 private:
  std::shared_ptr<tactile_sim::SimLogic> sim_;
  std::shared_ptr<GpisExplorerLogic> explorer_;
  std::vector<gpis_explorer::GpisPicture> pictures_;
  struct PhaseEntry {
    double t;
    std::string state, reason;
    uint32_t transitions;
  };
  std::vector<PhaseEntry> phases_;
};

}  // namespace

GraphInfo gpis_explore_graph() {
  GraphInfo g;
  g.name = "gpis_explore";
  g.description = "TDORC -> tactile_depth -> gpis_explorer: GPIS active exploration to the exit of a room (000)";
  g.vehicles = {tactile_sim::VehicleType::kWhiskerCrazyflie};
  g.nodes = {"tdorc_filter", "tactile_depth", "gpis_explorer"};
  g.metrics_key = "gpis";
  // 000 Fig. 5 / issue: mean and std of the reconstruction error and travel, GPIS updates.
  g.summary_metrics = {"gpis.reconstruction_error_m", "gpis.travel_distance_m", "gpis.gpis_updates"};
  g.build = [](GraphContext& ctx) { return std::make_unique<GpisExploreGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
