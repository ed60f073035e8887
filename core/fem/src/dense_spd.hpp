#pragma once
// Internal: the dense Cholesky factor and solves of the contact solver's held system (up to
// 3 x max_contacts unknowns; 40-60 for five fingertips' patches held in 3-D with friction). A
// friction step factors it about four times and solves it about nine (docs/fem.md, "Friction").
// Eigen's blocked LLT spends most of its instructions on packing and blocking at these sizes;
// the AVX-512 factor here is left-looking over columns (each column's rows in up to four
// 8-double registers while the columns to its left stream past: every update an FMA on
// contiguous memory): haptic_bench's deformable_2k_friction went from 64 to 54 us p50 and from
// 166 to 141 us p99 (docs/haptic_rendering.md). The solves take the right-hand sides one per
// lane (the slip directions of the slipping patches, or one column): 2.0 against Eigen's 6.9 us
// for 54 unknowns and 8 columns. A column-oriented AVX-512 substitution was 2.5 times slower
// than Eigen's (each unknown stored and read back by the next vector load, which waits for the
// store: the processor does not forward it), and one blocked by 8 rows with the unknowns kept
// scalar was no faster than Eigen's panels.
// Real-time safe: noexcept, no allocation.

#include "planar_columns.hpp"  // Isa

namespace handshare::fem::detail {

/// A = L L^T in the lower triangle of A's leading n x n block (column-major, leading dimension
/// ld; the lower triangle is read and overwritten with L, the upper triangle is left as it is).
/// False unless A is numerically positive definite with a finite factor.
bool FactorSpd(double* A, int n, int ld, Isa isa) noexcept;

/// FactorSpd of a matrix whose leading p0 x p0 block is that of one factored before: A's columns
/// [0, p0) hold that factor in their rows [0, p0), everything else in the lower triangle holds
/// the new matrix. Fills in the rest of L: bit for bit what FactorSpd would make of the whole
/// matrix (the left-looking order computes every entry from the same sums either way), at the
/// cost of the rows from p0 on. Held-set pivots that change only the last rows refactor this
/// way. AVX-512 only: false without it (A untouched; the caller assembles and factors it whole),
/// or, as FactorSpd, when the matrix is not numerically positive definite.
bool ResumeFactorSpd(double* A, int n, int ld, int p0, Isa isa) noexcept;

/// B = (L L^T)^-1 B for the nrhs columns of B (leading dimension ldb), L from FactorSpd. With
/// AVX-512, the columns are solved eight at a time, one per lane.
void SolveFactoredSpd(const double* L, int n, int ld, double* B, int nrhs, int ldb, Isa isa) noexcept;

/// s0[c] = sum_m w0[m] Z[c ldz + rows[m]] and s1 likewise with w1, for the columns c < ncols of
/// Z (column-major, leading dimension ldz) and the count rows listed: a weighted sum of a few
/// rows of every column (the friction solve's cone equations). With AVX-512 and up to 16
/// columns, a row of the columns is gathered at once and the sums stay in registers.
void WeightedRowSums(const double* Z, std::ptrdiff_t ldz, int ncols, const std::int32_t* rows, const double* w0,
                     const double* w1, int count, double* s0, double* s1, Isa isa) noexcept;

}  // namespace handshare::fem::detail
