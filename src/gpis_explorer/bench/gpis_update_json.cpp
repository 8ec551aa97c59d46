// One GPIS explorer update on given data, its outputs as JSON on stdout, for
// the agreement checks against numpy/scipy and scikit-learn
// (test/test_gpis_peer.py and scripts/bench_numpy_compare.py).
// stdin: a header "grid_cells,grid_size,variance_cells", then rows "x,y,label"
// (label 0 surface, -1 interior). The GPIS uses the defaults of GpisParams
// (000 eq. 33: beta 0.5, c 1, sigma^2 1e-2) and a grid centred on (0, 0).
// stdout: {"backend", "status", "grid_mean": [...], "grid_variance": [...],
//          "contours": [{"closed", "points": [[x, y], ...], "curvature": [...],
//                        "variance": [...], "acquisition": [...]}],
//          "corners": [[x, y], ...], "target": [x, y] or null}.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "gpis_explorer/explorer.hpp"

namespace {
void num(double v) {
  if (std::isfinite(v)) {
    std::printf("%.17g", v);
  } else {
    std::printf("null");
  }
}
void list(const std::vector<double>& v) {
  std::printf("[");
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) std::printf(",");
    num(v[i]);
  }
  std::printf("]");
}
void point(const Eigen::Vector2d& p) {
  std::printf("[");
  num(p.x());
  std::printf(",");
  num(p.y());
  std::printf("]");
}
}  // namespace

int main() {
  std::string line;
  if (!std::getline(std::cin, line)) {
    std::fprintf(stderr, "gpis_update_json: line 1: missing header grid_cells,grid_size,variance_cells\n");
    return 2;
  }
  gpis_explorer::ExplorerParams p;
  {
    std::istringstream hs(line);
    char comma = 0;
    double cells = 0, vcells = 0;
    if (!(hs >> cells >> comma >> p.grid_size >> comma >> vcells)) {
      std::fprintf(stderr, "gpis_update_json: line 1: expected grid_cells,grid_size,variance_cells, got '%s'\n",
                   line.c_str());
      return 2;
    }
    p.grid_cells = static_cast<uint32_t>(cells);
    p.variance_cells = static_cast<uint32_t>(vcells);
  }
  std::vector<Eigen::Vector2d> xs;
  std::vector<double> ys;
  int lineno = 1;
  while (std::getline(std::cin, line)) {
    ++lineno;
    if (line.empty()) continue;
    std::istringstream s(line);
    char c1 = 0, c2 = 0;
    double x = 0, y = 0, l = 0;
    if (!(s >> x >> c1 >> y >> c2 >> l)) {
      std::fprintf(stderr, "gpis_update_json: line %d: expected x,y,label, got '%s'\n", lineno, line.c_str());
      return 2;
    }
    xs.emplace_back(x, y);
    ys.push_back(l);
  }
  p.gpis.max_points = std::max<std::size_t>(xs.size(), 1);
  p.gpis.duplicate_tolerance = 0.0;
  gpis_explorer::GpisExplorer ex(p);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (ex.add_point(xs[i], ys[i]) != gpis_explorer::AddStatus::kAdded) {
      std::fprintf(stderr, "gpis_update_json: point %zu not added\n", i);
      return 3;
    }
  }
  const auto& r = ex.update();
  std::printf("{\"backend\":\"%s\",\"status\":\"%s\",\"grid_mean\":", gpis_explorer::Gpis::backend(),
              gpis_explorer::to_string(r.status));
  list(ex.grid_mean());
  std::printf(",\"grid_variance\":");
  list(ex.grid_variance());
  std::printf(",\"contours\":[");
  for (std::size_t k = 0; k < r.contours.size(); ++k) {
    const auto& c = r.contours[k];
    std::printf("%s{\"closed\":%s,\"points\":[", k ? "," : "", c.contour.closed ? "true" : "false");
    for (std::size_t i = 0; i < c.contour.points.size(); ++i) {
      if (i) std::printf(",");
      point(c.contour.points[i]);
    }
    std::printf("],\"curvature\":");
    list(c.curvature);
    std::printf(",\"variance\":");
    list(c.variance);
    std::printf(",\"acquisition\":");
    list(c.acquisition);
    std::printf("}");
  }
  std::printf("],\"corners\":[");
  for (std::size_t i = 0; i < r.corners.size(); ++i) {
    if (i) std::printf(",");
    point(r.corners[i]);
  }
  std::printf("],\"target\":");
  if (r.has_target) {
    point(r.target);
  } else {
    std::printf("null");
  }
  std::printf("}\n");
  return 0;
}
