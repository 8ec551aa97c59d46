#include "whisker_localization/stage_sim.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

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
