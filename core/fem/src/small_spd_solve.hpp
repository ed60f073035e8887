#pragma once
// Internal: solve (A + eps I) x = b for a small symmetric positive definite A (n <= 16, the
// 3 x 5 = 15 unknowns of five sticking fingertips), without touching A. The general Cholesky of
// dense_small.hpp walks strided rows with a scalar dependency chain and costs about 8,000
// instructions at n = 15; here the columns stay in SIMD registers (AVX-512: two 8-double vectors
// per column, every column update 2 FMAs), so the chain is one square root, division and FMA
// per column. A portable build (no AVX-512) copies A and uses dense_small.hpp.
// Real-time safe: noexcept, no allocation, no exceptions.

#include "planar_columns.hpp"  // Isa

namespace handshare::fem::detail {

inline constexpr int kSmallSpdMax = 16;

/// x = (A + eps I)^-1 b for n <= kSmallSpdMax, A column-major with leading dimension ld (only
/// the lower triangle, rows >= column, is read). b is overwritten with x. False if A + eps I is
/// not numerically positive definite or a result is not finite.
bool SmallSpdSolve(const double* A, int n, int ld, double eps, double* b, Isa isa) noexcept;

}  // namespace handshare::fem::detail
