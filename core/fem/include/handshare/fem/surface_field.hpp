#pragma once
/// @file
/// The surface displacement field of a set of nodal loads, u_n = sum_j C_{n,k_j} f_j for every
/// compliance node n (the graphics-rate half of the elementary displacement method). Separate
/// from ContactSolver so that the haptic thread can hand its loads (a trivially copyable list)
/// to a graphics or bridge thread that owns a SurfaceField. Evaluate() is noexcept and does not
/// allocate; its cost is O(N m) and memory-bound: it reads m packed columns of C, half of each
/// contiguous and half strided (symmetric storage). Uses AVX-512 for float32 storage when the
/// CPU has it, portable scalar code otherwise.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"

namespace handshare::fem {

/// A load on the object at one compliance node. Plain data, trivially copyable.
struct NodeLoad {
  std::int32_t slot = -1;                          ///< compliance slot (Compliance::SlotOf).
  Eigen::Vector3d f_N = Eigen::Vector3d::Zero();   ///< force on the object [N].
};

/// Evaluates surface displacement fields on one Compliance. Not thread-safe (owns scratch);
/// one per thread.
class SurfaceField {
 public:
  /// Allocates the scratch (9 N floats). allow_simd = false forces the portable code (tests).
  explicit SurfaceField(std::shared_ptr<const Compliance> compliance, bool allow_simd = true);

  /// u_m[n] = displacement [m] of slot n. Loads with an out-of-range slot are skipped.
  /// @returns false (and writes nothing) if u_m.size() != num_nodes().
  bool Evaluate(std::span<const NodeLoad> loads, std::span<Eigen::Vector3d> u_m) noexcept;

  /// True if Evaluate uses the AVX-512 kernel (float32 storage on a CPU with AVX-512F/VL).
  bool uses_simd() const noexcept { return simd_; }
  const Compliance& compliance() const noexcept { return *compliance_; }

 private:
  std::shared_ptr<const Compliance> compliance_;
  bool simd_ = false;
  std::vector<float> expanded_;  // 9 N (+ padding) partial products, float path
};

/// True if this CPU runs the AVX-512 kernels.
bool CpuHasAvx512() noexcept;

}  // namespace handshare::fem
