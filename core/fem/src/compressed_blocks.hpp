#pragma once
// Internal: the compressed compliance, a hierarchical matrix (H-matrix). The compliance nodes are
// ordered by a k-d tree (spatially coherent clusters; leaves of at most leaf_nodes nodes). The
// upper triangle is partitioned into blocks of cluster pairs (s, t): the diagonal recurses to the
// leaves; an off-diagonal pair that is admissible, min(diam s, diam t) <= eta dist(s, t) on the
// bounding boxes (or any off-diagonal pair with weak_admissibility), and has at most
// max_block_entries entries (larger ones are split, not streamed) is compressed as one U V^T:
// adaptive cross approximation with full pivoting on the explicit block down to 0.3 tolerance,
// then recompressed (QR of the factors, SVD of the small core) to the smallest rank whose
// explicit residual ||A - U V^T||_F <= tolerance ||A||_F, with U and V rounded as stored (float32,
// or float16 with a float32 scale per rank when factor_precision is kFloat16; computed, not
// estimated). It is kept where it stores fewer floats than dense and than its split (which is
// computed first, recursively); otherwise the split stays (both clusters, or the one that is not
// a leaf). A pair of leaves is always tried on its own (as the flat version did) and else stored
// dense. So ||C - C~||_F <= tolerance ||C||_F overall, blocks near the diagonal exact to float32,
// far ones smooth (the Green's function decays) and compressed.
//
// For O(1) lookup the kernels still see one tile per leaf pair (I <= J, C_JI = C_IJ^T): a diagonal
// tile (I == J, symmetric: its upper triangle packed by columns, 3 m (3 m + 1) / 2 floats), a dense
// tile (3 m x 3 n column-major, leading dimension 3 m) or a view into a block's factors: leaf I's
// rows of U start at offset_u with leading dimension ld_u (the block's row count), leaf J's rows
// of V at offset_v with ld_v. Factors are stored once per block.
// Block() and Apply() are real-time safe: noexcept, no allocation (Apply uses caller scratch).

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/aligned_buffer.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/surface_field.hpp"
#include "planar_columns.hpp"

namespace handshare::fem::detail {

// Tile kinds besides low rank (rank >= 0).
inline constexpr std::int32_t kDenseTile = -1;      // 3 m x 3 n column-major, leading dimension ld_u = 3 m
inline constexpr std::int32_t kSymmetricTile = -2;  // diagonal tile (I == J): upper triangle packed by columns

// Entry (i, j) of a diagonal tile stored as its upper triangle packed by columns.
inline std::int64_t SymmetricIndex(std::int64_t i, std::int64_t j) noexcept {
  return i <= j ? j * (j + 1) / 2 + i : i * (i + 1) / 2 + j;
}

// Offsets in floats into the factor data (int32: the build checks that the data fits).
struct CompressedTile {
  std::int32_t offset_u = 0;  // dense: the tile (see kDenseTile, kSymmetricTile)
  std::int32_t offset_v = 0;
  std::int32_t ld_u = 0, ld_v = 0;  // symmetric: ld_u = 3 m, the tile's order
  std::int32_t rank = kDenseTile;  // >= 0: U rows at offset_u (ld_u), V rows at offset_v (ld_v)
  std::int32_t scales = -1;  // low rank in float16: offsets into the halves, rank float32 scales at
                             // data[scales] (C = U diag(scales) V^T); -1: float32 factors in data
};

// One block of the partition (for inspection and tests): rows [row_begin, row_end) and columns
// [col_begin, col_end) in cluster order (row_end <= col_begin or the same leaf), rank -1: dense.
struct CompressedBlockInfo {
  std::int32_t row_begin = 0, row_end = 0, col_begin = 0, col_end = 0, rank = -1;
};

// Most rank of a kept block (the Apply kernels keep one weight per rank on the stack).
inline constexpr int kMaxBlockRank = 256;

// Plain view of the structure, for the kernels.
struct CompressedView {
  const std::int32_t* pos;
  const std::int32_t* leaf_of_pos;
  const std::int32_t* leaf_start;
  const std::int32_t* slot_of_pos;
  std::int32_t num_nodes, num_leaves;
  const CompressedTile* tiles;
  const float* data;
  const std::uint16_t* half;
};

class CompressedBlocks {
 public:
  /// Offline. positions_m[s] = position of slot s; block(n, k) = exact C_nk.
  static CompressedBlocks Build(std::span<const Eigen::Vector3d> positions_m, const Compliance& exact,
                                const CompressionOptions& options, CompressionStats* stats);

  std::int32_t num_nodes() const noexcept { return static_cast<std::int32_t>(pos_.size()); }
  Eigen::Matrix3d Block(std::int32_t n, std::int32_t k) const noexcept;
  /// out[n] = sum_j C_{n, slot_j} f_j (slot order); scratch: 3 N + 64 floats.
  void Apply(std::span<const NodeLoad> loads, Eigen::Vector3d* out, float* scratch, Isa isa) const noexcept;
  std::size_t storage_bytes() const noexcept;
  std::size_t scratch_floats() const noexcept { return 3 * pos_.size() + 64; }
  /// The partition of the upper triangle, and the slot of each cluster-order position.
  std::span<const CompressedBlockInfo> blocks() const noexcept { return blocks_; }
  std::span<const std::int32_t> slot_of_pos() const noexcept { return slot_of_pos_; }

 private:
  using Tile = CompressedTile;
  CompressedView View() const noexcept;
  Eigen::Matrix3d HalfBlock(const Tile& tile, std::int64_t a, std::int64_t b) const noexcept;
  std::int32_t num_leaves_() const noexcept { return static_cast<std::int32_t>(leaf_start_.size()) - 1; }

  std::vector<std::int32_t> slot_of_pos_;  // cluster order -> slot
  std::vector<std::int32_t> pos_;          // slot -> cluster order
  std::vector<std::int32_t> leaf_of_pos_;
  std::vector<std::int32_t> leaf_start_;   // num_leaves + 1
  std::vector<Tile> tiles_;                // tile (I, J), I <= J, at Compliance::PackedIndex(I, J)
  std::vector<CompressedBlockInfo> blocks_;
  AlignedVector<float> data_;          // dense tiles, float32 factors, scales of float16 factors
  std::vector<std::uint16_t> half_;    // float16 factors
};

}  // namespace handshare::fem::detail
