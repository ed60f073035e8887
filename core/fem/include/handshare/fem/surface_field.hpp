#pragma once
/// @file
/// The surface displacement field of a set of nodal loads, u_n = sum_j C_{n,k_j} f_j for every
/// compliance node n (the graphics-rate half of the elementary displacement method). Separate
/// from ContactSolver so that the haptic thread can hand its loads (a trivially copyable list)
/// to a graphics or bridge thread that owns a SurfaceField. Evaluate() is noexcept and does not
/// allocate; its cost is O(N m) and memory-bound. Layouts (SurfaceFieldOptions):
///  - kCompliance (default): reads the compliance as stored. Packed: m columns of C, half of each
///    contiguous and half strided; compressed: per cluster, dense tile columns or U (V^T f).
///  - kColumns: a private copy of all N columns of C (both halves: twice the symmetric memory) in
///    a planar SIMD layout, float32, float16 (one scale per 16 nodes) or int16 (fixed point, one
///    scale per column, summed with integer dot products, AVX-512 VNNI where the CPU has it):
///    every column streams.
/// Kernels are chosen at run time (AVX-512, AVX2 + FMA + F16C, portable); the build needs no
/// -march flag.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"

namespace handshare::fem {

namespace detail {
class PlanarColumns;
}  // namespace detail

/// A load on the object at one compliance node. Plain data, trivially copyable.
struct NodeLoad {
  std::int32_t slot = -1;                          ///< compliance slot (Compliance::SlotOf).
  Eigen::Vector3d f_N = Eigen::Vector3d::Zero();   ///< force on the object [N].
};

/// Where SurfaceField reads the columns of C from.
enum class SurfaceFieldLayout : std::uint8_t { kCompliance, kColumns };

struct SurfaceFieldOptions {
  SurfaceFieldLayout layout = SurfaceFieldLayout::kCompliance;
  /// kColumns only: kFloat64, kFloat32, kFloat16 or kInt16.
  Precision precision = Precision::kFloat32;
  /// false forces the portable kernels (tests).
  bool allow_simd = true;
};

/// Evaluates surface displacement fields on one Compliance. Not thread-safe (owns scratch);
/// one per thread.
class SurfaceField {
 public:
  /// Allocates the scratch (9 N floats). allow_simd = false forces the portable code (tests).
  explicit SurfaceField(std::shared_ptr<const Compliance> compliance, bool allow_simd = true);
  /// With a layout; kColumns copies the columns (offline: O(N^2) time and memory).
  /// @throws InputError for a null compliance or a bad precision.
  SurfaceField(std::shared_ptr<const Compliance> compliance, const SurfaceFieldOptions& options);
  ~SurfaceField();
  SurfaceField(SurfaceField&&) noexcept;
  SurfaceField& operator=(SurfaceField&&) noexcept;

  /// u_m[n] = displacement [m] of slot n. Loads with an out-of-range slot are skipped.
  /// @returns false (and writes nothing) if u_m.size() != num_nodes().
  bool Evaluate(std::span<const NodeLoad> loads, std::span<Eigen::Vector3d> u_m) noexcept;

  /// True if Evaluate uses a SIMD kernel (AVX-512 or AVX2; the packed layout has AVX-512 only,
  /// for float32).
  bool uses_simd() const noexcept { return simd_; }
  /// "avx512", "avx2" or "portable".
  const char* kernel_name() const noexcept;
  const Compliance& compliance() const noexcept { return *compliance_; }
  /// Bytes this object holds besides the compliance (the kColumns copy, scratch).
  std::size_t storage_bytes() const noexcept;

 private:
  std::shared_ptr<const Compliance> compliance_;
  SurfaceFieldOptions options_;
  bool simd_ = false;
  std::uint8_t isa_ = 0;         // detail::Isa
  std::vector<float> expanded_;  // 9 N (+ padding) partial products (packed float32), or 3 N + 64
                                 // accumulators (compressed)
  std::unique_ptr<detail::PlanarColumns> columns_;  // kColumns
};

/// True if this CPU runs the AVX-512 kernels.
bool CpuHasAvx512() noexcept;

}  // namespace handshare::fem
