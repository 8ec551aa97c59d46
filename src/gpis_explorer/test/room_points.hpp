// The training points of the gpis_explorer tests and benchmarks: n points of a rotated
// 2 m room, 80 % wall contacts with 1 cm noise (label 0), 20 % interior points (label -1),
// seeded. Shared by test/test_local_gpis.cpp and bench/bench_gpis.cpp.
#pragma once

#include <random>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace gpis_explorer::test {

inline void room_points(int n, unsigned seed, Eigen::Matrix2Xd& X, Eigen::VectorXd& y, double angle = 0.3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  X.resize(2, n);
  y.resize(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector2d p;
    if (i % 5 == 4) {
      p = {0.7 * u(rng), 0.7 * u(rng)};
      y(i) = -1.0;
    } else {
      const double t = u(rng);
      switch (i % 4) {
        case 0: p = {t, -1.0}; break;
        case 1: p = {t, 1.0}; break;
        case 2: p = {-1.0, t}; break;
        default: p = {1.0, t}; break;
      }
      p += Eigen::Vector2d(noise(rng), noise(rng));
      y(i) = 0.0;
    }
    X.col(i) = Eigen::Rotation2Dd(angle) * p;
  }
}

}  // namespace gpis_explorer::test
