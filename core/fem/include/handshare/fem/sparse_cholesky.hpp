#pragma once
/// @file
/// Sparse Cholesky factorization A = L L^T through CHOLMOD (supernodal, BLAS level 3 from the
/// system BLAS, OpenBLAS on Debian). Offline only: allocates, may take seconds.
/// Every CHOLMOD call is checked; failures become FemError in one place.

#include <cstdint>
#include <memory>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace handshare::fem {

/// A supernodal sparse Cholesky factor of a symmetric positive definite matrix.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Fill-reducing ordering and symbolic factorization of the pattern of A (square, compressed;
  /// only the upper triangle is read).
  void Analyze(const Eigen::SparseMatrix<double>& A);
  /// Numeric factorization of A, which must have the analysed pattern.
  /// @throws FemError "not positive definite at column j" (e.g. an unfixed, floating object).
  void Factorize(const Eigen::SparseMatrix<double>& A);
  /// Analyze + Factorize.
  void Compute(const Eigen::SparseMatrix<double>& A) {
    Analyze(A);
    Factorize(A);
  }

  /// Solves A X = B in place for a block of right-hand sides (rows() x k). Blocked right-hand
  /// sides go through BLAS level 3 in the supernodal solve; workspace is reused between calls.
  void SolveInPlace(Eigen::Ref<Eigen::MatrixXd> B);
  /// Returns A^-1 B.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& B);

  /// Dimension of A (0 before Analyze).
  std::int64_t rows() const noexcept;
  /// Nonzeros in L (after Factorize).
  std::int64_t factor_nonzeros() const noexcept;
  /// Floating-point operations of the numeric factorization, as counted by CHOLMOD.
  double factor_flops() const noexcept;
  /// True if the factor is supernodal.
  bool is_supernodal() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::fem
