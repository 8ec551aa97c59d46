// EKF of the wall distance and direction (004 eq. 20-25); see wall_ekf.hpp.
#include "wall_effect_ekf/wall_ekf.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace wall_effect_ekf {
namespace {

[[noreturn]] void bad(const std::string& field, const char* why, double v) {
  std::ostringstream s;
  s << "EkfParams." << field << ": " << why << ", got " << v;
  throw std::invalid_argument(s.str());
}
void positive(const char* f, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) bad(f, "must be finite and > 0", v);
}
void non_negative(const char* f, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) bad(f, "must be finite and >= 0", v);
}

const Vec3 kE2(0.0, 1.0, 0.0);
const Vec3 kE3(0.0, 0.0, 1.0);

/// Per-rotor wall force T_W,i and its derivatives w.r.t. y and dtheta.
struct RotorTerms {
  Vec3 f_wall;          // T_W,i (004 eq. 5)
  Vec3 df_dy;           // d T_W,i / d y
  Mat3 df_dth;          // d T_W,i / d dtheta
};

RotorTerms rotor_terms(double T, const Vec3& r_i, const WallState& x, const ProximityParams& pp) {
  const Mat3& R = x.R;
  const double c = R(2, 2);                                        // e3^T R e3
  const Eigen::RowVector3d dc = -R.row(2) * skew(kE3);             // d c / d dtheta
  const double yi = rotor_wall_distance(x.y, R, r_i, pp);          // 004: y_i
  const Eigen::RowVector3d dyi = -R.row(1) * skew(r_i);            // d y_i / d dtheta
  const Proximity g = proximity(yi, pp);
  RotorTerms t;
  // T_W,i = T (R e3 + (gamma_v - 1) c e3 - gamma_h c e2)          (004 eq. 5)
  t.f_wall = T * (R.col(2) + (g.gv - 1.0) * c * kE3 - g.gh * c * kE2);
  t.df_dy = T * c * (g.dgv * kE3 - g.dgh * kE2);
  t.df_dth = T * (-R * skew(kE3) + kE3 * ((g.gv - 1.0) * dc + c * g.dgv * dyi) -
                  kE2 * (g.gh * dc + c * g.dgh * dyi));
  return t;
}

}  // namespace

double WallState::wall_direction() const {
  const Vec3 u = wall_direction_body();
  return std::atan2(u.y(), u.x());
}

void EkfParams::validate() const {
  vehicle.validate();
  positive("dt", dt);
  non_negative("q_distance", q_distance);
  non_negative("q_height", q_height);
  non_negative("q_velocity", q_velocity);
  non_negative("q_attitude", q_attitude);
  non_negative("q_rate", q_rate);
  positive("r_accel", r_accel);
  positive("r_accel_z", r_accel_z);
  positive("r_gyro", r_gyro);
  positive("r_flow", r_flow);
  positive("r_tof", r_tof);
  positive("gate_chi2", gate_chi2);
  positive("y_min", y_min);
  if (!(y_max > y_min) || !std::isfinite(y_max)) bad("y_max", "must be finite and > y_min", y_max);
  positive("sigma_y_init", sigma_y_init);
  positive("sigma_yaw_init", sigma_yaw_init);
  positive("sigma_y_max", sigma_y_max);
  positive("sigma_attitude_max", sigma_attitude_max);
  non_negative("min_height", min_height);
  positive("reacquire_accel", reacquire_accel);
  positive("reacquire_angle", reacquire_angle);
  positive("reacquire_time_constant", reacquire_time_constant);
}

Vec3 so3_log(const Mat3& R) {
  const double c = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const double a = std::acos(c);
  const Vec3 w(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  if (a < 1e-7) return 0.5 * w;
  if (M_PI - a < 1e-6) {
    // Near pi: axis from the largest diagonal element of (R + I) / 2.
    const Mat3 B = 0.5 * (R + Mat3::Identity());
    int k = 0;
    B.diagonal().maxCoeff(&k);
    Vec3 axis = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
    return a * axis.normalized();
  }
  return a / (2.0 * std::sin(a)) * w;
}

WallState boxplus(const WallState& x, const ErrVec& dx) {
  WallState o = x;
  o.y += dx[idx::kY];
  o.z += dx[idx::kZ];
  o.v += dx.segment<3>(idx::kV);
  o.R = x.R * so3_exp(dx.segment<3>(idx::kTheta));
  o.omega += dx.segment<3>(idx::kOmega);
  return o;
}

ErrVec boxminus(const WallState& a, const WallState& b) {
  ErrVec d;
  d[idx::kY] = a.y - b.y;
  d[idx::kZ] = a.z - b.z;
  d.segment<3>(idx::kV) = a.v - b.v;
  d.segment<3>(idx::kTheta) = so3_log(b.R.transpose() * a.R);
  d.segment<3>(idx::kOmega) = a.omega - b.omega;
  return d;
}

StateDerivative dynamics(const WallState& x, const Vec4& thrust, const VehicleParams& v) {
  const Wrench w = rotor_wrench(thrust, x.y, x.R, v);
  const Vec3 J = v.inertia_diag;
  StateDerivative d;
  d.y_dot = x.v.y();                                                        // 004 eq. 20
  d.z_dot = x.v.z();
  d.v_dot = (w.force_wall - v.linear_drag * x.v) / v.mass - kGravity * kE3;  // 004 eq. 6, 20
  d.omega_dot = (w.torque_body - x.omega.cross(J.cwiseProduct(x.omega))).cwiseQuotient(J);  // 004 eq. 8
  return d;
}

Vec3 predict_accel(const WallState& x, const Vec4& thrust, const VehicleParams& v) {
  // 004 eq. 23: a_m = R^T (p_dd + g e3) (ENU, +g at rest) = R^T (T_W - k p_dot) / m.
  const Wrench w = rotor_wrench(thrust, x.y, x.R, v);
  return x.R.transpose() * (w.force_wall - v.linear_drag * x.v) / v.mass;
}

Vec2 predict_flow(const WallState& x) { return optical_flow(x.v, x.R, x.omega, x.z); }  // 004 eq. 9-10

double predict_tof(const WallState& x) { return x.z / x.R(2, 2); }

ModelJacobians jacobians(const WallState& x, const Vec4& thrust, const VehicleParams& v) {
  ModelJacobians j;
  j.H_accel.setZero();
  j.H_flow.setZero();
  j.H_tof.setZero();
  const Mat3& R = x.R;
  const auto r = v.rotor_positions();
  const Mat3 Rt = R.transpose();
  Vec3 dF_dy = Vec3::Zero();        // d T_W / d y
  Mat3 dF_dth = Mat3::Zero();       // d T_W / d dtheta
  Vec3 dtau_dy = Vec3::Zero();
  Mat3 dtau_dth = Mat3::Zero();
  Vec3 fb_sum_dy = Vec3::Zero();    // d (R^T T_W) / d y
  Mat3 fb_sum_dth = Mat3::Zero();   // d (R^T T_W) / d dtheta
  for (int i = 0; i < 4; ++i) {
    const RotorTerms t = rotor_terms(thrust[i], r[i], x, v.proximity);
    dF_dy += t.df_dy;
    dF_dth += t.df_dth;
    const Vec3 fb = Rt * t.f_wall;
    const Vec3 dfb_dy = Rt * t.df_dy;
    const Mat3 dfb_dth = skew(fb) + Rt * t.df_dth;  // d(R^T a) = [R^T a]x dtheta + R^T da
    const Mat3 M = skew(r[i]) + VehicleParams::kSpin[i] * v.torque_coefficient * Mat3::Identity();  // 004 eq. 7
    dtau_dy += M * dfb_dy;
    dtau_dth += M * dfb_dth;
    fb_sum_dy += dfb_dy;
    fb_sum_dth += dfb_dth;
  }
  const double m = v.mass, k = v.linear_drag;
  const Vec3 Jd = v.inertia_diag;
  const Vec3 Jinv = Jd.cwiseInverse();
  // F: continuous error-state Jacobian of eq. 20.
  ErrMat& F = j.F;
  F(idx::kY, idx::kV + 1) = 1.0;
  F(idx::kZ, idx::kV + 2) = 1.0;
  F.block<3, 1>(idx::kV, idx::kY) = dF_dy / m;
  F.block<3, 3>(idx::kV, idx::kV) = -k / m * Mat3::Identity();
  F.block<3, 3>(idx::kV, idx::kTheta) = dF_dth / m;
  F.block<3, 3>(idx::kTheta, idx::kTheta) = -skew(x.omega);
  F.block<3, 3>(idx::kTheta, idx::kOmega) = Mat3::Identity();
  F.block<3, 1>(idx::kOmega, idx::kY) = Jinv.asDiagonal() * dtau_dy;
  F.block<3, 3>(idx::kOmega, idx::kTheta) = Jinv.asDiagonal() * dtau_dth;
  const Mat3 Jm = Jd.asDiagonal();
  F.block<3, 3>(idx::kOmega, idx::kOmega) = Jinv.asDiagonal() * (skew(Jm * x.omega) - skew(x.omega) * Jm);
  // Accelerometer: R^T (T_W - k v) / m.
  j.H_accel.block<3, 1>(0, idx::kY) = fb_sum_dy / m;
  j.H_accel.block<3, 3>(0, idx::kV) = -k / m * Rt;
  j.H_accel.block<3, 3>(0, idx::kTheta) = (fb_sum_dth - k * skew(Rt * x.v)) / m;
  // Flow (004 eq. 9-10).
  const Vec3 vb = Rt * x.v;
  const Mat3 dvb_dth = skew(vb);
  for (int a = 0; a < 2; ++a) {
    j.H_flow.block<1, 3>(a, idx::kV) = Rt.row(a) / x.z;
    j.H_flow(a, idx::kZ) = -vb[a] / (x.z * x.z);
    j.H_flow.block<1, 3>(a, idx::kTheta) = dvb_dth.row(a) / x.z;
  }
  j.H_flow(0, idx::kOmega + 1) = -1.0;
  j.H_flow(1, idx::kOmega + 0) = 1.0;
  // ToF: z / c.
  const double c = R(2, 2);
  const Eigen::RowVector3d dc = -R.row(2) * skew(kE3);
  j.H_tof(0, idx::kZ) = 1.0 / c;
  j.H_tof.block<1, 3>(0, idx::kTheta) = -x.z / (c * c) * dc;
  return j;
}

WallEkf::WallEkf(const EkfParams& params) : p_(params) {
  p_.validate();
  reset(0.0);
}

void WallEkf::reset(double z) {
  WallState x;
  x.y = p_.y_max;
  x.z = z;
  ErrMat P = ErrMat::Zero();
  P(idx::kY, idx::kY) = p_.sigma_y_init * p_.sigma_y_init;
  P(idx::kZ, idx::kZ) = 0.05 * 0.05;
  P.block<3, 3>(idx::kV, idx::kV) = 0.1 * 0.1 * Mat3::Identity();
  P(idx::kTheta, idx::kTheta) = P(idx::kTheta + 1, idx::kTheta + 1) = 0.05 * 0.05;
  P(idx::kTheta + 2, idx::kTheta + 2) = p_.sigma_yaw_init * p_.sigma_yaw_init;
  P.block<3, 3>(idx::kOmega, idx::kOmega) = 0.1 * 0.1 * Mat3::Identity();
  reset(x, P);
}

void WallEkf::reset(const WallState& x0, const ErrMat& P0) {
  x_ = x0;
  P_ = 0.5 * (P0 + P0.transpose());
  lpf_h_.setZero();
  thrust_.setZero();
}

void WallEkf::predict(const Vec4& thrust) {
  if (!thrust.allFinite()) {
    ++stats_.nonfinite_inputs;
    return;
  }
  thrust_ = thrust;
  const double dt = p_.dt;
  const ModelJacobians J = jacobians(x_, thrust, p_.vehicle);
  const StateDerivative d = dynamics(x_, thrust, p_.vehicle);
  // 004 eq. 21: forward Euler (attitude on SO(3)).
  x_.y += d.y_dot * dt;
  x_.z += d.z_dot * dt;
  x_.v += d.v_dot * dt;
  x_.R = x_.R * so3_exp(x_.omega * dt);
  x_.omega += d.omega_dot * dt;
  // 004 eq. 22 with A = I + F dt. Q of the continuous white noise Qc over
  // one step, to third order in dt (Van Loan): the noise on the rates and
  // velocity reaches the attitude and position within the step.
  const ErrMat A = ErrMat::Identity() + J.F * dt;
  ErrVec q;
  q << p_.q_distance, p_.q_height, p_.q_velocity, p_.q_velocity, p_.q_velocity, p_.q_attitude,
      p_.q_attitude, p_.q_attitude, p_.q_rate, p_.q_rate, p_.q_rate;
  const ErrMat Qc = q.cwiseProduct(q).asDiagonal();
  const ErrMat FQ = J.F * Qc;
  const ErrMat Qd = Qc * dt + (FQ + FQ.transpose()) * (dt * dt / 2.0) + FQ * J.F.transpose() * (dt * dt * dt / 3.0);
  P_ = A * P_ * A.transpose() + Qd;
  ++stats_.predictions;
  finish();
}

template <int M>
bool WallEkf::update(const Eigen::Matrix<double, M, 1>& r, const Eigen::Matrix<double, M, kErrorDim>& H,
                     const Eigen::Matrix<double, M, 1>& sigma, double gate) {
  using MatM = Eigen::Matrix<double, M, M>;
  const MatM Rm = sigma.cwiseProduct(sigma).asDiagonal();
  const MatM S = H * P_ * H.transpose() + Rm;                       // 004 eq. 24
  const Eigen::LDLT<MatM> ldlt(S);
  if (gate > 0.0 && r.dot(ldlt.solve(r)) > gate) return false;
  const Eigen::Matrix<double, M, kErrorDim> HP = H * P_;
  const Eigen::Matrix<double, M, kErrorDim> SinvHP = ldlt.solve(HP);
  const Eigen::Matrix<double, kErrorDim, M> K = SinvHP.transpose();  // P H^T S^-1 (P, S symmetric)
  const ErrVec dx = K * r;                                           // 004 eq. 25
  const ErrMat IKH = ErrMat::Identity() - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * Rm * K.transpose();          // Joseph form of eq. 25
  x_ = boxplus(x_, dx);
  finish();
  return true;
}

void WallEkf::finish() {
  // Orthonormalise R (polar factor), keep y in its bounds and P symmetric
  // with bounded variances of y and of the attitude.
  const Eigen::JacobiSVD<Mat3> svd(x_.R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  x_.R = svd.matrixU() * svd.matrixV().transpose();
  x_.y = std::clamp(x_.y, p_.y_min, p_.y_max);
  x_.z = std::max(x_.z, 0.0);
  P_ = 0.5 * (P_ + P_.transpose());
  auto cap = [this](int i, double sigma_max) {
    const double v = P_(i, i), vmax = sigma_max * sigma_max;
    if (v > vmax) {
      const double s = std::sqrt(vmax / v);  // congruence D P D: stays positive definite
      P_.row(i) *= s;
      P_.col(i) *= s;
    }
  };
  cap(idx::kY, p_.sigma_y_max);
  for (int i = 0; i < 3; ++i) cap(idx::kTheta + i, p_.sigma_attitude_max);
}

void WallEkf::update_accel(const Vec3& a_m) {
  if (!a_m.allFinite()) {
    ++stats_.nonfinite_inputs;
    return;
  }
  reacquire(a_m);
  const ModelJacobians J = jacobians(x_, thrust_, p_.vehicle);
  const Vec3 r = a_m - predict_accel(x_, thrust_, p_.vehicle);
  update<3>(r, J.H_accel, Vec3(p_.r_accel, p_.r_accel, p_.r_accel_z), 0.0);
  ++stats_.accel_updates;
}

void WallEkf::update_gyro(const Vec3& w_m) {
  if (!w_m.allFinite()) {
    ++stats_.nonfinite_inputs;
    return;
  }
  Eigen::Matrix<double, 3, kErrorDim> H = Eigen::Matrix<double, 3, kErrorDim>::Zero();
  H.block<3, 3>(0, idx::kOmega) = Mat3::Identity();  // 004 eq. 23: w_m = w + v_w
  update<3>(Vec3(w_m - x_.omega), H, Vec3::Constant(p_.r_gyro), 0.0);
  ++stats_.gyro_updates;
}

void WallEkf::update_flow(const Vec2& n_m) {
  if (!n_m.allFinite()) {
    ++stats_.nonfinite_inputs;
    return;
  }
  if (x_.z < p_.min_height) return;
  const ModelJacobians J = jacobians(x_, thrust_, p_.vehicle);
  if (update<2>(Vec2(n_m - predict_flow(x_)), J.H_flow, Vec2::Constant(p_.r_flow), p_.gate_chi2)) ++stats_.flow_updates;
  else ++stats_.flow_gated;
}

void WallEkf::update_tof(double range) {
  if (!std::isfinite(range)) {
    ++stats_.nonfinite_inputs;
    return;
  }
  const ModelJacobians J = jacobians(x_, thrust_, p_.vehicle);
  Eigen::Matrix<double, 1, 1> r;
  r[0] = range - predict_tof(x_);
  if (update<1>(r, J.H_tof, Eigen::Matrix<double, 1, 1>::Constant(p_.r_tof), p_.gate_chi2)) ++stats_.tof_updates;
  else ++stats_.tof_gated;
}

void WallEkf::reacquire(const Vec3& a_m) {
  // Horizontal specific force in the body frame: zero in free flight apart
  // from drag (004 eq. 5-6: the thrust is along z_B), the wall attraction otherwise.
  const Vec3 drag = -p_.vehicle.linear_drag * (x_.R.transpose() * x_.v) / p_.vehicle.mass;
  const double k = 1.0 - std::exp(-p_.dt / p_.reacquire_time_constant);
  lpf_h_ += k * (Vec2(a_m.x() - drag.x(), a_m.y() - drag.y()) - lpf_h_);
  const double mag = lpf_h_.norm();
  if (mag < p_.reacquire_accel || thrust_.sum() <= 0.0) return;
  const Vec3 u = x_.wall_direction_body();
  const double ang_meas = std::atan2(lpf_h_.y(), lpf_h_.x());
  double dpsi = ang_meas - std::atan2(u.y(), u.x());
  dpsi = std::atan2(std::sin(dpsi), std::cos(dpsi));
  const Vec2 pred = predict_accel(x_, thrust_, p_.vehicle).head<2>();
  const bool direction_wrong = std::abs(dpsi) > p_.reacquire_angle;
  // The estimate says "no wall nearby" while the measurement says "wall".
  const bool too_far = pred.norm() < 0.5 * p_.reacquire_accel;
  if (!direction_wrong && !too_far) return;
  // Turn the wall about the body z axis so that the predicted direction is
  // the measured one: R <- R Rz(-dpsi) gives R^T(-e2) rotated by +dpsi.
  x_.R = x_.R * so3_exp(Vec3(0.0, 0.0, -dpsi));
  // Distance: invert |horizontal a_m|(y) (monotonic) by bisection.
  double lo = p_.y_min, hi = p_.y_max;
  WallState t = x_;
  for (int it = 0; it < 40; ++it) {
    t.y = 0.5 * (lo + hi);
    t.v.setZero();
    if (predict_accel(t, thrust_, p_.vehicle).head<2>().norm() > mag) lo = t.y;
    else hi = t.y;
  }
  x_.y = 0.5 * (lo + hi);
  // Uncertainty of a fresh acquisition.
  P_.row(idx::kY).setZero();
  P_.col(idx::kY).setZero();
  P_(idx::kY, idx::kY) = 0.05 * 0.05;
  const int iz = idx::kTheta + 2;
  P_.row(iz).setZero();
  P_.col(iz).setZero();
  P_(iz, iz) = 0.3 * 0.3;
  ++stats_.reacquisitions;
  finish();
}

Mat3 WallEkf::output_covariance() const {
  Eigen::Matrix<double, 3, kErrorDim> G = Eigen::Matrix<double, 3, kErrorDim>::Zero();
  G(0, idx::kY) = 1.0;
  const Vec3 u = x_.wall_direction_body();
  const double n2 = std::max(u.x() * u.x() + u.y() * u.y(), 1e-9);
  const Eigen::RowVector3d dpsi_du(-u.y() / n2, u.x() / n2, 0.0);
  G.block<1, 3>(1, idx::kTheta) = dpsi_du * skew(u);  // u(dtheta) = u + [u]x dtheta
  G(2, idx::kZ) = 1.0;
  const Mat3 C = G * P_ * G.transpose();
  return 0.5 * (C + C.transpose());
}

}  // namespace wall_effect_ekf
