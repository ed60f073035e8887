// The contact solver's dense Cholesky (dense_spd.hpp: the AVX-512 factor and the portable one)
// against Eigen's LLT, on random SPD matrices from one unknown to well past the 54 of five
// fingertip patches held in 3-D, in buffers with a leading dimension larger than n.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "../src/dense_spd.hpp"
#include "spd_test_support.hpp"

namespace handshare::fem::detail {
namespace {

// The lower triangle of A in a column-major buffer of leading dimension ld; the upper triangle
// and the padding hold NaN, which the factor must neither read nor write.
std::vector<double> LowerInBuffer(const Eigen::MatrixXd& A, int ld) {
  const int n = static_cast<int>(A.rows());
  std::vector<double> buf(static_cast<std::size_t>(ld) * n, std::numeric_limits<double>::quiet_NaN());
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i) buf[static_cast<std::size_t>(j) * ld + i] = A(i, j);
  return buf;
}

TEST(DenseSpd, FactorAndSolveMatchEigenLltForManySizes) {
  std::mt19937 rng(17);
  std::normal_distribution<double> g;
  for (Isa isa : IsasToTest()) {
    for (int n : {1, 2, 3, 7, 8, 9, 15, 16, 17, 24, 31, 32, 33, 40, 45, 54, 63, 64, 65, 96, 100, 150}) {
      const int ld = n + 5;
      const Eigen::MatrixXd A = RandomSpd(n, rng);
      std::vector<double> buf = LowerInBuffer(A, ld);
      ASSERT_TRUE(FactorSpd(buf.data(), n, ld, isa)) << IsaName(isa) << " n=" << n;
      Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < ld; ++i) {
          const double v = buf[static_cast<std::size_t>(j) * ld + i];
          if (i >= j && i < n) {
            L(i, j) = v;
          } else {
            ASSERT_TRUE(std::isnan(v)) << IsaName(isa) << " n=" << n << ": wrote (" << i << ", " << j << ")";
          }
        }
      }
      // The factor is unique: Eigen's within round-off, and L L^T is A.
      const Eigen::MatrixXd Le = A.llt().matrixL();
      EXPECT_LE((L - Le).norm(), 1e-12 * std::sqrt(A.norm()) * n) << IsaName(isa) << " n=" << n;
      EXPECT_LE((L * L.transpose() - A).norm(), 1e-14 * A.norm() * n) << IsaName(isa) << " n=" << n;
      // 1-11 right-hand sides (the solver's 1 and 2 per slipping patch) in a buffer of its own
      // leading dimension.
      const int nrhs = 1 + n % 11, ldb = n + 2;
      Eigen::MatrixXd B(n, nrhs);
      for (int i = 0; i < n; ++i)
        for (int c = 0; c < nrhs; ++c) B(i, c) = g(rng);
      std::vector<double> x(static_cast<std::size_t>(ldb) * nrhs, 0.0);
      for (int c = 0; c < nrhs; ++c)
        for (int i = 0; i < n; ++i) x[static_cast<std::size_t>(c) * ldb + i] = B(i, c);
      SolveFactoredSpd(buf.data(), n, ld, x.data(), nrhs, ldb, isa);
      const Eigen::MatrixXd want = A.llt().solve(B);
      const double cond_bound = 1e-13 * A.norm() * A.inverse().norm();
      for (int c = 0; c < nrhs; ++c) {
        const Eigen::VectorXd got = Eigen::Map<const Eigen::VectorXd>(x.data() + static_cast<std::ptrdiff_t>(c) * ldb, n);
        EXPECT_LE((got - want.col(c)).norm(), cond_bound * want.col(c).norm()) << IsaName(isa) << " n=" << n;
      }
    }
  }
}

TEST(DenseSpd, RejectsIndefiniteAndNonFiniteInput) {
  std::mt19937 rng(23);
  for (Isa isa : IsasToTest()) {
    for (int n : {1, 5, 8, 9, 33, 54, 70}) {
      const Eigen::MatrixXd A = RandomSpd(n, rng);
      // Indefinite: one negative eigenvalue.
      const Eigen::MatrixXd B = A - 2.0 * A.norm() * Eigen::VectorXd::Unit(n, n - 1) * Eigen::VectorXd::Unit(n, n - 1).transpose();
      std::vector<double> buf = LowerInBuffer(B, n);
      EXPECT_FALSE(FactorSpd(buf.data(), n, n, isa)) << IsaName(isa) << " n=" << n;
      // NaN on the diagonal, and an infinite entry below it.
      Eigen::MatrixXd C = A;
      C(n / 2, n / 2) = std::numeric_limits<double>::quiet_NaN();
      buf = LowerInBuffer(C, n);
      EXPECT_FALSE(FactorSpd(buf.data(), n, n, isa)) << IsaName(isa) << " n=" << n;
      if (n > 1) {
        Eigen::MatrixXd D = A;
        D(n - 1, 0) = std::numeric_limits<double>::infinity();
        buf = LowerInBuffer(D, n);
        EXPECT_FALSE(FactorSpd(buf.data(), n, n, isa)) << IsaName(isa) << " n=" << n;
      }
    }
  }
}

}  // namespace
}  // namespace handshare::fem::detail
