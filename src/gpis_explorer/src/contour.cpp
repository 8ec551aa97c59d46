// Marching squares and segment chaining (000 Fig. S4f). See contour.hpp.
#include "gpis_explorer/contour.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace gpis_explorer {

GridSpec GridSpec::centred(double cx, double cy, double size, uint32_t n) {
  GridSpec g;
  g.width = n;
  g.height = n;
  g.resolution = n > 1 ? size / static_cast<double>(n - 1) : size;
  g.origin_x = cx - 0.5 * size;
  g.origin_y = cy - 0.5 * size;
  return g;
}

Eigen::Matrix2Xd GridSpec::nodes() const {
  Eigen::Matrix2Xd q(2, static_cast<Eigen::Index>(count()));
  Eigen::Index k = 0;
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) q.col(k++) = node(i, j);
  }
  return q;
}

bool GridSpec::contains(const Eigen::Vector2d& p) const {
  return p.x() >= origin_x && p.y() >= origin_y && p.x() <= origin_x + (width - 1) * resolution &&
         p.y() <= origin_y + (height - 1) * resolution;
}

void GridSpec::validate() const {
  if (!std::isfinite(origin_x)) throw std::invalid_argument("GridSpec.origin_x: must be finite");
  if (!std::isfinite(origin_y)) throw std::invalid_argument("GridSpec.origin_y: must be finite");
  if (!(std::isfinite(resolution) && resolution > 0.0)) {
    throw std::invalid_argument("GridSpec.resolution: must be > 0, got " + std::to_string(resolution));
  }
  if (width < 2) throw std::invalid_argument("GridSpec.width: must be >= 2 nodes, got " + std::to_string(width));
  if (height < 2) throw std::invalid_argument("GridSpec.height: must be >= 2 nodes, got " + std::to_string(height));
  if (static_cast<std::size_t>(width) * height > 25000000u) {
    throw std::invalid_argument("GridSpec.width: width * height must be <= 25e6 nodes");
  }
}

namespace {

struct Edge {
  Eigen::Vector2d p;
  int nb[2] = {-1, -1};
  int degree = 0;
  bool visited = false;
};

}  // namespace

std::vector<Contour> marching_squares(const GridSpec& grid, const std::vector<double>& values) {
  grid.validate();
  if (values.size() != grid.count()) {
    throw std::invalid_argument("marching_squares: values has " + std::to_string(values.size()) +
                                " entries, grid has " + std::to_string(grid.count()));
  }
  const int W = static_cast<int>(grid.width);
  const int H = static_cast<int>(grid.height);
  auto val = [&](int i, int j) {
    const double v = values[static_cast<std::size_t>(j) * grid.width + static_cast<std::size_t>(i)];
    return std::isfinite(v) ? v : -1.0;
  };
  auto above = [&](int i, int j) { return val(i, j) >= 0.0; };
  // Edge ids: horizontal (i,j)-(i+1,j) = j*(W-1)+i; vertical (i,j)-(i,j+1) = nh + j*W+i.
  const int nh = (W - 1) * H;
  const int nv = W * (H - 1);
  std::vector<Edge> edges(static_cast<std::size_t>(nh + nv));
  std::vector<char> crossed(edges.size(), 0);
  auto hid = [&](int i, int j) { return j * (W - 1) + i; };
  auto vid = [&](int i, int j) { return nh + j * W + i; };
  auto make_point = [&](int id) {
    if (crossed[static_cast<std::size_t>(id)]) return;
    int i0, j0, i1, j1;
    if (id < nh) {
      j0 = id / (W - 1);
      i0 = id % (W - 1);
      i1 = i0 + 1;
      j1 = j0;
    } else {
      j0 = (id - nh) / W;
      i0 = (id - nh) % W;
      i1 = i0;
      j1 = j0 + 1;
    }
    const double v0 = val(i0, j0), v1 = val(i1, j1);
    double t = v0 / (v0 - v1);
    if (!std::isfinite(t)) t = 0.5;
    t = std::min(1.0, std::max(0.0, t));
    const Eigen::Vector2d a = grid.node(static_cast<uint32_t>(i0), static_cast<uint32_t>(j0));
    const Eigen::Vector2d b = grid.node(static_cast<uint32_t>(i1), static_cast<uint32_t>(j1));
    edges[static_cast<std::size_t>(id)].p = a + t * (b - a);
    crossed[static_cast<std::size_t>(id)] = 1;
  };
  auto link = [&](int a, int b) {
    make_point(a);
    make_point(b);
    Edge& ea = edges[static_cast<std::size_t>(a)];
    Edge& eb = edges[static_cast<std::size_t>(b)];
    if (ea.degree < 2) ea.nb[ea.degree++] = b;
    if (eb.degree < 2) eb.nb[eb.degree++] = a;
  };
  for (int j = 0; j + 1 < H; ++j) {
    for (int i = 0; i + 1 < W; ++i) {
      // corners a=(i,j) bit 1, b=(i+1,j) bit 2, c=(i+1,j+1) bit 4, d=(i,j+1) bit 8
      const int cs = (above(i, j) ? 1 : 0) | (above(i + 1, j) ? 2 : 0) | (above(i + 1, j + 1) ? 4 : 0) |
                     (above(i, j + 1) ? 8 : 0);
      if (cs == 0 || cs == 15) continue;
      const int bottom = hid(i, j), right = vid(i + 1, j), top = hid(i, j + 1), left = vid(i, j);
      if (cs == 5 || cs == 10) {
        const double centre = 0.25 * (val(i, j) + val(i + 1, j) + val(i + 1, j + 1) + val(i, j + 1));
        const bool centre_above = centre >= 0.0;
        // Cut off the two corners whose state differs from the centre.
        const bool cut_ac = (cs == 5) != centre_above;  // a, c isolated
        if (cut_ac) {
          link(left, bottom);  // around a
          link(right, top);    // around c
        } else {
          link(bottom, right);  // around b
          link(top, left);      // around d
        }
        continue;
      }
      std::array<int, 4> e{};
      int k = 0;
      if (((cs & 1) != 0) != ((cs & 2) != 0)) e[static_cast<std::size_t>(k++)] = bottom;
      if (((cs & 2) != 0) != ((cs & 4) != 0)) e[static_cast<std::size_t>(k++)] = right;
      if (((cs & 4) != 0) != ((cs & 8) != 0)) e[static_cast<std::size_t>(k++)] = top;
      if (((cs & 8) != 0) != ((cs & 1) != 0)) e[static_cast<std::size_t>(k++)] = left;
      if (k == 2) link(e[0], e[1]);
    }
  }
  std::vector<Contour> out;
  auto walk = [&](int start, bool closed) {
    Contour c;
    c.closed = closed;
    int prev = -1, cur = start;
    while (cur >= 0 && !edges[static_cast<std::size_t>(cur)].visited) {
      Edge& e = edges[static_cast<std::size_t>(cur)];
      e.visited = true;
      c.points.push_back(e.p);
      int next = -1;
      for (int q = 0; q < e.degree; ++q) {
        if (e.nb[q] != prev && !edges[static_cast<std::size_t>(e.nb[q])].visited) {
          next = e.nb[q];
          break;
        }
      }
      prev = cur;
      cur = next;
    }
    out.push_back(std::move(c));
  };
  for (std::size_t id = 0; id < edges.size(); ++id) {
    if (crossed[id] && !edges[id].visited && edges[id].degree == 1) walk(static_cast<int>(id), false);
  }
  for (std::size_t id = 0; id < edges.size(); ++id) {
    if (crossed[id] && !edges[id].visited) walk(static_cast<int>(id), edges[id].degree == 2);
  }
  return out;
}

}  // namespace gpis_explorer
