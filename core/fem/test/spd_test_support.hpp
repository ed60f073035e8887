#pragma once
// Shared by the dense SPD kernels' tests (small_spd_solve_test.cpp, dense_spd_test.cpp).

#include <random>
#include <vector>

#include <Eigen/Core>

#include "../src/planar_columns.hpp"

namespace handshare::fem::detail {

// The portable path always; the AVX-512 kernels where this processor has them.
inline std::vector<Isa> IsasToTest() {
  std::vector<Isa> isas = {Isa::kPortable};
  if (BestIsa() == Isa::kAvx512) isas.push_back(Isa::kAvx512);
  return isas;
}

// Random SPD matrix (Gram matrix plus a diagonal shift), condition number up to ~1e4.
inline Eigen::MatrixXd RandomSpd(int n, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd M(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) M(i, j) = g(rng);
  return M * M.transpose() + 1e-3 * n * Eigen::MatrixXd::Identity(n, n);
}

}  // namespace handshare::fem::detail
