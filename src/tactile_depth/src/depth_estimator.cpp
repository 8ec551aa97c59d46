#include "tactile_depth/depth_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tactile_depth {

namespace {

constexpr double kMm2ToM2 = 1e-6;

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void positive(const char* field, double v) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw std::invalid_argument(std::string("TactileDepthParams.") + field + ": must be finite and > 0, got " + num(v));
  }
}

}  // namespace

const char* to_string(EstimatorModel model) {
  switch (model) {
    case EstimatorModel::kMlp: return "mlp";
    case EstimatorModel::kKfSimplified: return "kf_simplified";
    case EstimatorModel::kKfFull: return "kf_full";
  }
  return "?";
}

EstimatorModel estimator_model_from_string(const char* text) {
  if (std::strcmp(text, "mlp") == 0) return EstimatorModel::kMlp;
  if (std::strcmp(text, "kf_simplified") == 0) return EstimatorModel::kKfSimplified;
  if (std::strcmp(text, "kf_full") == 0) return EstimatorModel::kKfFull;
  throw std::invalid_argument(std::string("unknown estimator \"") + text + "\" (mlp, kf_simplified, kf_full)");
}

void Params::validate() const {
  if (model != EstimatorModel::kMlp && model != EstimatorModel::kKfSimplified && model != EstimatorModel::kKfFull) {
    throw std::invalid_argument("TactileDepthParams.model: unknown value " + std::to_string(static_cast<int>(model)));
  }
  positive("q_mm2", q_mm2);
  positive("r_mm2", r_mm2);
  positive("p0_mm2", p0_mm2);
  if (!std::isfinite(slip_fraction) || slip_fraction < 0.0 || slip_fraction >= 1.0) {
    throw std::invalid_argument("TactileDepthParams.slip_fraction: must be in [0, 1) (0 = off), got " + num(slip_fraction));
  }
  if (slip_window_samples < 1 || slip_window_samples > TactileDepthEstimator::kMaxSlipWindow) {
    throw std::invalid_argument("TactileDepthParams.slip_window_samples: must be in [1, " +
                                std::to_string(TactileDepthEstimator::kMaxSlipWindow) + "], got " + std::to_string(slip_window_samples));
  }
  positive("slip_r_mm2", slip_r_mm2);
  if (slip_max_samples < 0 || slip_max_samples > TactileDepthEstimator::kMaxSlipWindow) {
    throw std::invalid_argument("TactileDepthParams.slip_max_samples: must be in [0, " +
                                std::to_string(TactileDepthEstimator::kMaxSlipWindow) + "] (0 = no limit), got " +
                                std::to_string(slip_max_samples));
  }
  positive("saturation_r_mm2", saturation_r_mm2);
  if (!std::isfinite(saturation_sum_pa) || saturation_sum_pa < 0.0) {
    throw std::invalid_argument("TactileDepthParams.saturation_sum_pa: must be finite and >= 0 (0 = off), got " + num(saturation_sum_pa));
  }
  positive("whisker_spacing", whisker_spacing);
  if (!std::isfinite(whisker_base_x)) {
    throw std::invalid_argument("TactileDepthParams.whisker_base_x: must be finite, got " + num(whisker_base_x));
  }
}

// ---------------------------------------------------------------------------
// Process model

double ProcessModel::wall_angle(double d_left, double d_right, double spacing) {
  return std::atan((d_left - d_right) / spacing);  // 000 eq. 22
}

bool ProcessModel::predict_full(double d_k, double theta_d_k, const Pose2& pose_k, const Pose2& pose_k1,
                                const Point2& base, double& out) {
  // World angle of the wall normal (from the drone into the wall), fixed for a
  // static wall: theta^W = psi_k - theta^D_k (000 eq. 21, with the sign of eq. 24).
  const double theta_w = pose_k.yaw - theta_d_k;
  const double nx = std::cos(theta_w);
  const double ny = std::sin(theta_w);
  // Whisker base in W at k and k+1: B = p + R(psi) b (000 eq. 17-20).
  const double c0 = std::cos(pose_k.yaw), s0 = std::sin(pose_k.yaw);
  const double c1 = std::cos(pose_k1.yaw), s1 = std::sin(pose_k1.yaw);
  const double dbx = (pose_k1.x + c1 * base.x - s1 * base.y) - (pose_k.x + c0 * base.x - s0 * base.y);
  const double dby = (pose_k1.y + s1 * base.x + c1 * base.y) - (pose_k.y + s0 * base.x + c0 * base.y);
  // Updated relative orientation theta^D_k+1 = psi_k+1 - theta^W (000 eq. 24).
  const double theta_d_k1 = pose_k1.yaw - theta_w;
  const double den = std::cos(theta_d_k1);
  if (std::fabs(den) < kMinCos) {
    out = d_k;
    return false;
  }
  // 000 eq. 25: perpendicular distance of the base to the wall at k,
  // d_k cos theta^D_k, minus the base's displacement along the normal, divided
  // by cos theta^D_k+1 to go back along the whisker (body x) at k+1.
  out = (d_k * std::cos(theta_d_k) - (nx * dbx + ny * dby)) / den;
  return true;
}

double ProcessModel::predict_simplified(double d_k, const Pose2& pose_k, const Pose2& pose_k1) {
  const double dx = pose_k1.x - pose_k.x;
  const double dy = pose_k1.y - pose_k.y;
  // Forward displacement in the body frame of step k (theta^D = 0: the wall is
  // perpendicular to the heading; 000 "simple version").
  const double forward = std::cos(pose_k.yaw) * dx + std::sin(pose_k.yaw) * dy;
  return d_k - forward;
}

// ---------------------------------------------------------------------------
// Kalman filter (000 eq. 27-30)

DepthKalmanFilter::DepthKalmanFilter(double q_m2, double r_m2, double p0_m2) : q_(q_m2), r_(r_m2), p0_(p0_m2) {
  if (!(q_m2 > 0.0) || !(r_m2 > 0.0) || !(p0_m2 > 0.0) || !std::isfinite(q_m2) || !std::isfinite(r_m2) || !std::isfinite(p0_m2)) {
    throw std::invalid_argument("DepthKalmanFilter: q, r, p0 must be finite and > 0");
  }
}

void DepthKalmanFilter::initialize(double m) {
  d_ = m;
  p_ = p0_;
  k_ = 0.0;
  initialized_ = true;
}

void DepthKalmanFilter::predict(double d_pred) {
  d_ = d_pred;  // d^-_k+1 from the process model (000 eq. 25)
  p_ = p_ + q_;  // P^-_k+1 = P_k + Q (000 eq. 27)
}

void DepthKalmanFilter::update(double m) { update(m, r_); }

void DepthKalmanFilter::update(double m, double r_m2) {
  k_ = p_ / (p_ + r_m2);    // K = P^- (P^- + R)^-1 (000 eq. 28)
  d_ = d_ + k_ * (m - d_);  // d = d^- + K (m - d^-) (000 eq. 29)
  p_ = (1.0 - k_) * p_;   // P = (I - K) P^- (000 eq. 30)
}

void DepthKalmanFilter::reset() {
  d_ = 0.0;
  p_ = 0.0;
  k_ = 0.0;
  initialized_ = false;
}

// ---------------------------------------------------------------------------
// Estimator

TactileDepthEstimator::TactileDepthEstimator(const Params& params, const MlpModel& left, const MlpModel& right)
    : params_(params), left_(left), right_(right) {
  params_.validate();
  if (!left_.valid() || !right_.valid()) throw std::invalid_argument("TactileDepthEstimator: both whisker models must be loaded");
  const double q = params_.q_mm2 * kMm2ToM2;
  r_m2_ = params_.r_mm2 * kMm2ToM2;
  const double p0 = params_.p0_mm2 * kMm2ToM2;
  slip_r_m2_ = params_.slip_r_mm2 * kMm2ToM2;
  sat_r_m2_ = params_.saturation_r_mm2 * kMm2ToM2;
  kf_[0] = DepthKalmanFilter(q, r_m2_, p0);
  kf_[1] = DepthKalmanFilter(q, r_m2_, p0);
}

Point2 TactileDepthEstimator::whisker_base(int side) const {
  const double half = 0.5 * params_.whisker_spacing;
  return {params_.whisker_base_x, side == 0 ? half : -half};
}

void TactileDepthEstimator::reset() {
  kf_[0].reset();
  kf_[1].reset();
  have_prev_pose_ = false;
  slip_head_ = 0;
  slip_count_ = 0;
  slipping_ = {false, false};
  slip_run_ = {0, 0};
  saturated_ = false;
  have_wall_world_ = false;
}

TickOutput TactileDepthEstimator::update(const TickInput& in) {
  TickOutput out;
  out.measurement[0] = left_.predict(in.sp_left);    // 000 eq. 12-14
  out.measurement[1] = right_.predict(in.sp_right);
  out.contact[0] = in.contact_left;
  out.contact[1] = in.contact_right;
  const bool both = in.contact_left && in.contact_right;
  const double s = params_.whisker_spacing;

  // The input sums (S_c of the three barometers) of the slip gate and the saturated contact.
  const std::array<double, 2> input_sum = {in.sp_left[0] + in.sp_left[1] + in.sp_left[2],
                                           in.sp_right[0] + in.sp_right[1] + in.sp_right[2]};

  // Slip gate (issue 17): input sum against its maximum over the last
  // slip_window_samples ticks, this one included. Off (slip_fraction 0, the
  // paper): no window is kept and slipping_ stays false.
  if (params_.slip_fraction > 0.0) {
    const int window = params_.slip_window_samples;
    input_sum_[0][static_cast<std::size_t>(slip_head_)] = input_sum[0];
    input_sum_[1][static_cast<std::size_t>(slip_head_)] = input_sum[1];
    if (slip_count_ < window) ++slip_count_;
    for (std::size_t i = 0; i < 2; ++i) {
      double peak = input_sum_[i][static_cast<std::size_t>(slip_head_)];
      for (int j = 1; j < slip_count_; ++j) {
        const int idx = (slip_head_ - j + window) % window;
        peak = std::max(peak, input_sum_[i][static_cast<std::size_t>(idx)]);
      }
      const bool below = input_sum_[i][static_cast<std::size_t>(slip_head_)] < params_.slip_fraction * peak;
      slip_run_[i] = below ? slip_run_[i] + 1 : 0;
      slipping_[i] = below && (params_.slip_max_samples == 0 || slip_run_[i] <= params_.slip_max_samples);
    }
    slip_head_ = (slip_head_ + 1) % window;
  }

  // Saturated contact (issue 17): both input sums at or above saturation_sum_pa
  // and a wall angle of an unsaturated tick to hold.
  // Off (the default and the paper): nothing of it runs.
  const bool saturation_on = params_.saturation_sum_pa > 0.0;
  const bool saturated_now =
      saturation_on && input_sum[0] >= params_.saturation_sum_pa && input_sum[1] >= params_.saturation_sum_pa;
  saturated_ = false;

  bool fused = false;
  if (params_.model != EstimatorModel::kMlp && both && in.pose_valid) {
    if (!kf_[0].initialized()) {
      kf_[0].initialize(out.measurement[0]);
      kf_[1].initialize(out.measurement[1]);
    } else if (have_prev_pose_) {
      // Prediction (000 eq. 25, 27). theta^D_k from the fused depths of the
      // previous tick (Fig. S3), shared by both whiskers (one planar wall).
      std::array<double, 2> pred{};
      if (params_.model == EstimatorModel::kKfFull) {
        saturated_ = saturated_now && have_wall_world_;
        // Saturated: theta^D_k from the held world angle (eq. 24, theta^D = psi - theta^W)
        // instead of eq. 22 on the saturated depths.
        const double theta_k = saturated_ ? prev_pose_.yaw - wall_world_
                                          : ProcessModel::wall_angle(kf_[0].depth(), kf_[1].depth(), s);
        for (int i = 0; i < 2; ++i) {
          if (!ProcessModel::predict_full(kf_[static_cast<std::size_t>(i)].depth(), theta_k, prev_pose_, in.pose,
                                          whisker_base(i), pred[static_cast<std::size_t>(i)])) {
            out.prediction_skipped = true;
          }
        }
      } else {
        for (std::size_t i = 0; i < 2; ++i) pred[i] = ProcessModel::predict_simplified(kf_[i].depth(), prev_pose_, in.pose);
      }
      for (std::size_t i = 0; i < 2; ++i) {
        kf_[i].predict(pred[i]);          // 000 eq. 27
        if (slipping_[i] || saturated_) {
          // 000 eq. 28-30 with the slip gate's / the saturated contact's R (the larger if both)
          kf_[i].update(out.measurement[i], std::max(slipping_[i] ? slip_r_m2_ : 0.0, saturated_ ? sat_r_m2_ : 0.0));
        } else {
          kf_[i].update(out.measurement[i]);  // 000 eq. 28-30
        }
      }
    }
    fused = true;
    // World angle of the wall normal (000 eq. 21/24) of this unsaturated tick,
    // held over the next saturated ones.
    if (saturation_on && params_.model == EstimatorModel::kKfFull && !saturated_now) {
      wall_world_ = in.pose.yaw - ProcessModel::wall_angle(kf_[0].depth(), kf_[1].depth(), s);
      have_wall_world_ = true;
    }
  } else {
    // Either whisker off the wall (or no odometry): the KF restarts at the next
    // double contact.
    kf_[0].reset();
    kf_[1].reset();
    have_wall_world_ = false;
  }
  if (in.pose_valid) {
    prev_pose_ = in.pose;
    have_prev_pose_ = true;
  } else {
    have_prev_pose_ = false;
  }

  for (std::size_t i = 0; i < 2; ++i) {
    out.depth[i] = fused ? kf_[i].depth() : out.measurement[i];
    out.variance[i] = fused ? kf_[i].variance() : r_m2_;
  }
  out.filter_initialized = fused;
  // theta^D = atan((d_l - d_r)/s) (000 eq. 22); var by first-order propagation
  // with independent whiskers: dtheta/dd_l = -dtheta/dd_r = s / (s^2 + (d_l - d_r)^2).
  const double diff = out.depth[0] - out.depth[1];
  out.wall_angle = ProcessModel::wall_angle(out.depth[0], out.depth[1], s);
  const double g = s / (s * s + diff * diff);
  out.wall_angle_variance = g * g * (out.variance[0] + out.variance[1]);
  // Contact points: whisker base + depth along body x, in the odometry frame.
  const double c = std::cos(in.pose.yaw), sn = std::sin(in.pose.yaw);
  for (int i = 0; i < 2; ++i) {
    const Point2 b = whisker_base(i);
    const double bx = b.x + out.depth[static_cast<std::size_t>(i)];
    out.contact_point[static_cast<std::size_t>(i)] = {in.pose.x + c * bx - sn * b.y, in.pose.y + sn * bx + c * b.y};
  }
  return out;
}

std::size_t TactileDepthEstimator::model_bytes() const {
  return left_.memory_bytes() + right_.memory_bytes() - 2 * sizeof(MlpModel);
}

std::size_t TactileDepthEstimator::filter_state_bytes() const {
  return sizeof(*this) - 2 * sizeof(MlpModel);
}

std::size_t TactileDepthEstimator::state_size_bytes() const {
  return sizeof(*this) + model_bytes();
}

}  // namespace tactile_depth
