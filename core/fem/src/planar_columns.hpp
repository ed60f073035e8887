#pragma once
// Internal: columns of 3x3 blocks stored "planar" for vertical SIMD, and the kernels that sum
// a few of them (the surface field u = sum_j X_{:,k_j} x_j). Real-time parts: noexcept, no
// allocation.
//
// Layout of one column (N blocks X_nk): chunks of 16 nodes; inside a chunk, plane p = 3 c + r
// holds entry (r, c) of the 16 blocks, one lane per node: scalar index 144 q + 16 p + l for node
// 16 q + l. A chunk of one column is 9 aligned 16-lane vectors, so u_r of 16 nodes is 3 vertical
// FMAs per column and input component, with no shuffles; padding lanes are zero.
// float16 columns carry one float scale per (column, chunk): X = half * scale, so every chunk
// uses the full 11-bit mantissa of its largest entry.
// int16 columns (fixed point) carry one float scale per (column, chunk), X = q * scale with
// |q| <= 32767 (the chunk's largest entry maps to 32767), and pair the planes for integer dot products
// (vpdpwssd: 16 lanes of a0 b0 + a1 b1 per instruction): in a chunk, the pair plane of row r
// holds (X(r, 0), X(r, 1)) of lane l at 2 l, 2 l + 1 (3 x 32 scalars) and the single plane of row
// r holds X(r, 2) of lane l at l (3 x 16 scalars), the same 144 scalars. Even chunks store the
// pair planes first, odd chunks the single planes first, and a column's length is rounded up to
// 64 bytes, so every 64-byte pair plane is aligned (a chunk is 288 bytes, 4.5 cache lines).

#include <cstdint>
#include <functional>
#include <span>

#include <Eigen/Core>

#include "handshare/fem/aligned_buffer.hpp"
#include "handshare/fem/surface_field.hpp"

namespace handshare::fem::detail {

constexpr int kChunkNodes = 16;
constexpr int kChunkScalars = 9 * kChunkNodes;
/// Offset of entry (r, c) of lane l of chunk q in an int16 column (layout above).
constexpr std::int64_t Int16Offset(std::int64_t q, int r, int c, int l) noexcept {
  const std::int64_t pairs = (q & 1) ? 48 : 0, singles = (q & 1) ? 0 : 96;
  return q * kChunkScalars + (c < 2 ? pairs + 32 * r + 2 * l + c : singles + 16 * r + l);
}

inline std::int64_t NumChunks(std::int32_t nodes) noexcept { return (nodes + kChunkNodes - 1) / kChunkNodes; }

/// Instruction sets the kernels are compiled for, picked at run time.
enum class Isa : std::uint8_t { kPortable, kAvx2, kAvx512 };
/// The best one this CPU runs (AVX-512F/VL; AVX2 + FMA + F16C; else portable).
Isa BestIsa() noexcept;
/// True if this CPU has AVX-512 VNNI (the int16 column kernel; without it AVX2 runs).
bool HasAvx512Vnni() noexcept;
const char* IsaName(Isa isa) noexcept;

enum class PlanarType : std::uint8_t { kFloat64, kFloat32, kFloat16, kInt16 };

std::uint16_t FloatToHalf(float f) noexcept;  // round to nearest even
float HalfToFloat(std::uint16_t h) noexcept;

class PlanarColumns {
 public:
  PlanarColumns() = default;
  /// Offline: fills `cols` columns of `rows` blocks from block(n, k).
  void Build(std::int32_t rows, std::int32_t cols, PlanarType type,
             const std::function<Eigen::Matrix3d(std::int32_t n, std::int32_t k)>& block);

  std::int32_t rows() const noexcept { return rows_; }
  std::int32_t cols() const noexcept { return cols_; }
  PlanarType type() const noexcept { return type_; }
  bool empty() const noexcept { return cols_ == 0; }
  /// Scalars from one column to the next (a chunk multiple, padded to 64 bytes for int16).
  std::int64_t column_scalars() const noexcept { return stride_; }
  /// The kernel SumColumns runs when asked for `requested`: portable for float64, AVX2 for int16
  /// on an AVX-512 CPU without VNNI, else `requested`.
  Isa KernelIsa(Isa requested) const noexcept;
  /// Block (n, k) as stored (rounded to the storage type).
  Eigen::Matrix3d Get(std::int32_t n, std::int32_t k) const noexcept;
  std::size_t storage_bytes() const noexcept {
    return f64_.size() * 8 + f32_.size() * 4 + f16_.size() * 2 + i16_.size() * 2 + scale_.size() * 4;
  }

  /// out[n] = sum_j X_{n, k[j]} x[j] for every row n (out.size() == rows()). Columns out of range
  /// are skipped. Accumulates in float (double for float64 storage). int16: each load is rounded
  /// to integers g_c = round(x_c / step_j), step_j = max_c |x_jc| / 21845 (so one column's int32
  /// sums cannot overflow), and a column's integer sums enter the float sums times
  /// scale(column, chunk) * step_j. Kernels: AVX-512 VNNI, AVX2, portable (the same integer sums
  /// and float operations: equal results).
  void SumColumns(std::span<const std::int32_t> k, std::span<const Eigen::Vector3d> x,
                  Eigen::Vector3d* out, Isa isa) const noexcept;
  /// Same with (slot, force) pairs.
  void SumColumns(std::span<const NodeLoad> loads, Eigen::Vector3d* out, Isa isa) const noexcept;

 private:
  using Getter = std::int32_t (*)(const void* ctx, std::size_t i, const Eigen::Vector3d** x);
  void Sum(std::size_t count, Getter get, const void* ctx, Eigen::Vector3d* out, Isa isa) const noexcept;

  std::int32_t rows_ = 0, cols_ = 0;
  PlanarType type_ = PlanarType::kFloat32;
  std::int64_t stride_ = 0;
  AlignedVector<double> f64_;
  AlignedVector<float> f32_;
  AlignedVector<std::uint16_t> f16_;
  AlignedVector<std::int16_t> i16_;
  AlignedVector<float> scale_;  // float16: per (column, chunk); int16: per column
};

}  // namespace handshare::fem::detail
