#pragma once
// Internal: the compressed compliance (block low-rank). The compliance nodes are ordered by a
// k-d tree (spatially coherent clusters of at most leaf_nodes nodes); the matrix is cut into
// tiles of cluster pairs (I <= J, symmetric: C_JI = C_IJ^T). Diagonal tiles are dense; every
// off-diagonal tile is compressed to U V^T by adaptive cross approximation with full pivoting
// on the exact tile, stopping when the residual ||A - U V^T||_F <= tolerance ||A||_F (checked
// on the explicit residual, not estimated), and kept low-rank only where that saves memory
// (r (m + n) < m n), else dense. Neighbouring clusters stay dense by that rule; far ones are
// smooth (the Green's function decays) and compress.
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

struct CompressedTile {
  std::int64_t offset = 0;
  std::int32_t rank = -1;  // -1: dense (3 m x 3 n column-major), else U (3m x r) then V (3n x r)
};

// Plain view of the structure, for the kernels.
struct CompressedView {
  const std::int32_t* pos;
  const std::int32_t* leaf_of_pos;
  const std::int32_t* leaf_start;
  const std::int32_t* slot_of_pos;
  std::int32_t num_nodes, num_leaves;
  const CompressedTile* tiles;
  const float* data;
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

 private:
  using Tile = CompressedTile;
  CompressedView View() const noexcept;
  static std::int64_t TileIndex(std::int32_t I, std::int32_t J) noexcept {
    return static_cast<std::int64_t>(J) * (J + 1) / 2 + I;
  }
  std::int32_t num_leaves_() const noexcept { return static_cast<std::int32_t>(leaf_start_.size()) - 1; }

  std::vector<std::int32_t> slot_of_pos_;  // cluster order -> slot
  std::vector<std::int32_t> pos_;          // slot -> cluster order
  std::vector<std::int32_t> leaf_of_pos_;
  std::vector<std::int32_t> leaf_start_;   // num_leaves + 1
  std::vector<Tile> tiles_;
  AlignedVector<float> data_;
};

}  // namespace handshare::fem::detail
