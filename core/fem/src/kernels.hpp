#pragma once
// Internal: the memory-bound kernels on the packed compliance blocks, for both precisions.
// Real-time safe: noexcept, no allocation.

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"

namespace handshare::fem::detail {

// out (column-major, leading dimension ld) = the full symmetric 3u x 3u matrix C_cc of `slots`.
template <class S>
void GatherBlocksT(const S* data, const std::int32_t* slots, std::int32_t u, double* out,
                   int ld) noexcept {
  for (std::int32_t j = 0; j < u; ++j) {
    for (std::int32_t i = 0; i <= j; ++i) {
      const std::int32_t a = slots[i], b = slots[j];
      double* oij = out + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i;  // block (i, j)
      double* oji = out + static_cast<std::ptrdiff_t>(3 * i) * ld + 3 * j;  // block (j, i)
      // Stored is C_{min,max}, column-major: C_ij(r, c) = blk[3 c + r], or blk[3 r + c] when
      // a > b (the transpose). Two straight-line copies, so the branch is taken once a block.
      const S* blk = data + 9 * Compliance::PackedIndex(std::min(a, b), std::max(a, b));
      // (GCC -O2 does not unroll these 3- and 9-trip loops by itself; unrolled they are plain
      // moves.)
      double v[9];  // C_ij column-major
      if (a <= b) {
#pragma GCC unroll 9
        for (int e = 0; e < 9; ++e) v[e] = static_cast<double>(blk[e]);
      } else {
#pragma GCC unroll 3
        for (int c = 0; c < 3; ++c)
#pragma GCC unroll 3
          for (int r = 0; r < 3; ++r) v[3 * c + r] = static_cast<double>(blk[3 * r + c]);
      }
#pragma GCC unroll 3
      for (int c = 0; c < 3; ++c)
#pragma GCC unroll 3
        for (int r = 0; r < 3; ++r) {
          oij[c * ld + r] = v[3 * c + r];  // C_ij(r, c)
          oji[r * ld + c] = v[3 * c + r];  // C_ji(c, r) = C_ij(r, c)
        }
    }
  }
}

inline void GatherBlocks(const Compliance& C, const std::int32_t* slots, std::int32_t u,
                         double* out, int ld) noexcept {
  if (C.storage() == ComplianceStorage::kCompressed) {
    // Block by block: dense for nodes of one cluster, U V^T rows for far pairs.
    for (std::int32_t j = 0; j < u; ++j)
      for (std::int32_t i = 0; i <= j; ++i) {
        const Eigen::Matrix3d B = C.Block(slots[i], slots[j]);
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) {
            out[static_cast<std::ptrdiff_t>(3 * j + c) * ld + 3 * i + r] = B(r, c);
            out[static_cast<std::ptrdiff_t>(3 * i + r) * ld + 3 * j + c] = B(r, c);
          }
      }
    return;
  }
  if (C.precision() == Precision::kFloat32) {
    GatherBlocksT(C.data_f32(), slots, u, out, ld);
  } else {
    GatherBlocksT(C.data_f64(), slots, u, out, ld);
  }
}

// The first 64-byte aligned float of v (scratch vectors carry 16 floats of slack for it).
float* Align64(std::vector<float>& v) noexcept;

}  // namespace handshare::fem::detail
