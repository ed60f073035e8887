#include "dense_spd.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace handshare::fem::detail {

namespace {

// ---- portable: Eigen (its work space for these sizes is on the stack) ----

using StridedMatrix = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

bool FactorEigen(double* A, int n, int ld) noexcept {
  StridedMatrix m(A, n, n, Eigen::OuterStride<>(ld));
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd, 0, Eigen::OuterStride<>>> llt(m);
  if (llt.info() != Eigen::Success) return false;
  for (int k = 0; k < n; ++k) {  // LLT's success does not say the factor is finite
    const double d = A[static_cast<std::ptrdiff_t>(k) * ld + k];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
  }
  return true;
}

void SolveEigen(const double* L, int n, int ld, double* B, int nrhs, int ldb) noexcept {
  const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> l(L, n, n, Eigen::OuterStride<>(ld));
  if (nrhs == 1) {  // a vector: Eigen's substitution, not its blocked matrix solve (1.3 against 1.7 us at 45)
    Eigen::Map<Eigen::VectorXd> b(B, n);
    l.triangularView<Eigen::Lower>().solveInPlace(b);
    l.triangularView<Eigen::Lower>().transpose().solveInPlace(b);
    return;
  }
  StridedMatrix b(B, n, nrhs, Eigen::OuterStride<>(ldb));
  l.triangularView<Eigen::Lower>().solveInPlace(b);
  l.triangularView<Eigen::Lower>().transpose().solveInPlace(b);
}

// ---- AVX-512 ----

#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma")))

// GCC 12 warns inside its own AVX-512 headers (the undefined source of masked intrinsics).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

// Lanes of the 8-row vector starting `offset` rows into a run of `rows` rows.
inline __mmask8 Lanes(int rows, int offset) noexcept {
  const int left = rows - offset;
  return left >= 8 ? static_cast<__mmask8>(0xFF) : left <= 0 ? static_cast<__mmask8>(0)
                                                             : static_cast<__mmask8>((1u << left) - 1u);
}

// The offsets of eight consecutive columns of leading dimension ld, for a gather or scatter of
// one row across them.
HS_AVX512 inline __m512i ColumnOffsets(std::ptrdiff_t ld) noexcept {
  const long long l = ld;
  return _mm512_set_epi64(7 * l, 6 * l, 5 * l, 4 * l, 3 * l, 2 * l, l, 0);
}

// Column j's rows [i0, i0 + rows) (rows <= 8 V) less sum_k L[j,k] L[i0.., k] over the columns
// k < j to its left: the accumulators stay in registers while those columns stream past. The
// sum is taken in the order of the lane solve below (SolveLanesRow): four accumulators over the
// columns before the last (column k to k mod 4, the few left over to the first), added in
// pairs, then the last column's term. So every row's sum is the same whatever chunk it falls
// in, and the rows below a resumed factor's leading block, which are one lane solve
// (FactorAvx512), are bit for bit those of a whole factor.
template <int V>
HS_AVX512 void UpdateRows(double* A, int ld, int j, int i0, int rows) noexcept {
  double* cj = A + static_cast<std::ptrdiff_t>(j) * ld + i0;
  __mmask8 m[V];
  __m512d a0[V], a1[V], a2[V], a3[V];
  for (int q = 0; q < V; ++q) {
    m[q] = Lanes(rows, 8 * q);
    a0[q] = _mm512_maskz_loadu_pd(m[q], cj + 8 * q);
    a1[q] = _mm512_setzero_pd();
    a2[q] = _mm512_setzero_pd();
    a3[q] = _mm512_setzero_pd();
  }
  const int to = j - 1;  // the columns before the last
  int k = 0;
  for (; k + 4 <= to; k += 4) {
    const double* c0 = A + static_cast<std::ptrdiff_t>(k) * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const double* c3 = c2 + ld;
    const __m512d l0 = _mm512_set1_pd(c0[j]), l1 = _mm512_set1_pd(c1[j]), l2 = _mm512_set1_pd(c2[j]),
                  l3 = _mm512_set1_pd(c3[j]);
    for (int q = 0; q < V; ++q) {
      a0[q] = _mm512_fnmadd_pd(l0, _mm512_maskz_loadu_pd(m[q], c0 + i0 + 8 * q), a0[q]);
      a1[q] = _mm512_fnmadd_pd(l1, _mm512_maskz_loadu_pd(m[q], c1 + i0 + 8 * q), a1[q]);
      a2[q] = _mm512_fnmadd_pd(l2, _mm512_maskz_loadu_pd(m[q], c2 + i0 + 8 * q), a2[q]);
      a3[q] = _mm512_fnmadd_pd(l3, _mm512_maskz_loadu_pd(m[q], c3 + i0 + 8 * q), a3[q]);
    }
  }
  for (; k < to; ++k) {
    const double* ck = A + static_cast<std::ptrdiff_t>(k) * ld;
    const __m512d l = _mm512_set1_pd(ck[j]);
    for (int q = 0; q < V; ++q) a0[q] = _mm512_fnmadd_pd(l, _mm512_maskz_loadu_pd(m[q], ck + i0 + 8 * q), a0[q]);
  }
  for (int q = 0; q < V; ++q) {
    __m512d sum = _mm512_add_pd(_mm512_add_pd(a0[q], a1[q]), _mm512_add_pd(a2[q], a3[q]));
    if (to >= 0) {
      const double* cl = A + static_cast<std::ptrdiff_t>(to) * ld;
      sum = _mm512_fnmadd_pd(_mm512_set1_pd(cl[j]), _mm512_maskz_loadu_pd(m[q], cl + i0 + 8 * q), sum);
    }
    _mm512_mask_storeu_pd(cj + 8 * q, m[q], sum);
  }
}

// Column j's rows [from, n) less the columns to its left (UpdateRows, 32 rows at a time).
HS_AVX512 __attribute__((always_inline)) inline void UpdateColumn(double* A, int n, int ld, int j, int from) noexcept {
  for (int i0 = from; i0 < n; i0 += 32) {
    const int rows = std::min(32, n - i0);
    switch ((rows + 7) / 8) {
      case 1: UpdateRows<1>(A, ld, j, i0, rows); break;
      case 2: UpdateRows<2>(A, ld, j, i0, rows); break;
      case 3: UpdateRows<3>(A, ld, j, i0, rows); break;
      default: UpdateRows<4>(A, ld, j, i0, rows); break;
    }
  }
}

// Rows [begin, end) of a column times 1 / L[j,j].
HS_AVX512 __attribute__((always_inline)) inline void ScaleRows(double* c, int begin, int end, double ljj) noexcept {
  const __m512d inv = _mm512_set1_pd(1.0 / ljj);
  for (int i = begin; i < end; i += 8) {
    const __mmask8 m = Lanes(end - begin, i - begin);
    _mm512_mask_storeu_pd(c + i, m, _mm512_mul_pd(_mm512_maskz_loadu_pd(m, c + i), inv));
  }
}

// Up to 8 (or 16) right-hand sides at once, one per lane: B's columns are copied into rows of lanes
// (Y[i] holds row i of every column), so each substitution step is a broadcast of one entry of
// L times a whole row of Y, and a row of Y is complete long before it is read again (the column
// form read each unknown back right after its vector store, which is not forwarded). Four
// accumulators split the sum of each row over the rows solved before the last; the last one's
// term is added after, so that a row waits on the one before it for one FMA and the multiply
// by the diagonal's reciprocal (computed off that chain) only.
constexpr int kLanesMaxRows = 256;  // 32 kB of stack (16 lanes); larger systems take Eigen's solve

// Row `row` of Y (8 lanes) solved in place and returned: Y[row] less l[k stride] Y[k] over the
// rows k in [from, to), then less l[last stride] times `prev` (the row solved just before it, still
// in a register: `last` < 0 for none), times 1 / l[row stride] (the diagonal). The chain from one
// row to the next is that one FMA and the multiply; the store of a row is read back only by rows
// two or more later, long after it has left the store buffer.
HS_AVX512 inline __m512d SolveLanesRow(double* Y, const double* l, std::ptrdiff_t stride, int row, int from, int to,
                                       int last, __m512d prev) noexcept {
  __m512d a0 = _mm512_load_pd(Y + 8 * row), a1 = _mm512_setzero_pd(), a2 = _mm512_setzero_pd(),
          a3 = _mm512_setzero_pd();
  int k = from;
  for (; k + 4 <= to; k += 4) {
    a0 = _mm512_fnmadd_pd(_mm512_set1_pd(l[k * stride]), _mm512_load_pd(Y + 8 * k), a0);
    a1 = _mm512_fnmadd_pd(_mm512_set1_pd(l[(k + 1) * stride]), _mm512_load_pd(Y + 8 * (k + 1)), a1);
    a2 = _mm512_fnmadd_pd(_mm512_set1_pd(l[(k + 2) * stride]), _mm512_load_pd(Y + 8 * (k + 2)), a2);
    a3 = _mm512_fnmadd_pd(_mm512_set1_pd(l[(k + 3) * stride]), _mm512_load_pd(Y + 8 * (k + 3)), a3);
  }
  for (; k < to; ++k) a0 = _mm512_fnmadd_pd(_mm512_set1_pd(l[k * stride]), _mm512_load_pd(Y + 8 * k), a0);
  __m512d sum = _mm512_add_pd(_mm512_add_pd(a0, a1), _mm512_add_pd(a2, a3));
  if (last >= 0) sum = _mm512_fnmadd_pd(_mm512_set1_pd(l[last * stride]), prev, sum);
  const __m512d y = _mm512_mul_pd(sum, _mm512_set1_pd(1.0 / l[row * stride]));
  _mm512_store_pd(Y + 8 * row, y);
  return y;
}

// Columns [0, p0) are already factored down to row p0 (see ResumeFactorSpd): only their rows
// from p0 on are computed, each from the same sums in the same order as a whole factor would.
// Those rows are L21 = A21 L11^-T, a forward substitution through L11 with the rows as right-hand
// sides: eight rows a lane pass (SolveLanesRow, the order UpdateRows sums in), instead of an
// update and a division per column of the leading block.
HS_AVX512 bool FactorAvx512(double* A, int n, int ld, int p0 = 0) noexcept {
  if (p0 > 0 && p0 <= kLanesMaxRows) {
    alignas(64) double Y[kLanesMaxRows * 8];
    for (int i0 = p0; i0 < n; i0 += 8) {
      const __mmask8 m = Lanes(n - i0, 0);
      for (int j = 0; j < p0; ++j) {
        _mm512_store_pd(Y + 8 * j, _mm512_maskz_loadu_pd(m, A + static_cast<std::ptrdiff_t>(j) * ld + i0));
      }
      __m512d prev = _mm512_setzero_pd();
      for (int j = 0; j < p0; ++j) prev = SolveLanesRow(Y, A + j, ld, j, 0, j - 1, j - 1, prev);
      for (int j = 0; j < p0; ++j) {
        _mm512_mask_storeu_pd(A + static_cast<std::ptrdiff_t>(j) * ld + i0, m, _mm512_load_pd(Y + 8 * j));
      }
    }
  }
  for (int j = 0; j < n; ++j) {
    double* cj = A + static_cast<std::ptrdiff_t>(j) * ld;
    if (j < p0) {
      if (p0 > kLanesMaxRows) {
        UpdateColumn(A, n, ld, j, p0);
        ScaleRows(cj, p0, n, cj[j]);
      }
      continue;
    }
    UpdateColumn(A, n, ld, j, j);
    const double d = cj[j];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double s = std::sqrt(d);
    cj[j] = s;
    ScaleRows(cj, j + 1, n, s);
  }
  return true;
}

// The same over 16 lanes (two vectors a row): each entry of L is broadcast once for both, and
// the two halves' chains run side by side. For 9-16 right-hand sides: one pass instead of two.
HS_AVX512 inline void SolveLanesRow16(double* Y, const double* l, std::ptrdiff_t stride, int row, int from, int to,
                                      int last, __m512d& prev0, __m512d& prev1) noexcept {
  __m512d a0 = _mm512_load_pd(Y + 16 * row), b0 = _mm512_load_pd(Y + 16 * row + 8);
  __m512d a1 = _mm512_setzero_pd(), b1 = _mm512_setzero_pd(), a2 = _mm512_setzero_pd(), b2 = _mm512_setzero_pd(),
          a3 = _mm512_setzero_pd(), b3 = _mm512_setzero_pd();
  int k = from;
  for (; k + 4 <= to; k += 4) {
    const __m512d l0 = _mm512_set1_pd(l[k * stride]), l1 = _mm512_set1_pd(l[(k + 1) * stride]),
                  l2 = _mm512_set1_pd(l[(k + 2) * stride]), l3 = _mm512_set1_pd(l[(k + 3) * stride]);
    a0 = _mm512_fnmadd_pd(l0, _mm512_load_pd(Y + 16 * k), a0);
    b0 = _mm512_fnmadd_pd(l0, _mm512_load_pd(Y + 16 * k + 8), b0);
    a1 = _mm512_fnmadd_pd(l1, _mm512_load_pd(Y + 16 * (k + 1)), a1);
    b1 = _mm512_fnmadd_pd(l1, _mm512_load_pd(Y + 16 * (k + 1) + 8), b1);
    a2 = _mm512_fnmadd_pd(l2, _mm512_load_pd(Y + 16 * (k + 2)), a2);
    b2 = _mm512_fnmadd_pd(l2, _mm512_load_pd(Y + 16 * (k + 2) + 8), b2);
    a3 = _mm512_fnmadd_pd(l3, _mm512_load_pd(Y + 16 * (k + 3)), a3);
    b3 = _mm512_fnmadd_pd(l3, _mm512_load_pd(Y + 16 * (k + 3) + 8), b3);
  }
  for (; k < to; ++k) {
    const __m512d lk = _mm512_set1_pd(l[k * stride]);
    a0 = _mm512_fnmadd_pd(lk, _mm512_load_pd(Y + 16 * k), a0);
    b0 = _mm512_fnmadd_pd(lk, _mm512_load_pd(Y + 16 * k + 8), b0);
  }
  __m512d sa = _mm512_add_pd(_mm512_add_pd(a0, a1), _mm512_add_pd(a2, a3));
  __m512d sb = _mm512_add_pd(_mm512_add_pd(b0, b1), _mm512_add_pd(b2, b3));
  if (last >= 0) {
    const __m512d ll = _mm512_set1_pd(l[last * stride]);
    sa = _mm512_fnmadd_pd(ll, prev0, sa);
    sb = _mm512_fnmadd_pd(ll, prev1, sb);
  }
  const __m512d inv = _mm512_set1_pd(1.0 / l[row * stride]);
  prev0 = _mm512_mul_pd(sa, inv);
  prev1 = _mm512_mul_pd(sb, inv);
  _mm512_store_pd(Y + 16 * row, prev0);
  _mm512_store_pd(Y + 16 * row + 8, prev1);
}

HS_AVX512 void SolveLanesAvx512(const double* L, int n, int ld, double* B, int nrhs, int ldb) noexcept {
  alignas(64) double Y[kLanesMaxRows * 16];
  for (int c0 = 0; c0 < nrhs;) {
    const int left = nrhs - c0;
    const int lanes = left > 8 ? 16 : 8;
    const int w = std::min(lanes, left);
    // Row i of the pass's columns: a gather per 8 lanes (lane c reads column c0 + c), zeros in
    // the lanes past the last column; and a scatter back below.
    const __m512i idx = ColumnOffsets(ldb);
    const __mmask8 m0 = Lanes(w, 0), m1 = Lanes(w, 8);
    double* b0 = B + static_cast<std::ptrdiff_t>(c0) * ldb;
    double* b1 = lanes == 16 ? b0 + static_cast<std::ptrdiff_t>(8) * ldb : b0;  // columns c0 + 8 on
    for (int i = 0; i < n; ++i) {
      double* y = Y + lanes * i;
      _mm512_store_pd(y, _mm512_mask_i64gather_pd(_mm512_setzero_pd(), m0, idx, b0 + i, 8));
      if (lanes == 16) _mm512_store_pd(y + 8, _mm512_mask_i64gather_pd(_mm512_setzero_pd(), m1, idx, b1 + i, 8));
    }
    __m512d prev = _mm512_setzero_pd(), prev1 = _mm512_setzero_pd();
    if (lanes == 8) {
      // L y = b, row by row: row i of L is L[i + k ld].
      for (int i = 0; i < n; ++i) prev = SolveLanesRow(Y, L + i, ld, i, 0, i - 1, i - 1, prev);
      // L^T x = y, from the last row up: column j of L below the diagonal, contiguous.
      prev = _mm512_setzero_pd();
      for (int j = n - 1; j >= 0; --j) {
        prev = SolveLanesRow(Y, L + static_cast<std::ptrdiff_t>(j) * ld, 1, j, j + 2, n, j + 1 < n ? j + 1 : -1, prev);
      }
    } else {
      for (int i = 0; i < n; ++i) SolveLanesRow16(Y, L + i, ld, i, 0, i - 1, i - 1, prev, prev1);
      for (int j = n - 1; j >= 0; --j) {
        SolveLanesRow16(Y, L + static_cast<std::ptrdiff_t>(j) * ld, 1, j, j + 2, n, j + 1 < n ? j + 1 : -1, prev,
                        prev1);
      }
    }
    for (int i = 0; i < n; ++i) {
      const double* y = Y + lanes * i;
      _mm512_mask_i64scatter_pd(b0 + i, m0, idx, _mm512_load_pd(y), 8);
      if (lanes == 16) _mm512_mask_i64scatter_pd(b1 + i, m1, idx, _mm512_load_pd(y + 8), 8);
    }
    c0 += w;
  }
}

HS_AVX512 void WeightedRowSumsAvx512(const double* Z, std::ptrdiff_t ldz, int ncols, const std::int32_t* rows,
                                     const double* w0, const double* w1, int count, double* s0, double* s1) noexcept {
  const __m512i idx = ColumnOffsets(ldz);
  const __mmask8 m0 = Lanes(ncols, 0), m1 = Lanes(ncols, 8);
  const double* z1 = ncols > 8 ? Z + 8 * ldz : Z;  // columns 8 on (none: its lanes are masked off)
  __m512d a00 = _mm512_setzero_pd(), a01 = _mm512_setzero_pd(), a10 = _mm512_setzero_pd(), a11 = _mm512_setzero_pd();
  for (int m = 0; m < count; ++m) {
    const __m512d x0 = _mm512_mask_i64gather_pd(_mm512_setzero_pd(), m0, idx, Z + rows[m], 8);
    const __m512d x1 = _mm512_mask_i64gather_pd(_mm512_setzero_pd(), m1, idx, z1 + rows[m], 8);
    const __m512d u = _mm512_set1_pd(w0[m]), v = _mm512_set1_pd(w1[m]);
    a00 = _mm512_fmadd_pd(u, x0, a00);
    a01 = _mm512_fmadd_pd(u, x1, a01);
    a10 = _mm512_fmadd_pd(v, x0, a10);
    a11 = _mm512_fmadd_pd(v, x1, a11);
  }
  _mm512_mask_storeu_pd(s0, m0, a00);
  _mm512_mask_storeu_pd(s0 + 8, m1, a01);
  _mm512_mask_storeu_pd(s1, m0, a10);
  _mm512_mask_storeu_pd(s1 + 8, m1, a11);
}

#pragma GCC diagnostic pop

}  // namespace

bool FactorSpd(double* A, int n, int ld, Isa isa) noexcept {
  if (n <= 0) return true;
  // The AVX-512 kernel checks each pivot before its square root; every entry of L reaches a
  // later pivot, so a non-finite one fails there too.
  return isa == Isa::kAvx512 ? FactorAvx512(A, n, ld) : FactorEigen(A, n, ld);
}

bool ResumeFactorSpd(double* A, int n, int ld, int p0, Isa isa) noexcept {
  if (isa != Isa::kAvx512 || p0 < 0 || p0 > n) return false;
  return FactorAvx512(A, n, ld, p0);
}

void SolveFactoredSpd(const double* L, int n, int ld, double* B, int nrhs, int ldb, Isa isa) noexcept {
  if (n <= 0 || nrhs <= 0) return;
  // One right-hand side too: seven idle lanes, as fast as Eigen's vector substitution (1.2 us
  // at 45 unknowns) and faster than its matrix solve (1.7), which a mapped column takes.
  if (isa == Isa::kAvx512 && n <= kLanesMaxRows) {
    SolveLanesAvx512(L, n, ld, B, nrhs, ldb);
  } else {
    SolveEigen(L, n, ld, B, nrhs, ldb);
  }
}

void WeightedRowSums(const double* Z, std::ptrdiff_t ldz, int ncols, const std::int32_t* rows, const double* w0,
                     const double* w1, int count, double* s0, double* s1, Isa isa) noexcept {
  if (isa == Isa::kAvx512 && ncols <= 16) {
    WeightedRowSumsAvx512(Z, ldz, ncols, rows, w0, w1, count, s0, s1);
    return;
  }
  std::fill(s0, s0 + ncols, 0.0);
  std::fill(s1, s1 + ncols, 0.0);
  for (int m = 0; m < count; ++m) {
    const double* v = Z + rows[m];
    for (int c = 0; c < ncols; ++c) {
      const double x = v[c * ldz];
      s0[c] += w0[m] * x;
      s1[c] += w1[m] * x;
    }
  }
}

}  // namespace handshare::fem::detail
