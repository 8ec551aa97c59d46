// IMQ kernel loops (000 eq. 33-39, beta = 1/2). See imq_kernels.hpp.
// Vectorised over the queries (the inner loop), so no sum is reassociated.
// Built with -fno-math-errno (sqrt without the errno branch, see CMakeLists).
#include "imq_kernels.hpp"

#include <algorithm>
#include <cmath>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define GPIS_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GPIS_CLONES
#endif

namespace gpis_explorer::detail {
namespace {
/// Queries per block: the per-query accumulators stay in L1.
constexpr std::ptrdiff_t kBlock = 256;
}  // namespace

GPIS_CLONES
void imq_mean(const double* __restrict xs, const double* __restrict ys, const double* __restrict alpha,
              std::ptrdiff_t n, const double* __restrict qx, const double* __restrict qy, std::ptrdiff_t m,
              double c2, double* __restrict out) {
  for (std::ptrdiff_t j0 = 0; j0 < m; j0 += kBlock) {
    const std::ptrdiff_t b = std::min(kBlock, m - j0);
    double* __restrict o = out + j0;
    const double* __restrict px = qx + j0;
    const double* __restrict py = qy + j0;
    for (std::ptrdiff_t j = 0; j < b; ++j) o[j] = 0.0;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const double xi = xs[i], yi = ys[i], a = alpha[i];
      for (std::ptrdiff_t j = 0; j < b; ++j) {
        const double dx = xi - px[j], dy = yi - py[j];
        o[j] += (1.0 / std::sqrt(c2 + (dx * dx + dy * dy))) * a;  // 000 eq. 33-34
      }
    }
  }
}

GPIS_CLONES
void imq_block(const double* __restrict xs, const double* __restrict ys, std::ptrdiff_t n,
               const double* __restrict qx, const double* __restrict qy, std::ptrdiff_t m, double c2,
               double* __restrict K, std::ptrdiff_t ld) {
  for (std::ptrdiff_t j = 0; j < m; ++j) {
    const double x = qx[j], y = qy[j];
    double* __restrict col = K + j * ld;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const double dx = xs[i] - x, dy = ys[i] - y;
      col[i] = 1.0 / std::sqrt(c2 + (dx * dx + dy * dy));  // 000 eq. 33
    }
  }
}

GPIS_CLONES
void imq_derivatives(const double* __restrict xs, const double* __restrict ys, const double* __restrict alpha,
                     std::ptrdiff_t n, const double* __restrict qx, const double* __restrict qy, std::ptrdiff_t m,
                     double c2, double* __restrict gx, double* __restrict gy, double* __restrict hxx,
                     double* __restrict hxy, double* __restrict hyy) {
  // k = s^-1/2, s = c^2 + |d|^2, d = x - x_i: dk/dx = -s^-3/2 d,
  // d2k/dx2 = -s^-3/2 I + 3 s^-5/2 d d^T (000 eq. 37, 39 for beta = 1/2; see README).
  for (std::ptrdiff_t j = 0; j < m; ++j) gx[j] = gy[j] = hxx[j] = hxy[j] = hyy[j] = 0.0;
  for (std::ptrdiff_t j0 = 0; j0 < m; j0 += kBlock) {
    const std::ptrdiff_t b = std::min(kBlock, m - j0);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const double xi = xs[i], yi = ys[i], a = alpha[i];
      for (std::ptrdiff_t j = j0; j < j0 + b; ++j) {
        const double dx = qx[j] - xi, dy = qy[j] - yi;
        const double s = c2 + (dx * dx + dy * dy);
        const double s1 = 1.0 / (s * std::sqrt(s));
        const double cg = -s1 * a;
        const double w = 3.0 * s1 / s * a;
        gx[j] += cg * dx;
        gy[j] += cg * dy;
        hxx[j] += w * (dx * dx) + cg;
        hxy[j] += w * (dx * dy);
        hyy[j] += w * (dy * dy) + cg;
      }
    }
  }
}

const char* simd_dispatch() {
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") ? "avx2" : "baseline";
#else
  return "baseline";
#endif
}

}  // namespace gpis_explorer::detail
