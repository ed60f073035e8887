#include "compressed_blocks.hpp"

#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>

#include "handshare/fem/error.hpp"

namespace handshare::fem::detail {
namespace {

// k-d tree: split the longest box axis at the median until a cluster has at most `leaf` nodes;
// the leaves, in tree order, are the clusters (neighbouring leaves are neighbouring in space).
void KdSplit(std::span<const Eigen::Vector3d> p, std::int32_t* first, std::int32_t* last, int leaf,
             std::vector<std::int32_t>& leaf_sizes) {
  const auto n = static_cast<int>(last - first);
  if (n <= leaf) {
    leaf_sizes.push_back(n);
    return;
  }
  Eigen::Vector3d lo = p[*first], hi = p[*first];
  for (auto* s = first; s != last; ++s) {
    lo = lo.cwiseMin(p[*s]);
    hi = hi.cwiseMax(p[*s]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  std::int32_t* mid = first + n / 2;
  std::nth_element(first, mid, last, [&](std::int32_t a, std::int32_t b) {
    return p[a][axis] < p[b][axis] || (p[a][axis] == p[b][axis] && a < b);
  });
  KdSplit(p, first, mid, leaf, leaf_sizes);
  KdSplit(p, mid, last, leaf, leaf_sizes);
}

// ACA with full pivoting on the explicit m x n tile R (destroyed: it ends as the residual).
// Returns the rank, or -1 if the tolerance is not met within max_rank; U (m x r), V (n x r).
int AcaFullPivot(Eigen::MatrixXd& R, double tol_abs, int max_rank, Eigen::MatrixXd& U, Eigen::MatrixXd& V) {
  const Eigen::Index m = R.rows(), n = R.cols();
  U.resize(m, max_rank);
  V.resize(n, max_rank);
  for (int r = 0;; ++r) {
    Eigen::Index pi = 0, pj = 0;
    double best = -1.0, res2 = 0.0;
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = 0; i < m; ++i) {
        const double a = std::abs(R(i, j));
        res2 += a * a;
        if (a > best) {
          best = a;
          pi = i;
          pj = j;
        }
      }
    if (std::sqrt(res2) <= tol_abs) return r;
    if (r == max_rank || best == 0.0) return -1;
    U.col(r) = R.col(pj);
    V.col(r) = R.row(pi).transpose() / R(pi, pj);
    R.noalias() -= U.col(r) * V.col(r).transpose();
  }
}

#define HS_AVX2 __attribute__((target("avx2,fma")))
#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma")))
#define HS_INLINE inline __attribute__((always_inline))

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

// y[0..len) += A w, A column-major (len x r, leading dimension ld).
struct GemvPortable {
  HS_INLINE static void Run(float* y, const float* A, std::int64_t ld, int len, int r, const float* w) noexcept {
    for (int t = 0; t < r; ++t) {
      const float* a = A + t * ld;
      const float wt = w[t];
      for (int i = 0; i < len; ++i) y[i] += a[i] * wt;
    }
  }
};

struct GemvAvx2 {
  HS_AVX2 HS_INLINE static void Run(float* y, const float* A, std::int64_t ld, int len, int r, const float* w) noexcept {
    int i = 0;
    for (; i + 16 <= len; i += 16) {
      __m256 a0 = _mm256_loadu_ps(y + i), a1 = _mm256_loadu_ps(y + i + 8);
      for (int t = 0; t < r; ++t) {
        const __m256 wt = _mm256_set1_ps(w[t]);
        a0 = _mm256_fmadd_ps(_mm256_loadu_ps(A + t * ld + i), wt, a0);
        a1 = _mm256_fmadd_ps(_mm256_loadu_ps(A + t * ld + i + 8), wt, a1);
      }
      _mm256_storeu_ps(y + i, a0);
      _mm256_storeu_ps(y + i + 8, a1);
    }
    for (; i < len; ++i) {
      float s = y[i];
      for (int t = 0; t < r; ++t) s += A[t * ld + i] * w[t];
      y[i] = s;
    }
  }
};

struct GemvAvx512 {
  HS_AVX512 HS_INLINE static void Run(float* y, const float* A, std::int64_t ld, int len, int r, const float* w) noexcept {
    int i = 0;
    for (; i + 32 <= len; i += 32) {
      __m512 a0 = _mm512_loadu_ps(y + i), a1 = _mm512_loadu_ps(y + i + 16);
      for (int t = 0; t < r; ++t) {
        const __m512 wt = _mm512_set1_ps(w[t]);
        a0 = _mm512_fmadd_ps(_mm512_loadu_ps(A + t * ld + i), wt, a0);
        a1 = _mm512_fmadd_ps(_mm512_loadu_ps(A + t * ld + i + 16), wt, a1);
      }
      _mm512_storeu_ps(y + i, a0);
      _mm512_storeu_ps(y + i + 16, a1);
    }
    for (; i < len; i += 16) {
      const int rest = len - i;
      const __mmask16 mk = rest >= 16 ? static_cast<__mmask16>(0xFFFF) : static_cast<__mmask16>((1u << rest) - 1u);
      __m512 a0 = _mm512_maskz_loadu_ps(mk, y + i);
      for (int t = 0; t < r; ++t) {
        a0 = _mm512_fmadd_ps(_mm512_maskz_loadu_ps(mk, A + t * ld + i), _mm512_set1_ps(w[t]), a0);
      }
      _mm512_mask_storeu_ps(y + i, mk, a0);
    }
  }
};

#pragma GCC diagnostic pop

}  // namespace

CompressedBlocks CompressedBlocks::Build(std::span<const Eigen::Vector3d> positions_m, const Compliance& exact,
                                         const CompressionOptions& options, CompressionStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::int32_t N = exact.num_nodes();
  if (static_cast<std::int32_t>(positions_m.size()) != N) throw InputError("", 0, "positions", "one per compliance node");
  if (!(options.tolerance > 0.0 && options.tolerance < 1.0)) throw InputError("", 0, "tolerance", "must be in (0, 1)");
  if (options.leaf_nodes < 4 || options.leaf_nodes > 256) throw InputError("", 0, "leaf_nodes", "must be in 4..256");
  CompressedBlocks h;
  h.slot_of_pos_.resize(static_cast<std::size_t>(N));
  std::iota(h.slot_of_pos_.begin(), h.slot_of_pos_.end(), 0);
  std::vector<std::int32_t> sizes;
  KdSplit(positions_m, h.slot_of_pos_.data(), h.slot_of_pos_.data() + N, options.leaf_nodes, sizes);
  h.pos_.resize(static_cast<std::size_t>(N));
  for (std::int32_t p = 0; p < N; ++p) h.pos_[h.slot_of_pos_[p]] = p;
  h.leaf_start_.assign(1, 0);
  for (std::int32_t s : sizes) h.leaf_start_.push_back(h.leaf_start_.back() + s);
  h.leaf_of_pos_.resize(static_cast<std::size_t>(N));
  const std::int32_t L = h.num_leaves_();
  for (std::int32_t I = 0; I < L; ++I)
    for (std::int32_t p = h.leaf_start_[I]; p < h.leaf_start_[I + 1]; ++p) h.leaf_of_pos_[p] = I;

  h.tiles_.resize(static_cast<std::size_t>(TileIndex(0, L)));
  std::int64_t low_rank = 0, rank_sum = 0;
  Eigen::MatrixXd A, U, V;
  std::vector<float> data;  // grows; copied into aligned storage at the end
  for (std::int32_t J = 0; J < L; ++J) {
    for (std::int32_t I = 0; I <= J; ++I) {
      const std::int32_t sI = h.leaf_start_[I], sJ = h.leaf_start_[J];
      const int m = 3 * (h.leaf_start_[I + 1] - sI), n = 3 * (h.leaf_start_[J + 1] - sJ);
      A.resize(m, n);
      for (int b = 0; b < n / 3; ++b)
        for (int a = 0; a < m / 3; ++a)
          A.block<3, 3>(3 * a, 3 * b) = exact.Block(h.slot_of_pos_[sI + a], h.slot_of_pos_[sJ + b]);
      Tile& tile = h.tiles_[static_cast<std::size_t>(TileIndex(I, J))];
      tile.offset = static_cast<std::int64_t>(data.size());
      int rank = -1;
      if (I != J) {
        const int max_rank = (m * n - 1) / (m + n);  // low rank only where it is smaller
        Eigen::MatrixXd R = A;
        rank = AcaFullPivot(R, options.tolerance * A.norm(), max_rank, U, V);
      }
      tile.rank = rank;
      if (rank < 0) {
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < m; ++i) data.push_back(static_cast<float>(A(i, j)));
      } else {
        ++low_rank;
        rank_sum += rank;
        for (int t = 0; t < rank; ++t)
          for (int i = 0; i < m; ++i) data.push_back(static_cast<float>(U(i, t)));
        for (int t = 0; t < rank; ++t)
          for (int j = 0; j < n; ++j) data.push_back(static_cast<float>(V(j, t)));
      }
    }
  }
  h.data_.assign(data.begin(), data.end());
  if (stats != nullptr) {
    stats->tiles = static_cast<std::int64_t>(h.tiles_.size());
    stats->low_rank_tiles = low_rank;
    stats->mean_rank = low_rank > 0 ? static_cast<double>(rank_sum) / static_cast<double>(low_rank) : 0.0;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return h;
}

Eigen::Matrix3d CompressedBlocks::Block(std::int32_t n, std::int32_t k) const noexcept {
  std::int32_t p = pos_[n], q = pos_[k];
  std::int32_t I = leaf_of_pos_[p], J = leaf_of_pos_[q];
  const bool transpose = I > J;
  if (transpose) {
    std::swap(p, q);
    std::swap(I, J);
  }
  const int a = p - leaf_start_[I], b = q - leaf_start_[J];
  const std::int64_t m = 3 * (leaf_start_[I + 1] - leaf_start_[I]), nn = 3 * (leaf_start_[J + 1] - leaf_start_[J]);
  const Tile& tile = tiles_[static_cast<std::size_t>(TileIndex(I, J))];
  const float* base = data_.data() + tile.offset;
  Eigen::Matrix3d B;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) {
      if (tile.rank < 0) {
        B(r, c) = base[(3 * b + c) * m + 3 * a + r];
      } else {
        const float* U = base;
        const float* V = base + m * tile.rank;
        double s = 0.0;
        for (int t = 0; t < tile.rank; ++t) s += static_cast<double>(U[t * m + 3 * a + r]) * V[t * nn + 3 * b + c];
        B(r, c) = s;
      }
    }
  if (transpose) B.transposeInPlace();
  return B;
}

namespace {

inline std::int64_t TileAt(std::int32_t I, std::int32_t J) noexcept {
  return static_cast<std::int64_t>(J) * (J + 1) / 2 + I;
}

#define HS_APPLY_NAME ApplyAvx512
#define HS_APPLY_ATTR HS_AVX512
#define HS_GEMV GemvAvx512
#include "compressed_apply.inc"
#undef HS_APPLY_NAME
#undef HS_APPLY_ATTR
#undef HS_GEMV
#define HS_APPLY_NAME ApplyAvx2
#define HS_APPLY_ATTR HS_AVX2
#define HS_GEMV GemvAvx2
#include "compressed_apply.inc"
#undef HS_APPLY_NAME
#undef HS_APPLY_ATTR
#undef HS_GEMV
#define HS_APPLY_NAME ApplyPortable
#define HS_APPLY_ATTR
#define HS_GEMV GemvPortable
#include "compressed_apply.inc"
#undef HS_APPLY_NAME
#undef HS_APPLY_ATTR
#undef HS_GEMV

}  // namespace

CompressedView CompressedBlocks::View() const noexcept {
  return {pos_.data(), leaf_of_pos_.data(), leaf_start_.data(), slot_of_pos_.data(), num_nodes(),
          num_leaves_(), tiles_.data(), data_.data()};
}

void CompressedBlocks::Apply(std::span<const NodeLoad> loads, Eigen::Vector3d* out, float* scratch,
                             Isa isa) const noexcept {
  const CompressedView v = View();
  switch (isa) {
    case Isa::kAvx512: ApplyAvx512(v, loads, out, scratch); break;
    case Isa::kAvx2: ApplyAvx2(v, loads, out, scratch); break;
    case Isa::kPortable: ApplyPortable(v, loads, out, scratch); break;
  }
}

std::size_t CompressedBlocks::storage_bytes() const noexcept {
  return data_.size() * sizeof(float) + tiles_.size() * sizeof(Tile) +
         (slot_of_pos_.size() + pos_.size() + leaf_of_pos_.size() + leaf_start_.size()) * sizeof(std::int32_t);
}

}  // namespace handshare::fem::detail
