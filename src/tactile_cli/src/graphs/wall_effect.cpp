// Graph `wall_effect` (paper 004): the ducted quadrotor flown by the INDI
// controller (eq. 26-36) on motion-capture odometry along 004's setpoint
// scripts (wall_trajectory: estimation flight, hold, distance sweep), while
// the wall-effect EKF (eq. 20-25) estimates the wall distance and direction
// from the IMU, flow, ToF and rotor thrusts. The estimate is evaluated
// against /ground_truth/wall: RMSE of distance and direction while the
// vehicle is within 20 cm of the wall (004: 1.8 cm, 13.6 deg over t = 10-70 s),
// NEES of (distance, direction) and of the full 11-dim error state (truth
// from the simulator's state and arena in 004's wall frame), tracking errors,
// per-setpoint errors of a sweep.
#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "graphs.hpp"
#include "tactile_cli/host_nodes.hpp"
#include "tactile_cli/wall_effect_eval.hpp"
#include "tactile_common/time.hpp"
#include "tactile_common/geometry.hpp"

namespace tactile_cli::graphs {

namespace {

class WallEffectGraph : public SimGraph {
 public:
  explicit WallEffectGraph(GraphContext& ctx) : sim_(ctx.sim) {
    ekf_ = add_wall_effect_ekf(ctx.host, ctx.overrides("wall_effect_ekf"));
    indi_ = add_indi_controller(ctx.host, ctx.overrides("indi_controller"));
    traj_ = add_wall_trajectory(ctx.host, ctx.overrides("wall_trajectory"));
    eval_ = std::make_unique<WallEffectEvaluation>(traj_->params());
    eval_->subscribe(ctx.host.bus(), [this](const tactile_msgs::msg::WallEstimate&) {
      if (eval_->have_odometry()) add_state_nees();
    });
    if (traj_->params().mode == "sweep") {
      ctx.host.bus().subscribe<tactile_msgs::msg::WallEstimate>(
          wall_effect_ekf::WallEffectEkfLogic::kOutputTopic,
          [this](const tactile_msgs::msg::WallEstimate& m) { on_sweep_estimate(m); });
    }
  }

  /// 004 Fig. 5: per-setpoint errors of the distance sweep.
  void on_sweep_estimate(const tactile_msgs::msg::WallEstimate& est) {
    const auto& truth = eval_->truth();
    if (!eval_->have_truth() || !truth.wall_detected) return;
    const double t = tactile_common::to_seconds(tactile_common::from_stamp(est.header.stamp));
    const auto& tp = traj_->params();
    const int k = wall_effect_ekf::sweep_segment(tp, t);
    // Skip the first 10 s of each hover (transition to the new setpoint).
    if (k >= 0 && t - tp.t_start - k * tp.sweep_hold_s > 10.0) {
      auto& s = sweep_[k];
      s.truth.add(truth.distance);
      s.dist.add(est.distance - truth.distance);
      s.angle.add(std::abs(wrap_angle(est.direction - truth.direction)) * 180.0 / M_PI);
    }
  }

  /// NEES of the EKF's 11-dim error state against the simulator's truth in
  /// 004's wall frame W (y_W = wall normal into the free space, z_W up,
  /// x_W = y_W x z_W): y, z, p_dot (W), R (body -> W), omega.
  void add_state_nees() {
    namespace we = wall_effect_ekf;
    const auto& odom = eval_->odometry();
    const auto& pp = odom.pose.pose;
    const tactile_sim::Vec3 p(pp.position.x, pp.position.y, pp.position.z);
    const tactile_sim::Quat q(pp.orientation.w, pp.orientation.x, pp.orientation.y, pp.orientation.z);
    const tactile_sim::Hit h = sim_->arena().closest(p.head<2>(), 1.0);
    if (!h.hit) return;
    const we::Vec3 yw(h.normal.x(), h.normal.y(), 0.0), zw(0.0, 0.0, 1.0);
    we::Mat3 W;  // rows: the wall axes in the world frame (world -> W)
    W.row(0) = yw.cross(zw).transpose();
    W.row(1) = yw.transpose();
    W.row(2) = zw.transpose();
    we::WallState truth;
    truth.y = h.distance;
    truth.z = p.z() - sim_->arena().floor_z();
    truth.R = W * q.toRotationMatrix();
    const auto& tw = odom.twist.twist;
    truth.v = truth.R * we::Vec3(tw.linear.x, tw.linear.y, tw.linear.z);
    truth.omega = we::Vec3(tw.angular.x, tw.angular.y, tw.angular.z);
    const auto& ekf = ekf_->ekf();
    const we::ErrVec e = we::boxminus(truth, ekf.state());  // R_true = R_est Exp(dtheta)
    const Eigen::LDLT<we::ErrMat> ldlt(ekf.covariance());
    const we::ErrVec Pe = ldlt.solve(e);
    const double nees = e.dot(Pe);
    state_nees_.add(nees);
    // 95 % two-sided chi-square interval of one sample, 11 dof.
    if (nees >= kChi2Lo11 && nees <= kChi2Hi11) ++state_nees_in95_;
    for (int i = 0; i < we::kErrorDim; ++i) {
      const double v = ekf.covariance()(i, i);
      if (v > 0.0) component_nees_[static_cast<size_t>(i)].add(e[i] * e[i] / v);
    }
  }

  nlohmann::json metrics() const override {
    nlohmann::json m;
    eval_->write(m);
    // Full error state (11 dof): mean NEES (11 for a consistent filter), the
    // fraction of samples inside the 95 % chi-square interval of one sample
    // [3.82, 21.92], and the normalised squared error of each component
    // (y, z, v_W x3, dtheta x3, omega x3), 1 each when consistent.
    m["nees_state"] = json_number(state_nees_.mean());
    m["nees_state_dim"] = wall_effect_ekf::kErrorDim;
    m["nees_state_samples"] = state_nees_.n;
    m["nees_state_in_chi2_95"] = json_number(state_nees_.n ? static_cast<double>(state_nees_in95_) / static_cast<double>(state_nees_.n) : NAN);
    nlohmann::json comp = nlohmann::json::array();
    for (const auto& c : component_nees_) comp.push_back(json_number(c.mean()));
    m["nees_components"] = comp;
    const auto& es = ekf_->ekf().stats();
    m["ekf_reacquisitions"] = es.reacquisitions;
    if (!sweep_.empty()) {
      nlohmann::json rows = nlohmann::json::array();
      for (const auto& [k, s] : sweep_) {
        rows.push_back({{"setpoint_m", traj_->params().sweep_distances[static_cast<size_t>(k)]},
                        {"mean_distance_m", json_number(s.truth.mean())},
                        {"mean_distance_error_cm", json_number(100.0 * s.dist.mean())},
                        {"std_distance_error_cm", json_number(100.0 * s.dist.std())},
                        {"mean_abs_angle_error_deg", json_number(s.angle.mean())},
                        {"std_abs_angle_error_deg", json_number(s.angle.std())}});
      }
      m["sweep"] = rows;
    }
    return m;
  }

 private:
  struct Segment {
    Accumulator truth, dist, angle;
  };
  static constexpr double kChi2Lo11 = 3.816, kChi2Hi11 = 21.920;  // chi2(11) 2.5 % / 97.5 %
  std::shared_ptr<tactile_sim::SimLogic> sim_;
  std::shared_ptr<wall_effect_ekf::WallEffectEkfLogic> ekf_;
  std::shared_ptr<wall_effect_ekf::IndiControlLogic> indi_;
  std::shared_ptr<wall_effect_ekf::WallTrajectoryLogic> traj_;
  std::unique_ptr<WallEffectEvaluation> eval_;
  Accumulator state_nees_;
  size_t state_nees_in95_ = 0;
  std::array<Accumulator, wall_effect_ekf::kErrorDim> component_nees_{};
  std::map<int, Segment> sweep_;
};

}  // namespace

GraphInfo wall_effect_graph() {
  GraphInfo g;
  g.name = "wall_effect";
  g.description = "ducted quadrotor: INDI on motion capture along 004's setpoint scripts, wall-effect EKF evaluated (004)";
  g.vehicles = {tactile_sim::VehicleType::kDuctedQuadrotor};
  g.nodes = {"wall_effect_ekf", "indi_controller", "wall_trajectory"};
  g.metrics_key = "wall_effect";
  g.build = [](GraphContext& ctx) { return std::make_unique<WallEffectGraph>(ctx); };
  return g;
}

}  // namespace tactile_cli::graphs
