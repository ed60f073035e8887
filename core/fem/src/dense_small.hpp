#pragma once
// Internal: small dense factorizations on caller-owned, column-major buffers with leading
// dimension ld. No allocation, no exceptions: the real-time solvers call these every step.

#include <cmath>
#include <cstdint>
#include <utility>

namespace handshare::fem::detail {

// In-place Cholesky A = L L^T of the leading n x n block (lower triangle read and written).
// Returns false if A is not numerically positive definite or not finite.
inline bool CholeskyInPlace(double* A, int n, int ld) noexcept {
  for (int j = 0; j < n; ++j) {
    double* cj = A + static_cast<std::ptrdiff_t>(j) * ld;
    double d = cj[j];
    for (int k = 0; k < j; ++k) {
      const double l = A[static_cast<std::ptrdiff_t>(k) * ld + j];
      d -= l * l;
    }
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double ljj = std::sqrt(d);
    cj[j] = ljj;
    const double inv = 1.0 / ljj;
    for (int i = j + 1; i < n; ++i) {
      double s = cj[i];
      for (int k = 0; k < j; ++k) {
        const double* ck = A + static_cast<std::ptrdiff_t>(k) * ld;
        s -= ck[i] * ck[j];
      }
      cj[i] = s * inv;
    }
  }
  return true;
}

// Solves L L^T x = b in place with the factor from CholeskyInPlace.
inline void CholeskySolveInPlace(const double* L, int n, int ld, double* b) noexcept {
  for (int i = 0; i < n; ++i) {  // L y = b (L column-major: row i of L is L[k*ld + i])
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= L[static_cast<std::ptrdiff_t>(k) * ld + i] * b[k];
    b[i] = s / L[static_cast<std::ptrdiff_t>(i) * ld + i];
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y (column i of L is row i of L^T)
    const double* ci = L + static_cast<std::ptrdiff_t>(i) * ld;
    double s = b[i];
    for (int k = i + 1; k < n; ++k) s -= ci[k] * b[k];
    b[i] = s / ci[i];
  }
}

// In-place LU with partial pivoting, P A = L U (unit lower L). piv[j] = row swapped with j.
// Returns false if a pivot is zero or not finite.
inline bool LuInPlace(double* A, int n, int ld, std::int32_t* piv) noexcept {
  for (int j = 0; j < n; ++j) {
    double* cj = A + static_cast<std::ptrdiff_t>(j) * ld;
    int p = j;
    double best = std::abs(cj[j]);
    for (int i = j + 1; i < n; ++i) {
      if (std::abs(cj[i]) > best) {
        best = std::abs(cj[i]);
        p = i;
      }
    }
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    piv[j] = p;
    if (p != j) {
      for (int k = 0; k < n; ++k) {
        double* ck = A + static_cast<std::ptrdiff_t>(k) * ld;
        std::swap(ck[j], ck[p]);
      }
    }
    const double inv = 1.0 / cj[j];
    for (int i = j + 1; i < n; ++i) cj[i] *= inv;
    for (int k = j + 1; k < n; ++k) {
      double* ck = A + static_cast<std::ptrdiff_t>(k) * ld;
      const double u = ck[j];
      if (u == 0.0) continue;
      for (int i = j + 1; i < n; ++i) ck[i] -= cj[i] * u;
    }
  }
  return true;
}

inline void LuSolveInPlace(const double* LU, int n, int ld, const std::int32_t* piv,
                           double* b) noexcept {
  for (int j = 0; j < n; ++j) std::swap(b[j], b[piv[j]]);
  for (int j = 0; j < n; ++j) {
    const double* cj = LU + static_cast<std::ptrdiff_t>(j) * ld;
    for (int i = j + 1; i < n; ++i) b[i] -= cj[i] * b[j];
  }
  for (int j = n - 1; j >= 0; --j) {
    const double* cj = LU + static_cast<std::ptrdiff_t>(j) * ld;
    b[j] /= cj[j];
    for (int i = 0; i < j; ++i) b[i] -= cj[i] * b[j];
  }
}

}  // namespace handshare::fem::detail
