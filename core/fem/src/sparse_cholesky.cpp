#include "handshare/fem/sparse_cholesky.hpp"

#include <algorithm>
#include <cstring>
#include <string>

#include <cholmod.h>

#include "handshare/fem/error.hpp"

namespace handshare::fem {

struct SparseCholesky::Impl {
  cholmod_common c;
  cholmod_factor* L = nullptr;
  cholmod_dense* X = nullptr;
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;
  std::int64_t n = 0;
  bool factorized = false;

  Impl() {
    cholmod_start(&c);
    // Supernodal: dense BLAS-3 kernels on the supernodes (OpenBLAS through libblas.so.3).
    c.supernodal = CHOLMOD_SUPERNODAL;
    // Errors are turned into exceptions by Check(), not printed by CHOLMOD.
    c.error_handler = nullptr;
    c.print = 0;
    // Try AMD and METIS (nested dissection), keep the ordering with the least fill: the factor
    // and the many solves of the precomputation both scale with it.
    c.nmethods = 2;
    c.method[0].ordering = CHOLMOD_AMD;
    c.method[1].ordering = CHOLMOD_METIS;
    c.postorder = 1;
  }
  ~Impl() {
    cholmod_free_dense(&X, &c);
    cholmod_free_dense(&Y, &c);
    cholmod_free_dense(&E, &c);
    cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }

  // The one place CHOLMOD status codes become exceptions.
  void Check(const char* call) {
    if (c.status < CHOLMOD_OK) {
      std::string why;
      switch (c.status) {
        case CHOLMOD_OUT_OF_MEMORY: why = "out of memory"; break;
        case CHOLMOD_TOO_LARGE: why = "problem too large"; break;
        case CHOLMOD_INVALID: why = "invalid input"; break;
        case CHOLMOD_GPU_PROBLEM: why = "GPU problem"; break;
        default: why = "error " + std::to_string(c.status); break;
      }
      throw FemError(std::string("CHOLMOD ") + call + " failed: " + why);
    }
  }

  // A view of an Eigen compressed column-major matrix; stype 1: CHOLMOD reads the upper part.
  static cholmod_sparse View(const Eigen::SparseMatrix<double>& A) {
    if (!A.isCompressed()) throw FemError("SparseCholesky: matrix must be compressed");
    if (A.rows() != A.cols()) throw FemError("SparseCholesky: matrix must be square");
    cholmod_sparse s{};
    s.nrow = static_cast<size_t>(A.rows());
    s.ncol = static_cast<size_t>(A.cols());
    s.nzmax = static_cast<size_t>(A.nonZeros());
    s.p = const_cast<int*>(A.outerIndexPtr());
    s.i = const_cast<int*>(A.innerIndexPtr());
    s.nz = nullptr;
    s.x = const_cast<double*>(A.valuePtr());
    s.z = nullptr;
    s.stype = 1;
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

void SparseCholesky::Analyze(const Eigen::SparseMatrix<double>& A) {
  cholmod_sparse s = Impl::View(A);
  cholmod_free_factor(&impl_->L, &impl_->c);
  impl_->factorized = false;
  impl_->L = cholmod_analyze(&s, &impl_->c);
  impl_->Check("analyze");
  if (impl_->L == nullptr) throw FemError("CHOLMOD analyze returned no factor");
  impl_->n = A.rows();
}

void SparseCholesky::AnalyzeWithOrdering(const Eigen::SparseMatrix<double>& A,
                                         const std::vector<int>& perm) {
  if (static_cast<Eigen::Index>(perm.size()) != A.rows()) {
    throw FemError("SparseCholesky::AnalyzeWithOrdering: permutation has the wrong size");
  }
  cholmod_sparse s = Impl::View(A);
  cholmod_free_factor(&impl_->L, &impl_->c);
  impl_->factorized = false;
  const int nmethods = impl_->c.nmethods;
  const int ordering = impl_->c.method[0].ordering;
  const int postorder = impl_->c.postorder;
  impl_->c.nmethods = 1;
  impl_->c.method[0].ordering = CHOLMOD_GIVEN;
  impl_->c.postorder = 0;
  std::vector<int> p = perm;
  impl_->L = cholmod_analyze_p(&s, p.data(), nullptr, 0, &impl_->c);
  impl_->c.nmethods = nmethods;
  impl_->c.method[0].ordering = ordering;
  impl_->c.postorder = postorder;
  impl_->Check("analyze (given ordering)");
  if (impl_->L == nullptr) throw FemError("CHOLMOD analyze returned no factor");
  impl_->n = A.rows();
}

std::vector<int> SparseCholesky::Permutation() const {
  if (!impl_ || impl_->L == nullptr) return {};
  const int* p = static_cast<const int*>(impl_->L->Perm);
  return std::vector<int>(p, p + impl_->L->n);
}

Eigen::MatrixXd SparseCholesky::TrailingFactor(std::int64_t t) const {
  const cholmod_factor* L = impl_ ? impl_->L : nullptr;
  if (L == nullptr || !impl_->factorized || !L->is_super) {
    throw FemError("SparseCholesky::TrailingFactor: needs a supernodal numeric factor");
  }
  const auto n = static_cast<std::int64_t>(L->n);
  if (t < 0 || t > n) throw FemError("SparseCholesky::TrailingFactor: bad size");
  const std::int64_t first = n - t;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(t, t);
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* px = static_cast<const int*>(L->px);
  const int* rows = static_cast<const int*>(L->s);
  const double* x = static_cast<const double*>(L->x);
  for (std::size_t s = 0; s < L->nsuper; ++s) {
    const std::int64_t k0 = super[s], k1 = super[s + 1];
    if (k1 <= first) continue;
    const std::int64_t nrows = pi[s + 1] - pi[s];
    const int* r = rows + pi[s];
    const double* v = x + px[s];
    // Supernode s: columns k0..k1-1, a dense nrows x (k1-k0) column-major block.
    for (std::int64_t j = std::max(k0, first); j < k1; ++j) {
      const double* col = v + (j - k0) * nrows;
      for (std::int64_t q = 0; q < nrows; ++q) {
        if (r[q] >= j) out(r[q] - first, j - first) = col[q];
      }
    }
  }
  return out;
}

void SparseCholesky::Factorize(const Eigen::SparseMatrix<double>& A) {
  if (impl_->L == nullptr || A.rows() != impl_->n) {
    throw FemError("SparseCholesky::Factorize: call Analyze with this pattern first");
  }
  cholmod_sparse s = Impl::View(A);
  cholmod_factorize(&s, impl_->L, &impl_->c);
  impl_->Check("factorize");
  if (impl_->c.status == CHOLMOD_NOT_POSDEF || impl_->L->minor < impl_->L->n) {
    throw FemError("stiffness matrix is not positive definite (CHOLMOD stopped at column " +
                   std::to_string(impl_->L->minor) + " of " + std::to_string(impl_->L->n) +
                   "): is every part of the object held by fixed nodes?");
  }
  impl_->factorized = true;
}

void SparseCholesky::SolveInPlace(Eigen::Ref<Eigen::MatrixXd> B) {
  if (impl_->L == nullptr || !impl_->factorized) {
    throw FemError("SparseCholesky::Solve: not factorized");
  }
  if (B.rows() != impl_->n) throw FemError("SparseCholesky::Solve: right-hand side has wrong size");
  if (B.cols() == 0) return;
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(B.rows());
  b.ncol = static_cast<size_t>(B.cols());
  b.d = static_cast<size_t>(B.outerStride());
  b.x = B.data();
  b.z = nullptr;
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  b.nzmax = b.d * b.ncol;
  const int ok = cholmod_solve2(CHOLMOD_A, impl_->L, &b, nullptr, &impl_->X, nullptr, &impl_->Y,
                                &impl_->E, &impl_->c);
  impl_->Check("solve");
  if (!ok || impl_->X == nullptr) throw FemError("CHOLMOD solve failed");
  const auto* x = static_cast<const double*>(impl_->X->x);
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    std::memcpy(B.col(j).data(), x + static_cast<std::size_t>(j) * impl_->X->d,
                sizeof(double) * static_cast<std::size_t>(B.rows()));
  }
}

Eigen::MatrixXd SparseCholesky::Solve(const Eigen::MatrixXd& B) {
  Eigen::MatrixXd X = B;
  SolveInPlace(X);
  return X;
}

std::int64_t SparseCholesky::rows() const noexcept { return impl_ ? impl_->n : 0; }

std::int64_t SparseCholesky::factor_nonzeros() const noexcept {
  if (!impl_ || impl_->L == nullptr) return 0;
  return static_cast<std::int64_t>(impl_->c.lnz);
}

double SparseCholesky::factor_flops() const noexcept {
  return impl_ ? impl_->c.fl : 0.0;
}

bool SparseCholesky::is_supernodal() const noexcept {
  return impl_ && impl_->L != nullptr && impl_->L->is_super;
}

}  // namespace handshare::fem
