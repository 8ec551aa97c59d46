// Tactile depth estimation of paper 000 (Methods "Whiskered drone process
// model", eq. 16-25, Fig. S3, and "Kalman filter fusion", eq. 26-30): the MLP
// sensor model of each whisker (mlp_model.hpp) fused with a process model
// driven by the odometry increment, one scalar Kalman filter per whisker.
//
// Core layer: no ROS, no messages, no allocation per tick. SI units inside
// (depth in m, variance in m^2); Q, R, P0 are given in mm^2 as in the paper's
// onboard code and converted once.
//
// Frames (2D): odometry/world frame W; body frame D with x forward, y left,
// yaw psi counter-clockwise. The whiskers point along body +x; their bases are
// at body (base_x, +s/2) (left) and (base_x, -s/2) (right). A depth d is the
// distance from a whisker base along body +x to the wall.
//
// Angles (see README.md "Process model: interpretation of eq. 21-25"):
//   theta^D = atan((d_l - d_r) / s)                            (000 eq. 22)
//     the wall's angle relative to the body y axis; > 0 when the left
//     whisker reaches further, i.e. the wall's normal (pointing from the drone
//     into the wall) is at angle -theta^D in the body frame;
//   theta^W = psi - theta^D                                    (000 eq. 21/24)
//     the world angle of that normal; fixed for a static planar wall.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tactile_depth/mlp_model.hpp"

namespace tactile_depth {

/// Which estimate is published (TactileDepth.MODEL_*).
enum class EstimatorModel : uint8_t {
  kMlp = 0,             ///< sensor model only (000 eq. 12-14)
  kKfSimplified = 1,    ///< KF with d_l = d_r, theta = 0 (000 "simple version")
  kKfFull = 2,          ///< KF with the full process model (000 eq. 21-25)
};

/// "mlp" / "kf_simplified" / "kf_full".
const char* to_string(EstimatorModel model);
/// Parses the names above; throws std::invalid_argument otherwise.
EstimatorModel estimator_model_from_string(const char* text);

/// 2D pose in the odometry frame.
struct Pose2 {
  double x = 0.0;    ///< [m]
  double y = 0.0;    ///< [m]
  double yaw = 0.0;  ///< psi [rad], counter-clockwise
};

/// A point in the odometry frame [m].
struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

/// Parameters of the estimator; defaults are the paper's / onboard values.
struct Params {
  EstimatorModel model = EstimatorModel::kKfFull;
  /// Q, process noise of one 50 Hz step [mm^2] (000 eq. 27; onboard default 0.01).
  double q_mm2 = 0.01;
  /// R, measurement noise of the MLP depth [mm^2] (000 eq. 28; onboard default 1).
  double r_mm2 = 1.0;
  /// P0, variance at initialisation [mm^2] (onboard default 50).
  double p0_mm2 = 50.0;
  /// Slip gate (issue 17, README "Slip gate"): a pressed whisker sliding on a
  /// baffle sticks and slips; on a slip its load, hence its input (sum of the
  /// three S_c), drops while it stays pressed, and the MLP reads a far wall.
  /// A whisker whose input sum is below slip_fraction x its maximum over the
  /// last slip_window_samples ticks (this one included, at most
  /// TactileDepthEstimator::kMaxSlipWindow) is updated with
  /// R = slip_r_mm2 instead of r_mm2. slip_fraction 0 = off (the paper).
  double slip_fraction = 0.0;
  int slip_window_samples = 25;
  double slip_r_mm2 = 1.0e4;
  /// A slip is short (the whisker sticks again within a few ticks); a sum that
  /// stays below the fraction is the whisker leaving the wall (the drone backs
  /// off or turns), which the MLP reads right. A whisker is gated for at most
  /// slip_max_samples consecutive ticks (0 = no limit, the first gate of
  /// issue 17), then not again until its sum is back over the fraction.
  int slip_max_samples = 0;
  /// Saturated contact (issue 17, README "Saturated contact"): a whisker
  /// pressed and sliding along a baffle is friction-limited; its input sum
  /// stops growing below ~70 mm and the MLP reads ~70 mm at any depth below.
  /// While both input sums are >= saturation_sum_pa, the process model keeps
  /// the wall's world angle of the last tick that was not saturated (a planar
  /// wall does not turn; eq. 22 on two saturated depths reads ~0) and both
  /// updates use R = saturation_r_mm2, so the odometry carries the approach.
  /// 0 = off (the paper).
  double saturation_sum_pa = 0.0;
  double saturation_r_mm2 = 1.0e4;
  /// s, lateral distance between the two whisker bases [m] (000 eq. 22: 0.05 m).
  double whisker_spacing = 0.05;
  /// x of the whisker bases in the body frame [m] (ahead of the odometry
  /// origin; our choice 0.05 m, as the simulator's whiskered Crazyflie).
  double whisker_base_x = 0.05;
  /// Throws std::invalid_argument "TactileDepthParams.<field>: <reason>".
  void validate() const;
};

/// Process model (000 eq. 21-25): predicted depth of one whisker at k+1 from
/// its depth at k, the wall angle at k and the poses at k and k+1.
struct ProcessModel {
  /// Full model (000 eq. 24-25), exact for a static planar wall:
  ///   theta^W     = psi_k - theta^D_k                        (eq. 21, 24)
  ///   n           = (cos theta^W, sin theta^W)               wall normal in W
  ///   B_k         = p_k + R(psi_k) b                          whisker base in W (eq. 17-20)
  ///   theta^D_k+1 = psi_k+1 - theta^W                         (eq. 24)
  ///   d^-_k+1     = (d_k cos theta^D_k - n . (B_k+1 - B_k)) / cos theta^D_k+1   (eq. 25)
  /// With b = 0, n . (B_k+1 - B_k) = Delta p cos(theta^W - atan2(Dy, Dx))
  /// = -Delta p sin(theta^W_t - atan2(Dy, Dx)) with theta^W_t = theta^W - pi/2 the
  /// wall's direction angle: eq. 25 as printed (eq. 23 gives Delta p).
  /// `base` is the whisker base in the body frame. Returns false (and leaves
  /// `out` = d_k) if the whisker would be (nearly) parallel to the wall at
  /// k+1 (|cos theta^D_k+1| < kMinCos): no intersection to predict.
  static bool predict_full(double d_k, double theta_d_k, const Pose2& pose_k, const Pose2& pose_k1,
                           const Point2& base, double& out);
  /// Simplified model (000: "we simply assume that d_l = d_r, meaning that
  /// theta^D_wall is always equal to 0"): the wall stays perpendicular to the
  /// heading, so only the forward translation in the body frame of step k
  /// changes the depth: d^-_k+1 = d_k - (R(psi_k)^T (p_k+1 - p_k))_x.
  static double predict_simplified(double d_k, const Pose2& pose_k, const Pose2& pose_k1);
  /// Wall angle theta^D = atan((d_l - d_r) / s) (000 eq. 22).
  static double wall_angle(double d_left, double d_right, double spacing);

  static constexpr double kMinCos = 1e-3;
};

/// Scalar Kalman filter of one whisker's depth (000 eq. 26-30). State in m,
/// variance in m^2.
class DepthKalmanFilter {
 public:
  DepthKalmanFilter() = default;
  /// q, r, p0 in m^2 (> 0).
  DepthKalmanFilter(double q_m2, double r_m2, double p0_m2);
  /// Starts the filter at the measurement m [m] with variance P0.
  void initialize(double m);
  /// Prediction step: d^- from the process model (000 eq. 25), P^- = P + Q (000 eq. 27).
  void predict(double d_pred);
  /// Update step with the MLP depth m (000 eq. 28-30):
  ///   K = P^- (P^- + R)^-1, d = d^- + K (m - d^-), P = (1 - K) P^-.
  void update(double m);
  /// Same with the measurement variance r_m2 [m^2] of this update only.
  void update(double m, double r_m2);
  void reset();
  bool initialized() const { return initialized_; }
  double depth() const { return d_; }
  double variance() const { return p_; }
  double gain() const { return k_; }  ///< K of the last update (000 eq. 28)

 private:
  double q_ = 0.0;
  double r_ = 0.0;
  double p0_ = 0.0;
  double d_ = 0.0;
  double p_ = 0.0;
  double k_ = 0.0;
  bool initialized_ = false;
};

/// Inputs of one 50 Hz tick.
struct TickInput {
  std::array<double, 3> sp_left{};   ///< S_p of the left whisker [Pa] (TDORC output)
  std::array<double, 3> sp_right{};
  bool contact_left = false;
  bool contact_right = false;
  Pose2 pose;                ///< odometry pose at this tick
  bool pose_valid = true;    ///< false: no usable odometry (the KF cannot predict)
};

/// Output of one tick.
struct TickOutput {
  std::array<double, 2> measurement{};  ///< MLP depths m_l, m_r [m] (000 eq. 14)
  std::array<double, 2> depth{};        ///< published d_l, d_r [m]
  std::array<double, 2> variance{};     ///< [m^2]
  std::array<bool, 2> contact{};
  double wall_angle = 0.0;              ///< theta^D (000 eq. 22) [rad]
  double wall_angle_variance = 0.0;     ///< [rad^2], first-order propagation of the depth variances
  bool filter_initialized = false;
  std::array<Point2, 2> contact_point{};  ///< base + depth along body x, odometry frame [m]
  bool prediction_skipped = false;        ///< the process model could not predict (parallel wall)
};

/// The whole depth estimator of one drone: two MLPs, two KFs, the process
/// model (000 eq. 12-30), one tick per paired whisker sample.
///
/// Filter life cycle (the paper's onboard logic as we read it):
///  - The KFs are initialised (d = m, P = P0) on the first tick with both
///    whiskers in contact; that tick publishes m.
///  - On every following tick with both in contact: predict with the process
///    model (eq. 25, using theta^D_k from the fused depths of tick k, Fig. S3)
///    and P^- = P + Q (eq. 27), then update with m (eq. 28-30).
///  - Either whisker losing contact, or a tick without valid odometry, resets
///    both filters; until they are initialised again the sensor model alone
///    is published with variance R (filter_initialized = false).
class TactileDepthEstimator {
 public:
  /// Validates params; copies the models (which must be valid).
  TactileDepthEstimator(const Params& params, const MlpModel& left, const MlpModel& right);

  TickOutput update(const TickInput& in);
  void reset();

  const Params& params() const { return params_; }
  const DepthKalmanFilter& filter(int side) const { return kf_[static_cast<std::size_t>(side)]; }
  const MlpModel& model(int side) const { return side == 0 ? left_ : right_; }
  Point2 whisker_base(int side) const;  ///< body frame; 0 = left, 1 = right

  /// True if the input sum of `side` at the last tick was below slip_fraction
  /// x its window maximum (the update used slip_r_mm2).
  bool slipping(int side) const { return slipping_[static_cast<std::size_t>(side)]; }
  /// True if both input sums at the last tick were >= saturation_sum_pa and a
  /// wall angle of an unsaturated tick was held (kf_full only: the update used
  /// saturation_r_mm2, or slip_r_mm2 if larger and the whisker was also slipping).
  bool saturated() const { return saturated_; }

  /// Bytes of the filter state (this object without the models' parameters).
  std::size_t filter_state_bytes() const;
  /// Bytes of both models as held here (double parameters + buffers).
  std::size_t model_bytes() const;
  /// Total bytes held (object + models).
  std::size_t state_size_bytes() const;

  /// Longest slip gate window (2 s at 50 Hz).
  static constexpr int kMaxSlipWindow = 100;

  /// Paper 000 Fig. S6: "the Tactile Depth Estimator occupies around 9.6 kB".
  static constexpr std::size_t kPaperBudgetBytes = 9600;

 private:
  Params params_;
  MlpModel left_;
  MlpModel right_;
  std::array<DepthKalmanFilter, 2> kf_;
  Pose2 prev_pose_;
  bool have_prev_pose_ = false;
  std::array<bool, 2> slipping_{};
  std::array<int, 2> slip_run_{};  ///< consecutive ticks below the slip fraction
  bool saturated_ = false;
  double wall_world_ = 0.0;     ///< theta^W of the last unsaturated fused tick [rad]
  bool have_wall_world_ = false;
  double r_m2_ = 0.0;
  double slip_r_m2_ = 0.0;
  double sat_r_m2_ = 0.0;
  /// Input sums of the last slip_window_samples ticks per whisker (ring).
  std::array<std::array<double, kMaxSlipWindow>, 2> input_sum_{};
  int slip_head_ = 0;    ///< next slot of the ring
  int slip_count_ = 0;   ///< filled slots
};

}  // namespace tactile_depth
