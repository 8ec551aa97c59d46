// Inner loops of the IMQ kernel (000 eq. 33, beta = 1/2) over many training
// points and queries: the kernel block for the triangular solves, the
// posterior mean (eq. 34) and its gradient / Hessian (eq. 36-39).
// Private to gpis_explorer_core. Each function is compiled twice (GCC
// target_clones): for x86-64 CPUs with AVX2 and for the baseline ISA; the
// loader picks the AVX2 clone where the CPU has it. The clones run the same
// IEEE operations in the same order (no FMA contraction, no reassociation:
// sums over training points run in point order per query), so both give the
// same bits and the same results as a scalar loop.
#pragma once

#include <cstddef>

namespace gpis_explorer::detail {

/// out[j] = sum_i alpha[i] / sqrt(c2 + |x_i - q_j|^2), summed in i order.
void imq_mean(const double* xs, const double* ys, const double* alpha, std::ptrdiff_t n, const double* qx,
              const double* qy, std::ptrdiff_t m, double c2, double* out);

/// K[i + j * ld] = 1 / sqrt(c2 + |x_i - q_j|^2) for i < n, j < m.
void imq_block(const double* xs, const double* ys, std::ptrdiff_t n, const double* qx, const double* qy,
               std::ptrdiff_t m, double c2, double* K, std::ptrdiff_t ld);

/// Gradient (g = [gx, gy]) and Hessian (h = [hxx, hxy, hyy]) of the mean at
/// m queries, each an array of m values (000 eq. 36-39 for beta = 1/2).
void imq_derivatives(const double* xs, const double* ys, const double* alpha, std::ptrdiff_t n, const double* qx,
                     const double* qy, std::ptrdiff_t m, double c2, double* gx, double* gy, double* hxx, double* hxy,
                     double* hyy);

/// "avx2" when the CPU runs the AVX2 clones, else "baseline".
const char* simd_dispatch();

}  // namespace gpis_explorer::detail
