// The contact solver's dense Cholesky (dense_spd.hpp: the AVX-512 factor and the portable one)
// against Eigen's LLT, on random SPD matrices from one unknown to well past the 54 of five
// fingertip patches held in 3-D, in buffers with a leading dimension larger than n.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
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
      // leading dimension, and widths that fill one and two passes of 8 and 16 lanes exactly
      // and one past.
      for (const int nrhs : {1 + n % 11, 16, 17, 24, 25, 33}) {
        const int ldb = n + 2;
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
          EXPECT_LE((got - want.col(c)).norm(), cond_bound * want.col(c).norm())
              << IsaName(isa) << " n=" << n << " nrhs=" << nrhs << " column " << c;
        }
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

// A factor resumed after the rows from p0 changed (ResumeFactorSpd) is bit for bit the factor of
// the whole new matrix: its leading p0 x p0 block is the old one's, the rows below are new (a
// held-set pivot that releases or adds the last nodes' rows). Sizes up to 100 with p0 from 0 to
// n, leading dimensions above n, NaN in the upper triangle; without AVX-512 it declines.
TEST(DenseSpd, AResumedFactorIsTheWholeFactorBitForBit) {
  std::mt19937 rng(23);
  std::normal_distribution<double> g;
  bool ran = false;
  for (Isa isa : IsasToTest()) {
    for (int n : {1, 5, 9, 17, 33, 41, 54, 70, 100}) {
      for (int p0 : {0, 1, n / 3, n / 2, n - 3, n - 1, n}) {
        if (p0 < 0 || p0 > n) continue;
        const int ld = n + 3;
        const Eigen::MatrixXd A = RandomSpd(n, rng);
        // The new matrix: the same leading block, other rows below it, SPD by construction
        // (its Schur complement onto the trailing rows is a random SPD matrix).
        const int t = n - p0;
        Eigen::MatrixXd B(n, n);
        const Eigen::MatrixXd A11 = A.topLeftCorner(p0, p0);
        Eigen::MatrixXd B21(t, p0);
        for (int i = 0; i < t; ++i)
          for (int j = 0; j < p0; ++j) B21(i, j) = 0.3 * g(rng);
        B.topLeftCorner(p0, p0) = A11;
        B.bottomLeftCorner(t, p0) = B21;
        B.topRightCorner(p0, t) = B21.transpose();
        Eigen::MatrixXd S = t > 0 ? RandomSpd(t, rng) : Eigen::MatrixXd(0, 0);
        if (p0 > 0 && t > 0) S += B21 * A11.llt().solve(B21.transpose());
        B.bottomRightCorner(t, t) = 0.5 * (S + S.transpose());
        std::vector<double> resumed = LowerInBuffer(A, ld);
        const bool avx = isa == Isa::kAvx512;
        ASSERT_TRUE(FactorSpd(resumed.data(), n, ld, isa));
        // B's rows from p0 on, over the old factor's leading columns' rows below p0.
        for (int j = 0; j < n; ++j)
          for (int i = std::max(j, p0); i < n; ++i) resumed[static_cast<std::size_t>(j) * ld + i] = B(i, j);
        const std::vector<double> before = resumed;
        const bool ok = ResumeFactorSpd(resumed.data(), n, ld, p0, isa);
        std::vector<double> whole = LowerInBuffer(B, ld);
        ASSERT_TRUE(FactorSpd(whole.data(), n, ld, isa));
        if (!avx) {
          EXPECT_FALSE(ok);
          EXPECT_EQ(0, std::memcmp(before.data(), resumed.data(), sizeof(double) * before.size()));
          continue;
        }
        ran = true;
        ASSERT_TRUE(ok) << "n=" << n << " p0=" << p0;
        for (std::size_t k = 0; k < whole.size(); ++k) {
          const double a = resumed[k], b = whole[k];
          ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0)
              << "n=" << n << " p0=" << p0 << " entry " << k << ": " << a << " against " << b;
        }
      }
    }
  }
  if (!ran) GTEST_SKIP() << "no AVX-512 here: the resumed factor is declined (checked above)";
}

TEST(DenseSpd, WeightedRowSumsAreTheSumsOfTheListedRowsOfEveryColumn) {
  // The friction solve's cone equations: a patch's rows (any order, a row listed twice adds
  // twice) of 1..20 columns, against the sums written out; the columns past ncols and the
  // entries past the sums are left alone.
  std::mt19937 rng(31);
  std::normal_distribution<double> g;
  const int rows_total = 40;
  const std::ptrdiff_t ldz = 45;
  for (Isa isa : IsasToTest()) {
    for (int ncols : {1, 2, 7, 8, 9, 15, 16, 17, 20}) {
      std::vector<double> Z(static_cast<std::size_t>(ldz) * (ncols + 1));
      for (double& z : Z) z = g(rng);
      const std::vector<std::int32_t> rows = {3, 4, 5, 17, 39, 0, 22, 17};
      std::vector<double> w0(rows.size()), w1(rows.size());
      for (std::size_t m = 0; m < rows.size(); ++m) {
        w0[m] = g(rng);
        w1[m] = g(rng);
      }
      std::vector<double> s(2 * static_cast<std::size_t>(ncols) + 1, std::numeric_limits<double>::quiet_NaN());
      WeightedRowSums(Z.data(), ldz, ncols, rows.data(), w0.data(), w1.data(), static_cast<int>(rows.size()), s.data(),
                      s.data() + ncols, isa);
      for (int c = 0; c < ncols; ++c) {
        double want0 = 0.0, want1 = 0.0;
        for (std::size_t m = 0; m < rows.size(); ++m) {
          ASSERT_LT(rows[m], rows_total);
          want0 += w0[m] * Z[static_cast<std::size_t>(c * ldz + rows[m])];
          want1 += w1[m] * Z[static_cast<std::size_t>(c * ldz + rows[m])];
        }
        EXPECT_NEAR(s[static_cast<std::size_t>(c)], want0, 1e-13) << IsaName(isa) << " ncols=" << ncols << " column " << c;
        EXPECT_NEAR(s[static_cast<std::size_t>(ncols + c)], want1, 1e-13) << IsaName(isa) << " ncols=" << ncols << " column " << c;
      }
      EXPECT_TRUE(std::isnan(s.back())) << IsaName(isa) << " ncols=" << ncols << ": wrote past the sums";
    }
  }
}

}  // namespace
}  // namespace handshare::fem::detail
