// Graph `wall_effect_nav` (paper 004, reactive navigation): the wall-effect
// EKF feeds the wall-following or vector-field behaviour (tactile_fsm's
// wall_effect_nav), whose setpoints the INDI controller flies on the
// ducted quadrotor; goal = metrics.target (arena frame) unless the scenario
// sets the node's goal itself. Metrics: goal reached, collisions (simulator),
// wall-tracking error |y - d*| while wall following (004: 0.4 cm RMS at
// psi_d = 0), speed along the wall, minimum wall distance, estimation RMSE.
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "graphs.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_common/time.hpp"

namespace tactile_cli::graphs {

namespace {

double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }
nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

class WallEffectNavGraph : public SimGraph {
 public:
  explicit WallEffectNavGraph(GraphContext& ctx) {
    ekf_ = add_wall_effect_ekf(ctx.host, ctx.overrides("wall_effect_ekf"));
    indi_ = add_indi_controller(ctx.host, ctx.overrides("indi_controller"));
    floor_z_ = ctx.sim ? ctx.sim->arena().floor_z() : 0.0;
    tactile_common::ParamMap extra;
    if (auto t = ctx.target()) {
      extra.set("goal_x", t->x());
      extra.set("goal_y", t->y());
    }
    nav_ = add_wall_effect_nav(ctx.host, ctx.overrides("wall_effect_nav", extra));
    auto& bus = ctx.host.bus();
    bus.subscribe<tactile_msgs::msg::WallEstimate>("/ground_truth/wall", [this](const tactile_msgs::msg::WallEstimate& m) {
      truth_ = m;
      have_truth_ = true;
      if (m.wall_detected) min_distance_ = std::min(min_distance_, m.distance);
      // Tracking error while wall following, after 2 s of settling (004 Fig. 6b).
      const double t = tactile_common::to_seconds(tactile_common::from_stamp(m.header.stamp));
      if (nav_->navigator().state() == tactile_fsm::NavState::kWallFollowing) {
        if (std::isnan(follow_start_)) follow_start_ = t;
        if (t - follow_start_ > 2.0 && m.wall_detected) {
          const double e = m.distance - nav_->params().nav.follow_distance;
          track_sum2_ += e * e;
          ++track_n_;
        }
      } else {
        follow_start_ = NAN;
      }
    });
    bus.subscribe<nav_msgs::msg::Odometry>("/ground_truth/odom", [this](const nav_msgs::msg::Odometry& m) {
      on_truth_for_failsafe(m);
      if (nav_->navigator().state() == tactile_fsm::NavState::kWallFollowing) {
        follow_time_ += 0.01;
        speed_sum_ += std::hypot(m.twist.twist.linear.x, m.twist.twist.linear.y);
        ++speed_n_;
      }
    });
    bus.subscribe<tactile_msgs::msg::ThrustCommand>(wall_effect_ekf::IndiControlLogic::kOutputTopic,
                                                    [this](const tactile_msgs::msg::ThrustCommand& t) {
                                                      last_commanded_thrust_ = t.total_thrust;
                                                    });
    bus.subscribe<tactile_msgs::msg::WallEstimate>(wall_effect_ekf::WallEffectEkfLogic::kOutputTopic,
                                                   [this](const tactile_msgs::msg::WallEstimate& est) {
      if (!have_truth_ || !truth_.wall_detected || truth_.distance >= 0.20) return;
      const double ed = est.distance - truth_.distance, ea = wrap_angle(est.direction - truth_.direction);
      est_d2_ += ed * ed;
      est_a2_ += ea * ea;
      ++est_n_;
    });
  }

  /// INDI's fail-safe from the truth: the height when it left NOMINAL, the highest point and
  /// fastest descent after that, and when the vehicle reached the floor.
  void on_truth_for_failsafe(const nav_msgs::msg::Odometry& m) {
    using wall_effect_ekf::IndiFailsafeState;
    const IndiFailsafeState st = indi_->state();
    if (st == IndiFailsafeState::kWaitingForInput || st == IndiFailsafeState::kNominal) return;
    const double t = tactile_common::to_seconds(tactile_common::from_stamp(m.header.stamp));
    const double z = m.pose.pose.position.z - floor_z_;
    const auto& q = m.pose.pose.orientation;
    const auto& v = m.twist.twist.linear;  // body frame (REP 105)
    const double vz = (Eigen::Quaterniond(q.w, q.x, q.y, q.z) * Eigen::Vector3d(v.x, v.y, v.z)).z();
    if (std::isnan(fs_left_nominal_s_)) {
      fs_left_nominal_s_ = tactile_common::to_seconds(indi_->stats().state_since_ns);
      fs_first_state_ = wall_effect_ekf::to_string(st);
      fs_z_at_loss_ = z;
    }
    fs_max_z_ = std::max(fs_max_z_, z);
    fs_max_descent_ = std::max(fs_max_descent_, -vz);
    if (std::isnan(fs_floor_s_) && z < 0.005) fs_floor_s_ = t;
  }

  nlohmann::json metrics() const override {
    nlohmann::json m;
    const auto& np = nav_->params();
    m["behaviour"] = np.nav.behaviour;
    m["final_state"] = tactile_fsm::to_string(nav_->navigator().state());
    m["goal_reached"] = nav_->navigator().state() == tactile_fsm::NavState::kGoalReached;
    m["transitions"] = nav_->navigator().transitions();
    // The shared fail-safe (NOMINAL unless an input went stale) and INDI's last total
    // thrust command: ~0 after a FAILSAFE_LAND has reached the floor.
    m["failsafe_state"] = tactile_fsm::to_string(nav_->safety().state());
    m["final_commanded_thrust_n"] = finite_or_null(last_commanded_thrust_);
    m["min_wall_distance_m"] = finite_or_null(min_distance_);
    m["wall_following_time_s"] = follow_time_;
    m["rms_tracking_error_cm"] = track_n_ ? finite_or_null(100.0 * std::sqrt(track_sum2_ / static_cast<double>(track_n_))) : nullptr;
    m["mean_following_speed_mps"] = speed_n_ ? finite_or_null(speed_sum_ / static_cast<double>(speed_n_)) : nullptr;
    m["rmse_distance_cm"] = est_n_ ? finite_or_null(100.0 * std::sqrt(est_d2_ / static_cast<double>(est_n_))) : nullptr;
    m["rmse_direction_deg"] = est_n_ ? finite_or_null(std::sqrt(est_a2_ / static_cast<double>(est_n_)) * 180.0 / M_PI) : nullptr;
    m["ekf_reacquisitions"] = ekf_->ekf().stats().reacquisitions;
    // INDI's own fail-safe (stale odometry / IMU): its state, and from the truth the height at
    // the loss, the highest point and fastest descent after it, and the floor reached.
    const auto& is = indi_->stats();
    m["indi"] = {{"state", wall_effect_ekf::to_string(is.state)},
                 {"reason", is.reason},
                 {"state_since_s", tactile_common::to_seconds(is.state_since_ns)},
                 {"first_failsafe_state", fs_first_state_},
                 {"left_nominal_s", finite_or_null(fs_left_nominal_s_)},
                 {"z_at_loss_m", finite_or_null(fs_z_at_loss_)},
                 {"max_z_after_loss_m", finite_or_null(fs_max_z_)},
                 {"max_descent_speed_mps", finite_or_null(fs_max_descent_)},
                 {"floor_reached_s", finite_or_null(fs_floor_s_)},
                 {"vertical_speed_estimate_mps", is.vertical_speed_estimate},
                 {"accel_bias_estimate", {is.accel_bias.x(), is.accel_bias.y(), is.accel_bias.z()}}};
    if (np.goal_mode != "direction") m["goal"] = {np.goal().position.x(), np.goal().position.y()};
    return m;
  }

  /// A position goal: reached; a pilot direction: no goal.
  std::optional<bool> reached_goal() const override {
    if (nav_->params().goal_mode == "direction") return std::nullopt;
    return nav_->navigator().state() == tactile_fsm::NavState::kGoalReached;
  }

  void decorate(TopView& view) const override {
    if (nav_->params().goal_mode != "direction") {
      const auto g = nav_->params().goal().position;
      view.targets.emplace_back(g.x(), g.y());
    }
  }

 private:
  std::shared_ptr<wall_effect_ekf::WallEffectEkfLogic> ekf_;
  std::shared_ptr<tactile_fsm::WallEffectNavLogic> nav_;
  std::shared_ptr<wall_effect_ekf::IndiControlLogic> indi_;
  double floor_z_ = 0.0;
  std::string fs_first_state_;
  double fs_left_nominal_s_ = NAN, fs_z_at_loss_ = NAN, fs_max_z_ = -INFINITY, fs_max_descent_ = -INFINITY,
         fs_floor_s_ = NAN;
  tactile_msgs::msg::WallEstimate truth_;
  bool have_truth_ = false;
  double min_distance_ = INFINITY, follow_start_ = NAN, follow_time_ = 0.0, last_commanded_thrust_ = NAN;
  double track_sum2_ = 0.0, speed_sum_ = 0.0, est_d2_ = 0.0, est_a2_ = 0.0;
  size_t track_n_ = 0, speed_n_ = 0, est_n_ = 0;
};

}  // namespace

GraphInfo wall_effect_nav_graph() {
  GraphInfo g;
  g.name = "wall_effect_nav";
  g.description = "ducted quadrotor: wall-effect EKF -> wall following / vector field -> INDI (004)";
  g.vehicles = {tactile_sim::VehicleType::kDuctedQuadrotor};
  g.nodes = {"wall_effect_ekf", "indi_controller", "wall_effect_nav"};
  g.metrics_key = "wall_effect_nav";
  g.build = [](GraphContext& ctx) { return std::make_unique<WallEffectNavGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
