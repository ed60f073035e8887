#pragma once
/// @file
/// Sparse Cholesky factorization A = L L^T through CHOLMOD (supernodal, BLAS level 3 from the
/// system BLAS, OpenBLAS on Debian). Offline only: allocates, may take seconds.
/// Every CHOLMOD call is checked; failures become FemError in one place.

#include <cstdint>
#include <memory>
#include <vector>

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
  /// Symbolic analysis with a given ordering and no postordering: column perm[k] of A becomes
  /// column k of the factored P A P^T (so the last columns of perm stay last).
  void AnalyzeWithOrdering(const Eigen::SparseMatrix<double>& A, const std::vector<int>& perm);
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

  /// The ordering in use: perm[k] = column of A factored k-th (after Analyze).
  std::vector<int> Permutation() const;
  /// Dense lower-triangular trailing block L(n-t.., n-t..) of the factor of P A P^T (after
  /// Factorize; supernodal only). With the last t columns of the ordering being a set S, this is
  /// the Cholesky factor of the Schur complement of A onto S.
  Eigen::MatrixXd TrailingFactor(std::int64_t t) const;

  /// Dimension of A (0 before Analyze).
  std::int64_t rows() const noexcept;
  /// Nonzeros in L (known after Analyze).
  std::int64_t factor_nonzeros() const noexcept;
  /// Floating-point operations of the numeric factorization (estimated by Analyze).
  double factor_flops() const noexcept;
  /// True if the factor is supernodal.
  bool is_supernodal() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::fem
