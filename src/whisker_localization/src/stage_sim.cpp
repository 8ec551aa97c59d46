#include "whisker_localization/stage_sim.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "whisker_localization/root_finding.hpp"

namespace whisker_localization {

void MomentNoise::validate() const {
  if (!(relative >= 0.0) || !std::isfinite(relative)) throw std::invalid_argument("MomentNoise.relative: must be finite and >= 0, got " + std::to_string(relative));
  if (!(absolute >= 0.0) || !std::isfinite(absolute)) throw std::invalid_argument("MomentNoise.absolute: must be finite and >= 0, got " + std::to_string(absolute));
}

double MomentNoise::apply(double m, std::mt19937_64& rng) const {
  std::normal_distribution<double> n(0.0, 1.0);
  const double a = n(rng), b = n(rng);
  return m * (1.0 + relative * a) + absolute * b;
}

void Table1Params::validate() const {
  beam.validate();
  sets.validate();
  noise.validate();
  if (contacts.empty()) throw std::invalid_argument("Table1Params.contacts: must not be empty");
  for (double c : contacts) {
    if (!(c > 0.0 && c < beam.length)) throw std::invalid_argument("Table1Params.contacts: each must be in (0, L), got " + std::to_string(c));
  }
  if (displacements.empty()) throw std::invalid_argument("Table1Params.displacements: must not be empty");
  for (double t : displacements) {
    if (!(t > 0.0) || t > 0.5 * beam.length) throw std::invalid_argument("Table1Params.displacements: each must be in (0, 0.5 L], got " + std::to_string(t));
  }
  if (trials < 1) throw std::invalid_argument("Table1Params.trials: must be >= 1, got " + std::to_string(trials));
}

std::vector<Table1Row> run_table1(const Table1Params& p) {
  p.validate();
  const ElasticaSolver solver(p.beam);
  const VirtualSensors sensors(solver, p.sets);
  TemporalFilterParams tf;
  tf.contact_threshold = 0.0;
  TemporalContactFilter filter(sensors, tf);
  std::mt19937_64 rng(p.seed);
  std::vector<Table1Row> rows;
  for (double t : p.displacements) {
    for (double px : p.contacts) {
      // Truth: the pole is world-fixed at (p_x, 0) at first touch; moving the
      // base by -t_y in y puts it at (p_x, t_y) in the sensor frame (point mode).
      const BeamShape b1 = solver.solve_point(px, t);
      if (!b1.ok) continue;  // out of the whisker's reach
      Table1Row row;
      row.p_x = px;
      row.t_y = t;
      row.m0 = b1.base_moment;
      row.phi_a = b1.phi_a;
      int ok = 0;
      double sum_ours = 0.0, sum_err = 0.0, sum_base = 0.0, sum_berr = 0.0;
      for (int k = 0; k < p.trials; ++k) {
        const double m1 = p.noise.apply(b1.base_moment, rng);
        filter.reset();
        filter.start_from_touch();  // P_t = undeformed axis at first touch
        const ContactEstimate e = filter.update(m1, 0.0, -t);  // base moved by (0, -t_y)
        if (e.status == ContactEstimate::Status::kEstimated) {
          ++ok;
          sum_ours += e.x;  // the contact in the touch frame is (x, y - t_y): distance = x
          sum_err += std::fabs(e.x - px) / px * 100.0;
        }
        const double d = baseline_distance(p.beam.ei_base(), t, m1);  // 002 eq. 5
        sum_base += d;
        sum_berr += std::fabs(d - px) / px * 100.0;
      }
      row.ours_failures = p.trials - ok;
      row.ours_mean = ok > 0 ? sum_ours / ok : std::nan("");
      row.ours_error_pct = ok > 0 ? sum_err / ok : std::nan("");
      row.baseline_mean = sum_base / p.trials;
      row.baseline_error_pct = sum_berr / p.trials;
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace whisker_localization

namespace whisker_localization {

namespace {
constexpr double kPi2 = 3.14159265358979323846;
}

WallContact tip_wall_contact(const ElasticaSolver& solver, const BoundaryMap& map, const Pose2& base) {
  WallContact w;
  const double L = solver.params().length;
  const double c = std::cos(base.theta), s = std::sin(base.theta);
  auto to_world = [&](double x, double y, double& wx, double& wy) {
    wx = base.x + c * x - s * y;
    wy = base.y + s * x + c * y;
  };
  double tx, ty;
  to_world(L, 0.0, tx, ty);
  double nx, ny, tan;
  if (map.signed_distance(tx, ty, &nx, &ny, &tan) >= 0.0) return w;  // tip in free space
  w.contact = true;
  for (int it = 0; it < 8; ++it) {
    // Load on the whisker along the wall's free-side normal, in the sensor frame.
    const double dir = tan + kPi2 / 2.0 - base.theta;
    auto gap = [&](double F) {
      const BeamShape b = solver.solve_fixed(F, dir, L);
      if (!b.ok) return std::nan("");
      double x, y;
      to_world(b.contact_x, b.contact_y, x, y);
      return map.signed_distance(x, y);
    };
    double lo = 0.0, flo = gap(0.0), hi = 1e-3, fhi = gap(hi);
    for (int k = 0; k < 60 && fhi < 0.0; ++k) {
      lo = hi;
      flo = fhi;
      hi *= 1.6;
      fhi = gap(hi);
    }
    auto F = brent_root(gap, lo, hi, flo, fhi, 1e-12, 200);
    if (!F) {
      w.ok = false;
      return w;
    }
    w.shape = solver.solve_fixed(*F, dir, L, true);
    to_world(w.shape.contact_x, w.shape.contact_y, w.tip_x, w.tip_y);
    double tan2;
    map.signed_distance(w.tip_x, w.tip_y, &nx, &ny, &tan2);
    const bool converged = std::fabs(wrap_angle(tan2 - tan)) < 1e-9;
    tan = tan2;
    if (converged) break;
  }
  w.m0 = w.shape.base_moment;
  // Beyond the elastic range (or a buckled branch): the whisker would snap over.
  w.ok = w.shape.ok && std::fabs(w.shape.phi_a) <= ElasticaSolver::kMaxSlope;
  return w;
}

std::vector<std::array<double, 2>> concave_corner_polyline(double fillet_radius, double leg, double spacing) {
  std::vector<std::array<double, 2>> pts;
  const int nl = std::max(1, static_cast<int>(std::ceil(leg / spacing)));
  for (int i = 0; i < nl; ++i) pts.push_back({-leg + leg * i / nl, 0.0});
  const double arc = fillet_radius * kPi2 / 2.0;
  const int na = std::max(2, static_cast<int>(std::ceil(arc / spacing)));
  for (int i = 0; i <= na; ++i) {
    const double a = (kPi2 / 2.0) * i / na;
    pts.push_back({fillet_radius * std::sin(a), fillet_radius * (1.0 - std::cos(a))});
  }
  for (int i = 1; i <= nl; ++i) pts.push_back({fillet_radius, fillet_radius + leg * i / nl});
  return pts;
}

void concave_corner_point(double r, double s, double& x, double& y, double& tangent) {
  const double arc = r * kPi2 / 2.0;
  if (s <= 0.0) {
    x = s;
    y = 0.0;
    tangent = 0.0;
  } else if (s < arc) {
    const double a = s / r;
    x = r * std::sin(a);
    y = r * (1.0 - std::cos(a));
    tangent = a;
  } else {
    x = r;
    y = r + (s - arc);
    tangent = kPi2 / 2.0;
  }
}

void table2_sweep(const Table2Params& p, std::size_t index, Pose2& start, Pose2& motion) {
  const double s0 = p.sweep_starts.at(index);
  double xc, yc, tangent, xe, ye, te;
  concave_corner_point(p.fillet_radius, s0, xc, yc, tangent);
  concave_corner_point(p.fillet_radius, s0 + p.steps * p.step, xe, ye, te);
  const double inward = tangent - kPi2 / 2.0;  // into the obstacle
  const double attack = p.attack_deg * kPi2 / 180.0;
  const double heading = inward + attack;      // whisker axis
  const double reach = p.beam.length - p.penetration / std::cos(attack);
  start = Pose2{xc - reach * std::cos(heading), yc - reach * std::sin(heading), heading};
  // A straight line along the chord of the swept part of the boundary.
  const double chord = std::atan2(ye - yc, xe - xc);
  motion = Pose2{p.step * std::cos(chord - heading), p.step * std::sin(chord - heading), 0.0};
}

void Table2Params::validate() const {
  beam.validate();
  localizer.validate();
  noise.validate();
  auto pos = [](double v, const char* f) {
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string("Table2Params.") + f + ": must be finite and > 0, got " + std::to_string(v));
  };
  pos(fillet_radius, "fillet_radius");
  pos(leg, "leg");
  pos(penetration, "penetration");
  pos(step, "step");
  pos(truth_distance, "truth_distance");
  pos(truth_angle, "truth_angle");
  pos(localized_spread, "localized_spread");
  if (!(attack_deg >= 0.0 && attack_deg < 80.0)) throw std::invalid_argument("Table2Params.attack_deg: must be in [0, 80), got " + std::to_string(attack_deg));
  if (steps < 4) throw std::invalid_argument("Table2Params.steps: must be >= 4, got " + std::to_string(steps));
  if (sweep_starts.empty()) throw std::invalid_argument("Table2Params.sweep_starts: must not be empty");
  const double arc = fillet_radius * kPi2 / 2.0;
  for (double x : sweep_starts) {
    if (!(x > -0.8 * leg && x + steps * step < arc + 0.8 * leg))
      throw std::invalid_argument("Table2Params.sweep_starts: each sweep must stay within 0.8 leg of the arc, got " + std::to_string(x));
  }
}

SweepScore::SweepScore(int id, const Table2Params& p)
    : truth_distance_(p.truth_distance), truth_angle_(p.truth_angle), localized_spread_(p.localized_spread) {
  r_.id = id;
}

void SweepScore::add(const Pose2& truth, const std::vector<Pose2>& set, const Pose2& best, double spread, int step,
                     bool second_half) {
  ++r_.localizing_steps;
  for (const auto& q : set) {
    if (std::hypot(q.x - truth.x, q.y - truth.y) <= truth_distance_ &&
        std::fabs(wrap_angle(q.theta - truth.theta)) <= truth_angle_) {
      ++kept_;
      break;
    }
  }
  const double err = std::hypot(best.x - truth.x, best.y - truth.y) * 1e3;
  r_.final_error_mm = err;
  if (second_half) half_.push_back(err);
  r_.final_spread_mm = spread * 1e3;
  r_.final_set_size = set.size();
  if (spread <= localized_spread_) {
    if (r_.first_localized_step < 0) r_.first_localized_step = step;
    ++r_.localized_steps;
    localized_.push_back(err);
  }
}

void SweepScore::add_profile_point(const BoundaryMap& world, const Pose2& base, double cx, double cy) {
  // 002 Sec. VI-B: the estimated contact placed by the known base pose.
  const double c = std::cos(base.theta), s = std::sin(base.theta);
  const double d = std::fabs(world.signed_distance(base.x + c * cx - s * cy, base.y + s * cx + c * cy)) * 1e3;
  ++r_.profile_points;
  profile_sum_ += d;
  r_.profile_max_error_mm = std::max(r_.profile_max_error_mm, d);
}

Table2Sweep SweepScore::finish(int steps, uint64_t resets) const {
  Table2Sweep r = r_;
  r.steps = steps;
  r.resets = resets;
  r.profile_mean_error_mm = r.profile_points > 0 ? profile_sum_ / static_cast<double>(r.profile_points) : 0.0;
  r.truth_kept_fraction = r.localizing_steps > 0 ? static_cast<double>(kept_) / r.localizing_steps : 0.0;
  auto stats = [](const std::vector<double>& e, double& mean, double& sd) {
    if (e.empty()) {
      mean = sd = std::nan("");
      return;
    }
    double m = 0.0;
    for (double x : e) m += x;
    m /= static_cast<double>(e.size());
    double v = 0.0;
    for (double x : e) v += (x - m) * (x - m);
    mean = m;
    sd = std::sqrt(v / static_cast<double>(e.size()));
  };
  stats(half_, r.mean_error_mm, r.std_error_mm);
  stats(localized_, r.localized_mean_error_mm, r.localized_std_error_mm);
  return r;
}

std::vector<Table2Sweep> run_table2(const Table2Params& p) {
  p.validate();
  const ElasticaSolver solver(p.beam);
  // The localizer's map: the boundary at 1 mm (002 Sec. VII-B). The world the
  // whisker touches: the same curve at 0.05 mm (closer to the analytic one).
  const BoundaryMap map({concave_corner_polyline(p.fillet_radius, p.leg, 0.001)}, 0.001);
  const BoundaryMap world({concave_corner_polyline(p.fillet_radius, p.leg, 0.00005)}, 0.001);
  std::mt19937_64 rng(p.seed);
  std::vector<Table2Sweep> out;
  for (std::size_t sw = 0; sw < p.sweep_starts.size(); ++sw) {
    SweepScore score(static_cast<int>(sw) + 1, p);
    Pose2 base, motion;
    table2_sweep(p, sw, base, motion);
    PreimageLocalizer loc(map, solver, p.localizer);
    loc.set_prior(base);  // 002 Sec. VII-D: the sweep starts at a known location
    for (int k = 0; k < p.steps; ++k) {
      if (k > 0) base = compose(base, motion);
      const WallContact wc = tip_wall_contact(solver, world, base);
      if (!wc.contact || !wc.ok) score.contact_failure();
      double z = wc.contact && wc.ok ? wc.m0 : 0.0;
      if (z != 0.0) {
        if (p.bounded_noise) {
          std::uniform_real_distribution<double> u(-p.noise.relative, p.noise.relative);
          z *= 1.0 + u(rng);
        } else {
          z = p.noise.apply(z, rng);
        }
      }
      const auto st = loc.step(k == 0 ? Pose2{} : motion, z);
      if (st.contact && (st.geometry.cx != 0.0 || st.geometry.cy != 0.0)) {
        score.add_profile_point(world, base, st.geometry.cx, st.geometry.cy);
      }
      if (st.localizing) score.add(base, loc.set().poses, st.best, st.spread, k, k >= p.steps / 2);
    }
    out.push_back(score.finish(p.steps, loc.resets()));
  }
  return out;
}

}  // namespace whisker_localization
