// The small dense SPD solve of the contact solver (AVX-512 register kernel and portable path)
// against Eigen's LLT, on random matrices of every size it takes.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/Core>

#include "../src/small_spd_solve.hpp"
#include "spd_test_support.hpp"

namespace handshare::fem::detail {
namespace {

TEST(SmallSpdSolve, MatchesEigenLltForEverySizeWithRegularization) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (Isa isa : IsasToTest()) {
    for (int n = 1; n <= kSmallSpdMax; ++n) {
      for (double eps : {0.0, 0.37}) {
        const int ld = n + 3;
        const Eigen::MatrixXd A = RandomSpd(n, rng);
        // Column-major with ld > n; the upper triangle and the padding hold NaN, which must
        // never be read (the solver reads rows >= column only).
        std::vector<double> buf(static_cast<std::size_t>(ld) * n, std::numeric_limits<double>::quiet_NaN());
        for (int j = 0; j < n; ++j)
          for (int i = j; i < n; ++i) buf[static_cast<std::size_t>(j) * ld + i] = A(i, j);
        const std::vector<double> before = buf;
        Eigen::VectorXd b(n);
        for (int i = 0; i < n; ++i) b[i] = g(rng);
        const Eigen::MatrixXd Ae = A + eps * Eigen::MatrixXd::Identity(n, n);
        const Eigen::VectorXd want = Ae.llt().solve(b);
        std::vector<double> x(b.data(), b.data() + n);
        ASSERT_TRUE(SmallSpdSolve(buf.data(), n, ld, eps, x.data(), isa)) << IsaName(isa) << " n=" << n;
        const Eigen::VectorXd got = Eigen::Map<Eigen::VectorXd>(x.data(), n);
        const double cond_bound = 1e-13 * Ae.norm() * Ae.inverse().norm();
        EXPECT_LE((got - want).norm(), cond_bound * want.norm() + 1e-300) << IsaName(isa) << " n=" << n << " eps=" << eps;
        // The residual is round-off.
        EXPECT_LE((Ae * got - b).norm(), 1e-12 * Ae.norm() * got.norm()) << IsaName(isa) << " n=" << n;
        for (std::size_t k = 0; k < buf.size(); ++k) {
          ASSERT_TRUE(std::isnan(before[k]) ? std::isnan(buf[k]) : buf[k] == before[k]) << "A was written";
        }
      }
    }
  }
}

TEST(SmallSpdSolve, RejectsIndefiniteAndNonFiniteInput) {
  std::mt19937 rng(11);
  for (Isa isa : IsasToTest()) {
    for (int n : {1, 5, 8, 9, 15, 16}) {
      Eigen::MatrixXd A = RandomSpd(n, rng);
      std::vector<double> b(static_cast<std::size_t>(n), 1.0);
      // Indefinite: one negative eigenvalue.
      Eigen::MatrixXd B = A - 2.0 * A.norm() * Eigen::VectorXd::Unit(n, n - 1) * Eigen::VectorXd::Unit(n, n - 1).transpose();
      EXPECT_FALSE(SmallSpdSolve(B.data(), n, n, 0.0, b.data(), isa)) << IsaName(isa) << " n=" << n;
      // NaN on the diagonal, and an infinite entry below it.
      Eigen::MatrixXd C = A;
      C(n / 2, n / 2) = std::numeric_limits<double>::quiet_NaN();
      std::fill(b.begin(), b.end(), 1.0);
      EXPECT_FALSE(SmallSpdSolve(C.data(), n, n, 0.0, b.data(), isa)) << IsaName(isa) << " n=" << n;
      if (n > 1) {
        Eigen::MatrixXd D = A;
        D(n - 1, 0) = std::numeric_limits<double>::infinity();
        std::fill(b.begin(), b.end(), 1.0);
        EXPECT_FALSE(SmallSpdSolve(D.data(), n, n, 0.0, b.data(), isa)) << IsaName(isa) << " n=" << n;
      }
    }
    std::vector<double> b(kSmallSpdMax + 1, 1.0);
    const Eigen::MatrixXd big = Eigen::MatrixXd::Identity(kSmallSpdMax + 1, kSmallSpdMax + 1);
    EXPECT_FALSE(SmallSpdSolve(big.data(), kSmallSpdMax + 1, kSmallSpdMax + 1, 0.0, b.data(), isa));
  }
}

}  // namespace
}  // namespace handshare::fem::detail
