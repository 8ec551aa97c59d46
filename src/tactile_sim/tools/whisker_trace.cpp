// Writes a whisker barometer trace as CSV: t, motors, load, p1..p3, T1..T3.
// Usage: whisker_trace <seed> <takeoff_s> <hover_s> [contact_start_s contact_duration_s peak_load_nm]...
// The motors run from takeoff_s to takeoff_s + hover_s; 50 Hz. A contact is a
// half-sine load pulse.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tactile_sim/whisker_barometer_model.hpp"

int main(int argc, char** argv) {
  if (argc < 4 || (argc - 4) % 3 != 0) {
    std::fprintf(stderr, "usage: %s seed takeoff_s hover_s [start dur peak]...\n", argv[0]);
    return 2;
  }
  const auto seed = std::strtoull(argv[1], nullptr, 10);
  const double takeoff = std::atof(argv[2]);
  const double hover = std::atof(argv[3]);
  struct Contact { double start, dur, peak; };
  std::vector<Contact> contacts;
  for (int a = 4; a + 2 < argc; a += 3)
    contacts.push_back({std::atof(argv[a]), std::atof(argv[a + 1]), std::atof(argv[a + 2])});
  tactile_sim::WhiskerBarometerParams params;
  // Optional overrides for tuning: WHISKER_PARAMS="cooling_tau_s=12,heating_delta_c=4".
  if (const char* env = std::getenv("WHISKER_PARAMS")) {
    std::string s(env);
    size_t pos = 0;
    while (pos < s.size()) {
      size_t end = s.find(',', pos);
      if (end == std::string::npos) end = s.size();
      const std::string kv = s.substr(pos, end - pos);
      pos = end + 1;
      const size_t eq = kv.find('=');
      if (eq == std::string::npos) continue;
      const std::string k = kv.substr(0, eq);
      const double v = std::atof(kv.c_str() + eq + 1);
      auto& p = params;
      if (k == "cooling_tau_s") p.cooling_tau_s = v;
      else if (k == "package_tau_s") p.package_tau_s = v;
      else if (k == "cooling_scale") for (auto& c : p.cooling_delta_c) c *= v;
      else if (k == "coeff_scale") for (auto& c : p.temp_coeff_pa_per_c) c *= v;
      else if (k == "heating_delta_c") p.heating_delta_c = v;
      else if (k == "heating_tau_s") p.heating_tau_s = v;
      else if (k == "airflow_sigma_c") p.airflow_sigma_c = v;
      else if (k == "airflow_tau_s") p.airflow_tau_s = v;
      else if (k == "random_walk_pa_per_sqrt_s") p.random_walk_pa_per_sqrt_s = v;
      else if (k == "vibration_noise_pa") p.vibration_noise_pa = v;
      else { std::fprintf(stderr, "unknown parameter %s\n", k.c_str()); return 2; }
    }
  }
  tactile_sim::WhiskerBarometerModel model(params, seed);
  const double dt = 0.02;
  const double end = takeoff + hover + 10.0;
  const long n = std::lround(end / dt);
  std::printf("t,motors,load,p1,p2,p3,T1,T2,T3\n");
  for (long k = 1; k <= n; ++k) {
    const double t = static_cast<double>(k) * dt;
    const bool motors = t >= takeoff && t < takeoff + hover;
    double load = 0.0;
    for (const auto& c : contacts) {
      if (t >= c.start && t < c.start + c.dur) load += c.peak * std::sin(3.14159265358979323846 * (t - c.start) / c.dur);
    }
    const auto s = model.step(dt, load, motors);
    std::printf("%.2f,%d,%.9g,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", t, motors ? 1 : 0, load, s.pressure[0],
                s.pressure[1], s.pressure[2], s.temperature[0], s.temperature[1], s.temperature[2]);
  }
  return 0;
}
