#include "compressed_blocks.hpp"

#include <immintrin.h>

#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

#include "handshare/fem/error.hpp"

namespace handshare::fem::detail {
namespace {

// k-d cluster tree: split the longest box axis at the median until a cluster has at most `leaf`
// nodes. Every cluster (inner or leaf) is recorded with its bounding box and its ranges of
// positions and of leaves; the leaves, in tree order, are the tiles' clusters (neighbouring
// leaves are neighbouring in space), and every cluster is a contiguous run of them.
struct Cluster {
  std::int32_t begin = 0, end = 0;            // positions [begin, end)
  std::int32_t leaf_begin = 0, leaf_end = 0;  // leaves [leaf_begin, leaf_end)
  std::int32_t child[2] = {-1, -1};           // -1: a leaf
  Eigen::Vector3d lo, hi;                     // bounding box
  bool leaf() const { return child[0] < 0; }
  std::int32_t size() const { return end - begin; }
};

std::int32_t KdSplit(std::span<const Eigen::Vector3d> p, std::int32_t* order, std::int32_t first, std::int32_t last,
                     int leaf, std::vector<Cluster>& clusters, std::vector<std::int32_t>& leaf_sizes) {
  const auto id = static_cast<std::int32_t>(clusters.size());
  clusters.emplace_back();
  Cluster c;
  c.begin = first;
  c.end = last;
  c.lo = c.hi = p[order[first]];
  for (std::int32_t s = first; s != last; ++s) {
    c.lo = c.lo.cwiseMin(p[order[s]]);
    c.hi = c.hi.cwiseMax(p[order[s]]);
  }
  c.leaf_begin = static_cast<std::int32_t>(leaf_sizes.size());
  const std::int32_t n = last - first;
  if (n <= leaf) {
    leaf_sizes.push_back(n);
  } else {
    int axis = 0;
    (c.hi - c.lo).maxCoeff(&axis);
    const std::int32_t mid = first + n / 2;
    std::nth_element(order + first, order + mid, order + last, [&](std::int32_t a, std::int32_t b) {
      return p[a][axis] < p[b][axis] || (p[a][axis] == p[b][axis] && a < b);
    });
    c.child[0] = KdSplit(p, order, first, mid, leaf, clusters, leaf_sizes);
    c.child[1] = KdSplit(p, order, mid, last, leaf, clusters, leaf_sizes);
  }
  c.leaf_end = static_cast<std::int32_t>(leaf_sizes.size());
  clusters[static_cast<std::size_t>(id)] = c;
  return id;
}

// Zero halves after the float16 factors: the vector kernels' last loads may run this far past a column.
constexpr std::size_t kHalfPadding = 16;

// ACA stops at this share of the block's error budget; the SVD recompression may spend the rest.
constexpr double kAcaShare = 0.3;

double Diameter(const Cluster& c) { return (c.hi - c.lo).norm(); }

double BoxDistance(const Cluster& a, const Cluster& b) {
  const Eigen::Vector3d gap = (a.lo - b.hi).cwiseMax(b.lo - a.hi).cwiseMax(0.0);
  return gap.norm();
}

// ACA with full pivoting on the explicit m x n block R (destroyed: it ends as the residual).
// Returns the rank, or -1 if the tolerance is not met within max_rank; U (m x r), V (n x r).
int AcaFullPivot(Eigen::MatrixXd& R, double tol_abs, int max_rank, Eigen::MatrixXd& U, Eigen::MatrixXd& V) {
  U.resize(R.rows(), std::max(max_rank, 1));
  V.resize(R.cols(), std::max(max_rank, 1));
  const double tol2 = tol_abs * tol_abs;
  for (int r = 0;; ++r) {
    if (R.squaredNorm() <= tol2) return r;
    Eigen::Index pi = 0, pj = 0;
    const double best = R.cwiseAbs().maxCoeff(&pi, &pj);
    if (r >= max_rank || best == 0.0) return -1;
    U.col(r) = R.col(pj);
    V.col(r) = R.row(pi).transpose() / R(pi, pj);
    R.noalias() -= U.col(r) * V.col(r).transpose();
  }
}

#define HS_AVX2 __attribute__((target("avx2,fma,f16c")))
#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma,f16c")))
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
  // The same with A in float16.
  HS_INLINE static void RunHalf(float* y, const std::uint16_t* A, std::int64_t ld, int len, int r,
                                const float* w) noexcept {
    for (int t = 0; t < r; ++t) {
      const std::uint16_t* a = A + t * ld;
      const float wt = w[t];
      for (int i = 0; i < len; ++i) y[i] += HalfToFloat(a[i]) * wt;
    }
  }
  HS_INLINE static float H(std::uint16_t h) noexcept { return HalfToFloat(h); }
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
  HS_AVX2 HS_INLINE static void RunHalf(float* y, const std::uint16_t* A, std::int64_t ld, int len, int r,
                                        const float* w) noexcept {
    int i = 0;
    for (; i + 16 <= len; i += 16) {
      __m256 a0 = _mm256_loadu_ps(y + i), a1 = _mm256_loadu_ps(y + i + 8);
      for (int t = 0; t < r; ++t) {
        const __m256 wt = _mm256_set1_ps(w[t]);
        const std::uint16_t* a = A + t * ld + i;
        a0 = _mm256_fmadd_ps(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a))), wt, a0);
        a1 = _mm256_fmadd_ps(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + 8))), wt, a1);
      }
      _mm256_storeu_ps(y + i, a0);
      _mm256_storeu_ps(y + i + 8, a1);
    }
    // The rest 8 at a time through a copy of y; A may be read up to 7 halves past a column
    // (the float16 data is padded at its end, the extra lanes are dropped).
    for (; i < len; i += 8) {
      const int rest = std::min(len - i, 8);
      alignas(32) float tmp[8] = {};
      for (int j = 0; j < rest; ++j) tmp[j] = y[i + j];
      __m256 a0 = _mm256_load_ps(tmp);
      for (int t = 0; t < r; ++t) {
        a0 = _mm256_fmadd_ps(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(A + t * ld + i))),
                             _mm256_set1_ps(w[t]), a0);
      }
      _mm256_store_ps(tmp, a0);
      for (int j = 0; j < rest; ++j) y[i + j] = tmp[j];
    }
  }
  HS_AVX2 HS_INLINE static float H(std::uint16_t h) noexcept { return _cvtsh_ss(h); }
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
  HS_AVX512 HS_INLINE static void RunHalf(float* y, const std::uint16_t* A, std::int64_t ld, int len, int r,
                                          const float* w) noexcept {
    int i = 0;
    for (; i + 32 <= len; i += 32) {
      __m512 a0 = _mm512_loadu_ps(y + i), a1 = _mm512_loadu_ps(y + i + 16);
      for (int t = 0; t < r; ++t) {
        const __m512 wt = _mm512_set1_ps(w[t]);
        const std::uint16_t* a = A + t * ld + i;
        a0 = _mm512_fmadd_ps(_mm512_cvtph_ps(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(a))), wt, a0);
        a1 = _mm512_fmadd_ps(_mm512_cvtph_ps(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + 16))), wt, a1);
      }
      _mm512_storeu_ps(y + i, a0);
      _mm512_storeu_ps(y + i + 16, a1);
    }
    // The rest 16 at a time, y masked; A may be read up to 15 halves past a column (the float16
    // data is padded at its end, the extra lanes are dropped).
    for (; i < len; i += 16) {
      const int rest = len - i;
      const __mmask16 mk = rest >= 16 ? static_cast<__mmask16>(0xFFFF) : static_cast<__mmask16>((1u << rest) - 1u);
      __m512 a0 = _mm512_maskz_loadu_ps(mk, y + i);
      for (int t = 0; t < r; ++t) {
        a0 = _mm512_fmadd_ps(_mm512_cvtph_ps(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(A + t * ld + i))),
                             _mm512_set1_ps(w[t]), a0);
      }
      _mm512_mask_storeu_ps(y + i, mk, a0);
    }
  }
  HS_AVX512 HS_INLINE static float H(std::uint16_t h) noexcept { return _cvtsh_ss(h); }
};

#pragma GCC diagnostic pop

}  // namespace

namespace {

// The offline partition and compression (see compressed_blocks.hpp).
class HBuilder {
 public:
  HBuilder(const Compliance& exact, const CompressionOptions& options, const std::vector<Cluster>& clusters,
           const std::vector<std::int32_t>& slot_of_pos, const std::vector<std::int32_t>& leaf_start,
           std::vector<CompressedTile>& tiles, std::vector<CompressedBlockInfo>& blocks)
      : exact_(exact), o_(options), cl_(clusters), slot_(slot_of_pos), leaf_start_(leaf_start), tiles_(tiles),
        blocks_(blocks) {}

  void Partition(std::int32_t si, std::int32_t ti) {
    const Cluster& s = cl_[static_cast<std::size_t>(si)];
    const Cluster& t = cl_[static_cast<std::size_t>(ti)];
    if (si == ti) {
      if (s.leaf()) {
        Symmetric(s);
      } else {
        Partition(s.child[0], s.child[0]);
        Partition(s.child[0], s.child[1]);
        Partition(s.child[1], s.child[1]);
      }
      return;
    }
    if (s.leaf() && t.leaf()) {
      // A leaf pair on its own: low rank where that beats dense, else dense.
      const int rank = Compress(s, t, kNoLimit);
      if (rank >= 0) {
        Emit(s, t, rank);
      } else {
        Dense(s, t);
      }
      return;
    }
    const std::int64_t entries = 9 * static_cast<std::int64_t>(s.size()) * t.size();
    const bool admissible =
        o_.hierarchical && (o_.weak_admissibility || std::min(Diameter(s), Diameter(t)) <= o_.eta * BoxDistance(s, t));
    if (!admissible || entries > o_.max_block_entries) {
      Split(si, ti);
      return;
    }
    // One U V^T for (s, t) if it stores fewer floats than its split (computed first, recursively,
    // and undone when the single block wins; its size caps the rank the compression may use).
    const Mark mark = Save();
    Split(si, ti);
    const std::int64_t split_floats = static_cast<std::int64_t>(data.size()) - mark.data +
                                      (static_cast<std::int64_t>(halves.size()) - mark.halves + 1) / 2;
    const int rank = Compress(s, t, split_floats);
    if (rank >= 0) {
      Restore(mark);
      Emit(s, t, rank);
    }
  }

  // Both clusters' children, or the one that is not a leaf.
  void Split(std::int32_t si, std::int32_t ti) {
    const Cluster& s = cl_[static_cast<std::size_t>(si)];
    const Cluster& t = cl_[static_cast<std::size_t>(ti)];
    if (s.leaf()) {
      Partition(si, t.child[0]);
      Partition(si, t.child[1]);
    } else if (t.leaf()) {
      Partition(s.child[0], ti);
      Partition(s.child[1], ti);
    } else {
      for (std::int32_t a : s.child)
        for (std::int32_t b : t.child) Partition(a, b);
    }
  }

  std::vector<float> data;             // dense tiles, float32 factors, float16 factors' scales
  std::vector<std::uint16_t> halves;   // float16 factors
  // What the emitted blocks add up to (undone with them when a single block beats a split).
  struct Totals {
    std::int64_t low_rank_blocks = 0, half_blocks = 0, rank_sum = 0, largest = 0, dense_floats = 0, factor_bytes = 0;
    int max_rank = 0;
  } totals;
  std::int64_t tried = 0;  // blocks compressed (kept or not): not undone

 private:
  // What Emit and Dense have appended, to undo a split that a single block beats.
  struct Mark {
    std::int64_t data, halves, blocks;
    Totals totals;
  };
  Mark Save() const {
    return {static_cast<std::int64_t>(data.size()), static_cast<std::int64_t>(halves.size()),
            static_cast<std::int64_t>(blocks_.size()), totals};
  }
  void Restore(const Mark& m) {
    data.resize(static_cast<std::size_t>(m.data));
    halves.resize(static_cast<std::size_t>(m.halves));
    blocks_.resize(static_cast<std::size_t>(m.blocks));
    totals = m.totals;
  }

  // The exact block (s rows, t columns) into A_.
  void Fill(const Cluster& s, const Cluster& t) {
    A_.resize(3 * s.size(), 3 * t.size());
    for (std::int32_t b = 0; b < t.size(); ++b)
      for (std::int32_t a = 0; a < s.size(); ++a)
        A_.block<3, 3>(3 * a, 3 * b) = exact_.Block(slot_[s.begin + a], slot_[t.begin + b]);
  }

  void Dense(const Cluster& s, const Cluster& t) {
    Fill(s, t);
    CompressedTile& tile = tiles_[static_cast<std::size_t>(Compliance::PackedIndex(s.leaf_begin, t.leaf_begin))];
    tile.offset_u = Offset();
    tile.ld_u = static_cast<std::int32_t>(A_.rows());
    tile.rank = kDenseTile;
    for (Eigen::Index j = 0; j < A_.cols(); ++j)
      for (Eigen::Index i = 0; i < A_.rows(); ++i) data.push_back(static_cast<float>(A_(i, j)));
    totals.dense_floats += A_.size();
    blocks_.push_back({s.begin, s.end, t.begin, t.end, -1});
  }

  // A diagonal leaf tile: C_ss is symmetric, so only its upper triangle is stored (by columns).
  void Symmetric(const Cluster& s) {
    Fill(s, s);
    CompressedTile& tile = tiles_[static_cast<std::size_t>(Compliance::PackedIndex(s.leaf_begin, s.leaf_begin))];
    tile.offset_u = Offset();
    tile.ld_u = static_cast<std::int32_t>(A_.rows());
    tile.rank = kSymmetricTile;
    for (Eigen::Index j = 0; j < A_.cols(); ++j)
      for (Eigen::Index i = 0; i <= j; ++i) data.push_back(static_cast<float>(A_(i, j)));
    totals.dense_floats += A_.rows() * (A_.rows() + 1) / 2;
    blocks_.push_back({s.begin, s.end, s.begin, s.end, -1});
  }

  // The rank of one U V^T for the whole block if the tolerance is met by a factorization that
  // stores fewer floats than dense and at most max_floats (float16 factors count half, plus one
  // float32 scale per rank), else -1; the stored factors are left in U_, V_ (float32) or Uh_, Vh_,
  // Sh_ (float16, half_ = true). ACA first runs to a fraction of the tolerance (its rank is not
  // optimal), then the product is recompressed to the smallest rank whose explicit residual
  // ||A - U V^T||_F, with U and V rounded exactly as they will be stored, meets the tolerance (QR
  // of both factors, SVD of the r x r core; candidates from the singular values, each one
  // checked). With factor_precision kFloat16 the float16 candidates are tried first and float32
  // is the fallback for the block.
  static constexpr std::int64_t kNoLimit = std::numeric_limits<std::int64_t>::max() / 4;
  int Compress(const Cluster& s, const Cluster& t, std::int64_t max_floats) {
    const std::int64_t m = 3 * static_cast<std::int64_t>(s.size()), n = 3 * static_cast<std::int64_t>(t.size());
    const std::int64_t cap = std::min(max_floats, m * n - 1);
    const bool try_half = o_.factor_precision == Precision::kFloat16;
    if (cap < 0) return -1;
    Fill(s, t);
    ++tried;
    Candidates c;
    c.m = m;
    c.n = n;
    const double norm = A_.norm();
    c.budget = o_.tolerance * norm;
    R_ = A_;
    // ACA may overshoot the rank that the recompression ends at, so its limit follows the dense
    // break-even rank (not max_floats: a tighter ACA limit was measured to cost memory).
    const int dense_limit = MostRank(m, n, m * n - 1, try_half);
    const int aca_limit = static_cast<int>(std::min<std::int64_t>({dense_limit + dense_limit / 2 + 2, m, n}));
    c.aca = AcaFullPivot(R_, kAcaShare * c.budget, aca_limit, U_, V_);
    if (c.aca < 0) return -1;
    Recompress(c);
    return SmallestStoredRank(c, cap, try_half);
  }

  // Compress's stages. The candidate factors of one block: of rank k from the SVD of the
  // recompression of ACA's factors, or ACA's own at rank <= 1.
  struct Candidates {
    std::int64_t m = 0, n = 0;  // the block's rows and columns
    double budget = 0.0;        // tolerance * ||A||_F
    int aca = 0;                // ACA's rank
    int k0 = 0;                 // the smallest rank the singular values allow
    Eigen::MatrixXd qum, qvm, su, sv_mat;
    Eigen::VectorXd sv;
    Eigen::MatrixXd u, v;       // the candidate Meets last rounded
  };
  // Floats a rank-k factorization of an m x n block stores (float16 factors count half, plus
  // one float32 scale per rank).
  static std::int64_t Cost(std::int64_t m, std::int64_t n, std::int64_t k, bool half) {
    return half ? (k * (m + n) + 1) / 2 + k : k * (m + n);
  }
  // The largest k with Cost(k) <= floats (at most kMaxBlockRank).
  static int MostRank(std::int64_t m, std::int64_t n, std::int64_t floats, bool half) {
    std::int64_t k = half ? 2 * floats / (m + n + 2) + 1 : floats / (m + n);
    while (k > 0 && Cost(m, n, k, half) > floats) --k;
    return static_cast<int>(std::min<std::int64_t>(k, kMaxBlockRank));
  }

  // QR of both ACA factors, SVD of the r x r core, and the smallest k whose discarded singular
  // values, added to the ACA residual, fit the budget.
  void Recompress(Candidates& c) {
    c.k0 = c.aca;
    if (c.aca <= 1) return;
    const int aca = c.aca;
    const Eigen::HouseholderQR<Eigen::MatrixXd> qu(U_.leftCols(aca)), qv(V_.leftCols(aca));
    const Eigen::MatrixXd ru = qu.matrixQR().topRows(aca).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd rv = qv.matrixQR().topRows(aca).triangularView<Eigen::Upper>();
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(ru * rv.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    c.sv = svd.singularValues();
    const double r2 = R_.squaredNorm();
    double tail2 = 0.0;
    while (c.k0 > 0 && r2 + tail2 + c.sv(c.k0 - 1) * c.sv(c.k0 - 1) <= c.budget * c.budget) {
      tail2 += c.sv(c.k0 - 1) * c.sv(c.k0 - 1);
      --c.k0;
    }
    c.qum = qu.householderQ() * Eigen::MatrixXd::Identity(c.m, aca);
    c.qvm = qv.householderQ() * Eigen::MatrixXd::Identity(c.n, aca);
    c.su = svd.matrixU();
    c.sv_mat = svd.matrixV();
  }

  // Rounds the rank-k candidate as it would be stored and checks its explicit residual; on
  // success the stored form is left for Emit.
  bool Meets(Candidates& c, int k, bool half) {
    if (c.aca > 1) {
      c.u = c.qum * (c.su.leftCols(k) * c.sv.head(k).asDiagonal());
      c.v = c.qvm * c.sv_mat.leftCols(k);
    } else {
      c.u = U_.leftCols(k);
      c.v = V_.leftCols(k);
    }
    Round(c.u, c.v, half);
    R_ = A_;
    R_.noalias() -= c.u * c.v.transpose();
    if (R_.norm() > c.budget) return false;
    half_ = half;
    if (!half) {
      U_.leftCols(k) = c.u;
      V_.leftCols(k) = c.v;
    }
    return true;
  }

  // The smallest rank that meets the tolerance within cap floats: float16 first (with
  // factor_precision kFloat16), then float32 at the ranks that store less than that; -1: none.
  int SmallestStoredRank(Candidates& c, std::int64_t cap, bool try_half) {
    int half_rank = -1;
    if (try_half) {
      // First at the largest allowed rank, where truncation is smallest: if the rounding fails
      // there, it fails at every rank (saves the search at tight tolerances).
      const int limit = std::min(MostRank(c.m, c.n, cap, true), c.aca);
      if (c.k0 <= limit && (c.k0 == limit || Meets(c, limit, true))) {
        for (int k = c.k0; k <= limit && half_rank < 0; ++k)
          if (Meets(c, k, true)) half_rank = k;
      }
    }
    // float32 at the ranks that store less than the float16 result (if any).
    const int limit =
        std::min(MostRank(c.m, c.n, half_rank >= 0 ? Cost(c.m, c.n, half_rank, true) - 1 : cap, false), c.aca);
    for (int k = c.k0; k <= limit; ++k)
      if (Meets(c, k, false)) return k;
    half_ = half_rank >= 0;
    return half_rank;
  }

  // Rounds u, v (m x k, n x k) to what is stored: float32, or (half) columns scaled to a largest
  // entry of 1 in float16 with the product of the scales in float32 (kept in Uh_, Vh_, Sh_; u
  // returns with the scales applied).
  void Round(Eigen::MatrixXd& u, Eigen::MatrixXd& v, bool half) {
    if (!half) {
      u = u.cast<float>().cast<double>();
      v = v.cast<float>().cast<double>();
      return;
    }
    const Eigen::Index k = u.cols();
    Uh_.resize(static_cast<std::size_t>(u.size()));
    Vh_.resize(static_cast<std::size_t>(v.size()));
    Sh_.resize(static_cast<std::size_t>(k));
    for (Eigen::Index c = 0; c < k; ++c) {
      const double au = u.col(c).cwiseAbs().maxCoeff(), av = v.col(c).cwiseAbs().maxCoeff();
      const double iu = au > 0.0 ? 1.0 / au : 0.0, iv = av > 0.0 ? 1.0 / av : 0.0;
      const float scale = static_cast<float>(au * av);
      Sh_[static_cast<std::size_t>(c)] = scale;
      for (Eigen::Index i = 0; i < u.rows(); ++i) {
        const std::uint16_t h = FloatToHalf(static_cast<float>(u(i, c) * iu));
        Uh_[static_cast<std::size_t>(c * u.rows() + i)] = h;
        u(i, c) = static_cast<double>(HalfToFloat(h)) * scale;
      }
      for (Eigen::Index j = 0; j < v.rows(); ++j) {
        const std::uint16_t h = FloatToHalf(static_cast<float>(v(j, c) * iv));
        Vh_[static_cast<std::size_t>(c * v.rows() + j)] = h;
        v(j, c) = static_cast<double>(HalfToFloat(h));
      }
    }
  }

  // Stores the factors Compress left (rank columns) for the block (s, t); its tiles become views.
  void Emit(const Cluster& s, const Cluster& t, int rank) {
    const std::int64_t m = 3 * static_cast<std::int64_t>(s.size()), n = 3 * static_cast<std::int64_t>(t.size());
    std::int32_t off_u = 0, off_v = 0, scales = -1;
    if (half_) {
      scales = Offset();
      data.insert(data.end(), Sh_.begin(), Sh_.begin() + rank);
      off_u = HalfOffset();
      halves.insert(halves.end(), Uh_.begin(), Uh_.begin() + rank * m);
      off_v = HalfOffset();
      halves.insert(halves.end(), Vh_.begin(), Vh_.begin() + rank * n);
      ++totals.half_blocks;
      totals.factor_bytes += 2 * rank * (m + n) + 4 * rank;
    } else {
      off_u = Offset();
      for (int r = 0; r < rank; ++r)
        for (Eigen::Index i = 0; i < m; ++i) data.push_back(static_cast<float>(U_(i, r)));
      off_v = Offset();
      for (int r = 0; r < rank; ++r)
        for (Eigen::Index j = 0; j < n; ++j) data.push_back(static_cast<float>(V_(j, r)));
      totals.factor_bytes += 4 * rank * (m + n);
    }
    for (std::int32_t J = t.leaf_begin; J < t.leaf_end; ++J)
      for (std::int32_t I = s.leaf_begin; I < s.leaf_end; ++I) {
        CompressedTile& tile = tiles_[static_cast<std::size_t>(Compliance::PackedIndex(I, J))];
        tile.rank = rank;
        tile.scales = scales;
        tile.ld_u = static_cast<std::int32_t>(m);
        tile.ld_v = static_cast<std::int32_t>(n);
        tile.offset_u = off_u + 3 * (leaf_start_[I] - s.begin);
        tile.offset_v = off_v + 3 * (leaf_start_[J] - t.begin);
      }
    blocks_.push_back({s.begin, s.end, t.begin, t.end, rank});
    ++totals.low_rank_blocks;
    totals.rank_sum += rank;
    totals.max_rank = std::max(totals.max_rank, rank);
    totals.largest = std::max(totals.largest, m * n);
  }

  std::int32_t HalfOffset() const {
    if (halves.size() >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) / 2) {
      throw InputError("", 0, "compliance", "too large for the compressed storage (2^30 float16 factors)");
    }
    return static_cast<std::int32_t>(halves.size());
  }

  std::int32_t Offset() const {
    if (data.size() >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) / 2) {
      throw InputError("", 0, "compliance", "too large for the compressed storage (2^30 floats of factors)");
    }
    return static_cast<std::int32_t>(data.size());
  }

  const Compliance& exact_;
  const CompressionOptions& o_;
  const std::vector<Cluster>& cl_;
  const std::vector<std::int32_t>& slot_;
  const std::vector<std::int32_t>& leaf_start_;
  std::vector<CompressedTile>& tiles_;
  std::vector<CompressedBlockInfo>& blocks_;
  Eigen::MatrixXd A_, R_, U_, V_;
  std::vector<std::uint16_t> Uh_, Vh_;  // the last float16 candidate (column-major, scaled)
  std::vector<float> Sh_;
  bool half_ = false;                   // the last accepted candidate is float16
};

}  // namespace

CompressedBlocks CompressedBlocks::Build(std::span<const Eigen::Vector3d> positions_m, const Compliance& exact,
                                         const CompressionOptions& options, CompressionStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::int32_t N = exact.num_nodes();
  if (static_cast<std::int32_t>(positions_m.size()) != N) throw InputError("", 0, "positions", "one per compliance node");
  if (!(options.tolerance > 0.0 && options.tolerance < 1.0)) throw InputError("", 0, "tolerance", "must be in (0, 1)");
  if (options.leaf_nodes < 4 || options.leaf_nodes > 256) throw InputError("", 0, "leaf_nodes", "must be in 4..256");
  if (!(options.eta > 0.0 && options.eta <= 100.0)) {
    throw InputError("", 0, "eta", "must be in (0, 100] (admissibility min(diam s, diam t) <= eta dist(s, t))");
  }
  if (options.max_block_entries < 1) throw InputError("", 0, "max_block_entries", "must be positive");
  if (options.factor_precision != Precision::kFloat32 && options.factor_precision != Precision::kFloat16) {
    throw InputError("", 0, "factor_precision", "must be kFloat32 or kFloat16");
  }
  CompressedBlocks h;
  h.slot_of_pos_.resize(static_cast<std::size_t>(N));
  std::iota(h.slot_of_pos_.begin(), h.slot_of_pos_.end(), 0);
  std::vector<std::int32_t> sizes;
  std::vector<Cluster> clusters;
  if (N > 0) KdSplit(positions_m, h.slot_of_pos_.data(), 0, N, options.leaf_nodes, clusters, sizes);
  h.pos_.resize(static_cast<std::size_t>(N));
  for (std::int32_t p = 0; p < N; ++p) h.pos_[h.slot_of_pos_[p]] = p;
  h.leaf_start_.assign(1, 0);
  for (std::int32_t s : sizes) h.leaf_start_.push_back(h.leaf_start_.back() + s);
  h.leaf_of_pos_.resize(static_cast<std::size_t>(N));
  const std::int32_t L = h.num_leaves_();
  for (std::int32_t I = 0; I < L; ++I)
    for (std::int32_t p = h.leaf_start_[I]; p < h.leaf_start_[I + 1]; ++p) h.leaf_of_pos_[p] = I;

  h.tiles_.resize(static_cast<std::size_t>(Compliance::PackedIndex(0, L)));
  HBuilder b(exact, options, clusters, h.slot_of_pos_, h.leaf_start_, h.tiles_, h.blocks_);
  if (N > 0) b.Partition(0, 0);
  h.data_.assign(b.data.begin(), b.data.end());
  h.half_.assign(b.halves.begin(), b.halves.end());
  if (!h.half_.empty()) h.half_.resize(h.half_.size() + kHalfPadding, 0);  // the kernels' tails read past a column
  h.blocks_.shrink_to_fit();
  if (stats != nullptr) {
    stats->tiles = static_cast<std::int64_t>(h.tiles_.size());
    stats->low_rank_tiles = std::count_if(h.tiles_.begin(), h.tiles_.end(), [](const Tile& t) { return t.rank >= 0; });
    const auto& t = b.totals;
    stats->low_rank_blocks = t.low_rank_blocks;
    stats->mean_rank = t.low_rank_blocks > 0 ? static_cast<double>(t.rank_sum) / static_cast<double>(t.low_rank_blocks) : 0.0;
    stats->max_rank = t.max_rank;
    stats->largest_block_entries = t.largest;
    stats->dense_bytes = t.dense_floats * static_cast<std::int64_t>(sizeof(float));
    stats->factor_bytes = t.factor_bytes;
    stats->half_blocks = t.half_blocks;
    stats->table_bytes = static_cast<std::int64_t>(h.storage_bytes()) - stats->dense_bytes - stats->factor_bytes;
    stats->blocks_tried = b.tried;
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
  const std::int64_t a = p - leaf_start_[I], b = q - leaf_start_[J];
  const Tile& tile = tiles_[static_cast<std::size_t>(Compliance::PackedIndex(I, J))];
  const float* U = data_.data() + tile.offset_u;
  const float* V = data_.data() + tile.offset_v;
  Eigen::Matrix3d B;
  if (tile.rank >= 0 && tile.scales >= 0) {
    B = HalfBlock(tile, a, b);
  } else {
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) {
        if (tile.rank == kSymmetricTile) {
          B(r, c) = U[SymmetricIndex(3 * a + r, 3 * b + c)];
        } else if (tile.rank < 0) {
          B(r, c) = U[(3 * b + c) * tile.ld_u + 3 * a + r];
        } else {
          double s = 0.0;
          for (std::int64_t t = 0; t < tile.rank; ++t) {
            s += static_cast<double>(U[t * tile.ld_u + 3 * a + r]) * V[t * tile.ld_v + 3 * b + c];
          }
          B(r, c) = s;
        }
      }
  }
  if (transpose) B.transposeInPlace();
  return B;
}

namespace {

// Sum over the rank of scale_t U(3a.., t) V(3b.., t)^T from float16 factors: six conversions per
// rank (F16C where the CPU has it; Block() is on the force path, the software conversion made a
// 5-contact step ten times slower).
template <class Cvt>
HS_INLINE Eigen::Matrix3d HalfOuter(const std::uint16_t* U, std::int64_t ld_u, const std::uint16_t* V,
                                    std::int64_t ld_v, const float* scale, int rank, Cvt cvt) noexcept {
  double acc[9] = {};
  for (int t = 0; t < rank; ++t, U += ld_u, V += ld_v) {
    const double s = scale[t];
    const double u[3] = {s * cvt(U[0]), s * cvt(U[1]), s * cvt(U[2])};
    const double v[3] = {cvt(V[0]), cvt(V[1]), cvt(V[2])};
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) acc[3 * c + r] += u[r] * v[c];
  }
  Eigen::Matrix3d B;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) B(r, c) = acc[3 * c + r];
  return B;
}

__attribute__((target("f16c"))) Eigen::Matrix3d HalfOuterF16c(const std::uint16_t* U, std::int64_t ld_u,
                                                              const std::uint16_t* V, std::int64_t ld_v,
                                                              const float* scale, int rank) noexcept {
  return HalfOuter(U, ld_u, V, ld_v, scale, rank, [](std::uint16_t h) __attribute__((target("f16c"))) {
    return static_cast<double>(_cvtsh_ss(h));
  });
}

Eigen::Matrix3d HalfOuterPortable(const std::uint16_t* U, std::int64_t ld_u, const std::uint16_t* V,
                                  std::int64_t ld_v, const float* scale, int rank) noexcept {
  return HalfOuter(U, ld_u, V, ld_v, scale, rank,
                   [](std::uint16_t h) { return static_cast<double>(HalfToFloat(h)); });
}

}  // namespace

Eigen::Matrix3d CompressedBlocks::HalfBlock(const Tile& tile, std::int64_t a, std::int64_t b) const noexcept {
  const std::uint16_t* U = half_.data() + tile.offset_u + 3 * a;
  const std::uint16_t* V = half_.data() + tile.offset_v + 3 * b;
  const float* scale = data_.data() + tile.scales;
  return BestIsa() == Isa::kPortable ? HalfOuterPortable(U, tile.ld_u, V, tile.ld_v, scale, tile.rank)
                                     : HalfOuterF16c(U, tile.ld_u, V, tile.ld_v, scale, tile.rank);
}

namespace {

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
          num_leaves_(), tiles_.data(), data_.data(), half_.data()};
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
  return data_.size() * sizeof(float) + half_.size() * sizeof(std::uint16_t) + tiles_.size() * sizeof(Tile) + blocks_.size() * sizeof(CompressedBlockInfo) +
         (slot_of_pos_.size() + pos_.size() + leaf_of_pos_.size() + leaf_start_.size()) * sizeof(std::int32_t);
}

}  // namespace handshare::fem::detail
