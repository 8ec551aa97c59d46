// Test world for the exploration sequencing: a kinematic drone (body
// velocities integrated exactly) with two ideal forward whiskers (ray cast to
// the nearest wall, 0.2 m reach) in a room of wall segments. Not the SITL: it
// checks the sequencing logic, not the physics.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "gpis_explorer/sequencer.hpp"

namespace gpis_test {

struct Segment {
  Eigen::Vector2d a, b;
};

/// Square room of side `side` centred at the origin, rotated by `yaw`, with a
/// gap of `exit` metres centred on the wall at +y (before rotation).
/// `offset` moves the gap's centre along that wall (+x before rotation).
inline std::vector<Segment> room(double side, double exit, double yaw, double offset = 0.0) {
  const double h = side / 2;
  std::vector<Segment> w{{{-h, -h}, {h, -h}}, {{h, -h}, {h, h}}, {{-h, h}, {-h, -h}}};
  if (exit > 0) {
    w.push_back({{h, h}, {offset + exit / 2, h}});
    w.push_back({{offset - exit / 2, h}, {-h, h}});
  } else {
    w.push_back({{h, h}, {-h, h}});
  }
  const Eigen::Matrix2d R = (Eigen::Matrix2d() << std::cos(yaw), -std::sin(yaw), std::sin(yaw), std::cos(yaw)).finished();
  for (auto& s : w) {
    s.a = R * s.a;
    s.b = R * s.b;
  }
  return w;
}

/// The four walls of a square pillar of half side h centred at o.
inline std::vector<Segment> square(const Eigen::Vector2d& o, double h) {
  const Eigen::Vector2d q[4] = {o + Eigen::Vector2d(-h, -h), o + Eigen::Vector2d(h, -h), o + Eigen::Vector2d(h, h),
                                o + Eigen::Vector2d(-h, h)};
  std::vector<Segment> w;
  for (int k = 0; k < 4; ++k) w.push_back({q[k], q[(k + 1) % 4]});
  return w;
}

inline double ray(const std::vector<Segment>& walls, const Eigen::Vector2d& p, const Eigen::Vector2d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : walls) {
    const Eigen::Vector2d e = s.b - s.a;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const Eigen::Vector2d ap = s.a - p;
    const double t = (ap.x() * e.y() - ap.y() * e.x()) / den;
    const double u = (ap.x() * d.y() - ap.y() * d.x()) / den;
    if (t >= 0 && u >= 0 && u <= 1) best = std::min(best, t);
  }
  return best;
}

inline double wall_distance(const std::vector<Segment>& walls, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : walls) {
    const Eigen::Vector2d e = s.b - s.a;
    const double t = std::clamp((p - s.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (s.a + t * e - p).norm());
  }
  return best;
}

struct Run {
  bool exit_found = false;
  bool outside = false;
  double min_wall_distance = 1e9;
  gpis_explorer::Phase min_wall_phase = gpis_explorer::Phase::kHoverInit;  ///< phase at the closest approach
  Eigen::Vector2d min_wall_at{0, 0};
  double t_end = 0;
  std::size_t updates = 0;
  gpis_explorer::Outcome outcome = gpis_explorer::Outcome::kRunning;
};

/// Flies the sequencer in `walls` from the origin with heading yaw0.
/// The closest approach to a wall is tracked while the drone is inside the
/// room (room frame rotated by room_yaw, half side room_half).
/// `on_step(seq, position, yaw)` is called after every step (optional);
/// `edit_input(in)` may change the tick's input before the step (optional:
/// stale inputs).
inline Run fly(gpis_explorer::ExplorationSequencer& seq, const std::vector<Segment>& walls, double yaw0,
               double max_t = 400.0, double room_half = 1.0, double room_yaw = 0.0,
               const std::function<void(const gpis_explorer::ExplorationSequencer&, const Eigen::Vector2d&, double)>&
                   on_step = {},
               const std::function<void(gpis_explorer::SequencerInput&)>& edit_input = {}) {
  Run r;
  Eigen::Vector2d p(0, 0);
  double yaw = yaw0;
  const double dt = 0.02, reach = 0.2, base_x = 0.05, half_s = 0.025;
  for (double t = 0; t < max_t; t += dt) {
    gpis_explorer::SequencerInput in;
    in.t = t;
    in.pose_valid = true;
    in.x = p.x();
    in.y = p.y();
    in.yaw = yaw;
    in.depth_valid = true;
    const Eigen::Vector2d fx(std::cos(yaw), std::sin(yaw)), fy(-std::sin(yaw), std::cos(yaw));
    for (int side = 0; side < 2; ++side) {
      const Eigen::Vector2d base = p + base_x * fx + (side == 0 ? half_s : -half_s) * fy;
      const double d = ray(walls, base, fx);
      const bool c = d < reach;
      (side == 0 ? in.contact_left : in.contact_right) = c;
      (side == 0 ? in.depth_left : in.depth_right) = c ? d : NAN;
      (side == 0 ? in.point_left : in.point_right) = c ? Eigen::Vector2d(base + d * fx) : Eigen::Vector2d(NAN, NAN);
    }
    if (edit_input) edit_input(in);
    const auto out = seq.step(in);
    if (on_step) on_step(seq, p, yaw);
    if (seq.phase() == gpis_explorer::Phase::kDone) break;
    p += dt * (out.setpoint.vx * fx + out.setpoint.vy * fy);
    yaw += dt * out.setpoint.yaw_rate;
    const Eigen::Vector2d pr(std::cos(room_yaw) * p.x() + std::sin(room_yaw) * p.y(),
                             -std::sin(room_yaw) * p.x() + std::cos(room_yaw) * p.y());
    const bool inside = pr.cwiseAbs().maxCoeff() < room_half;
    const double wd = wall_distance(walls, p);
    if (inside && wd < r.min_wall_distance) {
      r.min_wall_distance = wd;
      r.min_wall_phase = seq.phase();
      r.min_wall_at = p;
    }
    r.t_end = t;
  }
  r.exit_found = seq.exit_found();
  r.outcome = seq.outcome();
  r.updates = seq.explorer().updates();
  // outside: beyond the rotated room's half side (any axis of the room frame)
  const Eigen::Vector2d pr(std::cos(room_yaw) * p.x() + std::sin(room_yaw) * p.y(),
                           -std::sin(room_yaw) * p.x() + std::cos(room_yaw) * p.y());
  r.outside = pr.cwiseAbs().maxCoeff() > room_half;
  return r;
}

}  // namespace gpis_test
