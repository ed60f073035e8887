#pragma once
// Internal: the memory-bound kernels on the packed compliance blocks, for both precisions.
// Real-time safe: noexcept, no allocation.

#include <cstdint>
#include <span>
#include <utility>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"

namespace handshare::fem::detail {

// out (column-major, leading dimension ld) = the full symmetric 3u x 3u matrix C_cc of `slots`.
template <class S>
void GatherBlocksT(const S* data, const std::int32_t* slots, std::int32_t u, double* out,
                   int ld) noexcept {
  for (std::int32_t j = 0; j < u; ++j) {
    for (std::int32_t i = 0; i <= j; ++i) {
      std::int32_t a = slots[i], b = slots[j];
      const bool transpose = a > b;  // stored is C_{min,max}
      if (transpose) std::swap(a, b);
      const S* blk = data + 9 * Compliance::PackedIndex(a, b);
      double* oij = out + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i;  // block (i, j)
      double* oji = out + static_cast<std::ptrdiff_t>(3 * i) * ld + 3 * j;  // block (j, i)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) {
          const double v = transpose ? static_cast<double>(blk[3 * r + c])
                                     : static_cast<double>(blk[3 * c + r]);
          oij[c * ld + r] = v;   // C_ij(r, c)
          oji[r * ld + c] = v;   // C_ji(c, r) = C_ij(r, c)
        }
    }
  }
}

inline void GatherBlocks(const Compliance& C, const std::int32_t* slots, std::int32_t u,
                         double* out, int ld) noexcept {
  if (C.precision() == Precision::kFloat32) {
    GatherBlocksT(C.data_f32(), slots, u, out, ld);
  } else {
    GatherBlocksT(C.data_f64(), slots, u, out, ld);
  }
}

// out[n] = sum_j C_{n, slots[j]} f[j] over the active j, for every slot n.
template <class S>
void ApplyColumnsT(const S* data, std::int32_t N, const std::int32_t* slots,
                   const Eigen::Vector3d* f, const std::uint8_t* active, std::int32_t u,
                   Eigen::Vector3d* out) noexcept {
  for (std::int32_t n = 0; n < N; ++n) out[n].setZero();
  for (std::int32_t j = 0; j < u; ++j) {
    if (!active[j]) continue;
    const std::int32_t k = slots[j];
    const double f0 = f[j][0], f1 = f[j][1], f2 = f[j][2];
    // n <= k: blocks C_nk are contiguous in packed column k.
    const S* blk = data + 9 * Compliance::PackedIndex(0, k);
    for (std::int32_t n = 0; n <= k; ++n, blk += 9) {
      double* o = out[n].data();
      o[0] += blk[0] * f0 + blk[3] * f1 + blk[6] * f2;
      o[1] += blk[1] * f0 + blk[4] * f1 + blk[7] * f2;
      o[2] += blk[2] * f0 + blk[5] * f1 + blk[8] * f2;
    }
    // n > k: C_nk = (stored C_kn)^T, found in packed column n at row k.
    for (std::int32_t n = k + 1; n < N; ++n) {
      const S* b = data + 9 * Compliance::PackedIndex(k, n);
      double* o = out[n].data();
      o[0] += b[0] * f0 + b[1] * f1 + b[2] * f2;
      o[1] += b[3] * f0 + b[4] * f1 + b[5] * f2;
      o[2] += b[6] * f0 + b[7] * f1 + b[8] * f2;
    }
  }
}

inline void ApplyColumns(const Compliance& C, const std::int32_t* slots, const Eigen::Vector3d* f,
                         const std::uint8_t* active, std::int32_t u,
                         std::span<Eigen::Vector3d> out) noexcept {
  if (C.precision() == Precision::kFloat32) {
    ApplyColumnsT(C.data_f32(), C.num_nodes(), slots, f, active, u, out.data());
  } else {
    ApplyColumnsT(C.data_f64(), C.num_nodes(), slots, f, active, u, out.data());
  }
}

}  // namespace handshare::fem::detail
