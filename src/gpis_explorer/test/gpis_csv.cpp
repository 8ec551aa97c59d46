// Test helper for test_gpis_numpy.py. stdin: a header line
// "beta,c,noise", then "P,x,y,label" training rows and "Q,x,y" query rows.
// stdout: per query "mean,variance,gx,gy,hxx,hxy,hyy,kappa" (%.17g).
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "gpis_explorer/gpis.hpp"

int main() {
  gpis_explorer::GpisParams p;
  std::string line;
  if (!std::getline(std::cin, line)) return 2;
  char comma;
  std::istringstream hs(line);
  hs >> p.beta >> comma >> p.c >> comma >> p.noise;
  std::vector<std::pair<Eigen::Vector2d, double>> pts;
  std::vector<Eigen::Vector2d> qs;
  while (std::getline(std::cin, line)) {
    if (line.empty()) continue;
    std::istringstream s(line.substr(2));
    double x, y, l = 0;
    s >> x >> comma >> y;
    if (line[0] == 'P') {
      s >> comma >> l;
      pts.push_back({{x, y}, l});
    } else {
      qs.emplace_back(x, y);
    }
  }
  p.max_points = std::max<std::size_t>(pts.size(), 1);
  p.duplicate_tolerance = 0.0;
  gpis_explorer::Gpis g(p);
  for (const auto& pl : pts) {
    if (g.add_point(pl.first, pl.second) != gpis_explorer::AddStatus::kAdded) return 3;
  }
  for (const auto& q : qs) {
    double m, v;
    g.predict(q, &m, &v);
    Eigen::Vector2d gr;
    Eigen::Matrix2d H;
    g.derivatives(q, &gr, &H);
    std::printf("%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", m, v, gr.x(), gr.y(), H(0, 0), H(0, 1), H(1, 1),
                g.curvature(q));
  }
  return 0;
}
