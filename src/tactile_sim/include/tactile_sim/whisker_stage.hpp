// The whisker of paper 002 on a planar linear stage (or slow mobile base):
// a kinematic base pose that moves straight to its setpoint at the stage's
// speed, and the base bending moment M(0) of the nitinol whisker computed by
// the elastica model of whisker_localization (002 eq. 1-4) against the arena,
// with Hall-sensor noise. Core layer: no ROS, no messages.
//
// Contacts (both frictionless, as in the paper):
// - arena walls: tip contact (002 Sec. VII, Table II), the load at s = L
//   along the wall normal with the magnitude that puts the tip on the wall
//   (whisker_localization::tip_wall_contact). The wall polylines must be
//   walked with the free space on their LEFT (the map convention of 002's
//   localization);
// - arena cylinders of radius <= pin_radius: point obstacles (poles, 002
//   Table I), contacted at their centre along the shaft (point mode). The side
//   of the whisker the pin presses is latched when the pin leaves the
//   undeformed whisker's band (+-radius) after touching it, and released when
//   it slips past the tip or goes back across. One contact at a time: pins
//   before walls; contact of the shaft with a wall is not modelled.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "tactile_sim/arena.hpp"
#include "tactile_sim/types.hpp"
#include "whisker_localization/elastica.hpp"
#include "whisker_localization/preimage.hpp"
#include "whisker_localization/stage_sim.hpp"

namespace tactile_sim {

struct WhiskerStageParams {
  /// The whisker: 002 Sec. V-A nitinol, d = 0.58 mm, E = 52 GPa,
  /// I = 5.555e-15 m^4, L = 75 mm (whisker_localization::BeamParams defaults).
  whisker_localization::BeamParams beam;
  double speed = 0.02;             ///< stage translation speed [m/s]; choice
  double yaw_rate = 1.0;           ///< stage rotation speed [rad/s]; choice
  double sample_rate_hz = 100.0;   ///< base-moment samples [Hz]; choice (002's Teensy streams 300 Hz)
  /// Hall moment noise after calibration: relative * M(0) * n1 + absolute *
  /// n2 (n Gaussian), or, with noise_bounded, uniform in +-relative * M(0)
  /// (the bounded error of 002 eq. 24). Choice, as
  /// whisker_localization::MomentNoise.
  double noise_relative = 0.005;
  double noise_absolute = 2e-7;    ///< [N m]
  bool noise_bounded = false;
  double pin_radius = 0.002;       ///< cylinders up to this radius are point obstacles [m]; choice
  void validate() const;           ///< throws std::invalid_argument naming the field
};

/// The arena's walls as polylines (consecutive segments of one obstacle
/// joined), in file order: the boundary map a whisker sees (and, written to
/// a map file, the known map of 002's localization).
std::vector<std::vector<std::array<double, 2>>> wall_polylines(const Arena& arena);

class WhiskerStage {
 public:
  /// One base-moment sample.
  struct Reading {
    bool contact = false;   ///< the whisker touches something
    bool ok = true;         ///< false: no equilibrium (beyond the elastic range), moment reported 0
    bool tip = false;       ///< tip contact on a wall (else a pin along the shaft)
    double m0_true = 0.0;   ///< M(0) [N m], positive bending toward the whisker's left
    double m0 = 0.0;        ///< with noise [N m]
    Vec2 contact_point = Vec2::Zero();  ///< world [m]
  };

  WhiskerStage(const WhiskerStageParams& params, const Vec3& position, double yaw, uint64_t seed);
  ~WhiskerStage();

  /// Moves straight toward the setpoint (and turns toward its yaw).
  void set_setpoint(const Vec3& position, double yaw);
  void step(double dt);
  /// The base moment against `arena` at the current pose (advances the noise stream).
  Reading sense(const Arena& arena);

  const RigidBodyState& state() const { return state_; }
  double yaw() const { return yaw_; }
  const WhiskerStageParams& params() const { return params_; }
  const whisker_localization::ElasticaSolver& solver() const { return *solver_; }

 private:
  void build_map(const Arena& arena);
  double noisy(double m);

  WhiskerStageParams params_;
  std::unique_ptr<whisker_localization::ElasticaSolver> solver_;
  std::unique_ptr<whisker_localization::BoundaryMap> walls_;  ///< arena walls as the whisker sees them
  bool map_built_ = false;
  RigidBodyState state_;
  double yaw_ = 0.0;
  Vec3 setpoint_ = Vec3::Zero();
  double yaw_setpoint_ = 0.0;
  std::vector<int> pin_side_;  ///< per arena cylinder: 0 free, +-1 pressing that side, 2 touching the axis
  std::mt19937_64 rng_;
};

}  // namespace tactile_sim
