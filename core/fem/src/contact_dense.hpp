#pragma once
// Internal: the contact solver's small dense Cholesky on a compact, column-major buffer
// (leading dimension n). Right-looking, so every inner loop runs down a contiguous column and
// vectorizes (the strided row-dot form costs about 3x at the 20-80 rows of five fingertip
// patches). No allocation, no exceptions: called every haptic step.

#include <cmath>
#include <cstddef>

namespace handshare::fem::detail {

// A = L L^T in place (lower triangle read and written). False if not numerically positive
// definite or not finite.
inline bool CholeskyCompact(double* A, int n) noexcept {
  for (int j = 0; j < n; ++j) {
    double* cj = A + static_cast<std::ptrdiff_t>(j) * n;
    const double d = cj[j];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double ljj = std::sqrt(d);
    cj[j] = ljj;
    const double inv = 1.0 / ljj;
    for (int i = j + 1; i < n; ++i) cj[i] *= inv;
    for (int k = j + 1; k < n; ++k) {
      double* ck = A + static_cast<std::ptrdiff_t>(k) * n;
      const double lkj = cj[k];
      for (int i = k; i < n; ++i) ck[i] -= cj[i] * lkj;
    }
  }
  return true;
}

// Solves L L^T x = b in place with the factor of CholeskyCompact.
inline void CholeskyCompactSolve(const double* L, int n, double* b) noexcept {
  for (int j = 0; j < n; ++j) {  // L y = b, column by column
    const double* cj = L + static_cast<std::ptrdiff_t>(j) * n;
    const double yj = b[j] / cj[j];
    b[j] = yj;
    for (int i = j + 1; i < n; ++i) b[i] -= cj[i] * yj;
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y: row i of L^T is column i of L
    const double* ci = L + static_cast<std::ptrdiff_t>(i) * n;
    double s = b[i];
    for (int k = i + 1; k < n; ++k) s -= ci[k] * b[k];
    b[i] = s / ci[i];
  }
}

}  // namespace handshare::fem::detail
