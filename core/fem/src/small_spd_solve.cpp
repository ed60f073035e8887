#include "small_spd_solve.hpp"

#include <immintrin.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

#include "dense_small.hpp"

namespace handshare::fem::detail {

namespace {

bool Portable(const double* A, int n, int ld, double eps, double* b) noexcept {
  double L[kSmallSpdMax * kSmallSpdMax];
  for (int j = 0; j < n; ++j) {
    for (int i = j; i < n; ++i) L[j * n + i] = A[static_cast<std::ptrdiff_t>(j) * ld + i];
    L[j * n + j] += eps;
  }
  if (!CholeskyInPlace(L, n, n)) return false;
  CholeskySolveInPlace(L, n, n, b);
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(b[i])) return false;
  }
  return true;
}

#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma")))

// GCC 12 warns inside its own AVX-512 headers (the undefined source of masked intrinsics).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

// Lanes of vector r (rows 8 r .. 8 r + 7) that hold a row in [lo, n).
constexpr __mmask8 Rows(int lo, int n, int r) {
  unsigned m = 0;
  for (int l = 0; l < 8; ++l) {
    const int row = 8 * r + l;
    if (row >= lo && row < n) m |= 1u << l;
  }
  return static_cast<__mmask8>(m);
}

HS_AVX512 inline double Lane(__m512d v, int l) noexcept {
  return _mm512_cvtsd_f64(_mm512_permutexvar_pd(_mm512_set1_epi64(l), v));
}

HS_AVX512 inline __m512d Splat(__m512d v, int l) noexcept { return _mm512_permutexvar_pd(_mm512_set1_epi64(l), v); }

// LDL^T, right-looking, with compile-time bounds: the loops unroll, so the columns live in
// registers and every lane index and mask is a constant. The critical path is one division, one
// multiply and one FMA per column (no square root; the broadcast factors c_j[k] are taken before
// the division). Column j's rows above j are never read.
template <int N>
HS_AVX512 bool Avx512(const double* A, int ld, double eps, double* b) noexcept {
  constexpr int R = (N + 7) / 8;
  __m512d c[N][R];
#pragma GCC unroll 16
  for (int j = 0; j < N; ++j) {
#pragma GCC unroll 2
    for (int r = j / 8; r < R; ++r) c[j][r] = _mm512_maskz_loadu_pd(Rows(j, N, r), A + static_cast<std::ptrdiff_t>(j) * ld + 8 * r);
    c[j][j / 8] = _mm512_mask_add_pd(c[j][j / 8], static_cast<__mmask8>(1u << (j % 8)), c[j][j / 8], _mm512_set1_pd(eps));
  }
  // L (unit lower, column j = c_j / d_j) kept row-major for the transposed solve: Lt[i][k] = L_ik.
  alignas(64) double Lc[N][8 * R];
  __m512d dinv[R];
#pragma GCC unroll 2
  for (int r = 0; r < R; ++r) dinv[r] = _mm512_setzero_pd();
#pragma GCC unroll 16
  for (int j = 0; j < N; ++j) {
    const double d = Lane(c[j][j / 8], j % 8);
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double rd = 1.0 / d;
    dinv[j / 8] = _mm512_mask_mov_pd(dinv[j / 8], static_cast<__mmask8>(1u << (j % 8)), _mm512_set1_pd(rd));
    __m512d m[R];
#pragma GCC unroll 2
    for (int r = j / 8; r < R; ++r) {
      m[r] = _mm512_mul_pd(c[j][r], _mm512_set1_pd(rd));
      _mm512_store_pd(&Lc[j][8 * r], m[r]);
    }
#pragma GCC unroll 16
    for (int k = j + 1; k < N; ++k) {
      const __m512d f = Splat(c[j][k / 8], k % 8);
#pragma GCC unroll 2
      for (int r = k / 8; r < R; ++r) c[k][r] = _mm512_fnmadd_pd(m[r], f, c[k][r]);
    }
  }
  // Rows of L (for L^T x = z by columns); scalar copies, off the critical path.
  alignas(64) double Lr[N][8 * R];
#pragma GCC unroll 16
  for (int i = 0; i < N; ++i) {
    for (int k = 0; k < 8 * R; ++k) Lr[i][k] = k < i ? Lc[k][i] : 0.0;
  }
  // L y = b: y_j is final once the columns before it are subtracted.
  __m512d y[R];
#pragma GCC unroll 2
  for (int r = 0; r < R; ++r) y[r] = _mm512_maskz_loadu_pd(Rows(0, N, r), b + 8 * r);
#pragma GCC unroll 16
  for (int j = 0; j + 1 < N; ++j) {
    const __m512d yj = Splat(y[j / 8], j % 8);
#pragma GCC unroll 2
    for (int r = j / 8; r < R; ++r) {
      y[r] = _mm512_mask3_fnmadd_pd(_mm512_load_pd(&Lc[j][8 * r]), yj, y[r], Rows(j + 1, N, r));
    }
  }
  // z = D^-1 y, then L^T x = z from the bottom: x_i final, subtract it from the rows above.
#pragma GCC unroll 2
  for (int r = 0; r < R; ++r) y[r] = _mm512_mul_pd(y[r], dinv[r]);
#pragma GCC unroll 16
  for (int i = N - 1; i > 0; --i) {
    const __m512d xi = Splat(y[i / 8], i % 8);
#pragma GCC unroll 2
    for (int r = 0; r <= (i - 1) / 8; ++r) {
      y[r] = _mm512_mask3_fnmadd_pd(_mm512_load_pd(&Lr[i][8 * r]), xi, y[r], Rows(0, i, r));
    }
  }
#pragma GCC unroll 2
  for (int r = 0; r < R; ++r) {
    // A non-finite result fails the solve (x - x is 0 only for finite x).
    if (_mm512_cmp_pd_mask(_mm512_sub_pd(y[r], y[r]), _mm512_setzero_pd(), _CMP_EQ_OQ) != 0xFF) return false;
    _mm512_mask_storeu_pd(b + 8 * r, Rows(0, N, r), y[r]);
  }
  return true;
}

#pragma GCC diagnostic pop

using Kernel = bool (*)(const double*, int, double, double*) noexcept;

template <std::size_t... I>
constexpr auto MakeTable(std::index_sequence<I...>) {
  return std::array<Kernel, sizeof...(I)>{&Avx512<static_cast<int>(I) + 1>...};
}

}  // namespace

bool SmallSpdSolve(const double* A, int n, int ld, double eps, double* b, Isa isa) noexcept {
  if (n <= 0) return true;
  if (n > kSmallSpdMax) return false;
  if (isa == Isa::kAvx512) {
    static constexpr auto kTable = MakeTable(std::make_index_sequence<kSmallSpdMax>{});
    return kTable[static_cast<std::size_t>(n - 1)](A, ld, eps, b);
  }
  return Portable(A, n, ld, eps, b);
}

}  // namespace handshare::fem::detail
