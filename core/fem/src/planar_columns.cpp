// Planar column storage and its summation kernels: portable, AVX2 (+FMA, F16C) and AVX-512,
// chosen at run time (target attributes, no global -march), so the library runs on any x86-64.

#include "planar_columns.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

namespace handshare::fem::detail {

Isa BestIsa() noexcept {
  static const Isa isa = [] {
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) return Isa::kAvx512;
#if defined(__clang__) && __clang_major__ < 16
    // clang 14 cannot ask for f16c; every x86 processor with AVX2 has F16C.
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
#else
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("f16c")) {
#endif
      return Isa::kAvx2;
    }
    return Isa::kPortable;
  }();
  return isa;
}

bool HasAvx512Vnni() noexcept {
  static const bool has = BestIsa() == Isa::kAvx512 && __builtin_cpu_supports("avx512bw") &&
                          __builtin_cpu_supports("avx512vnni");
  return has;
}

const char* IsaName(Isa isa) noexcept {
  switch (isa) {
    case Isa::kAvx512: return "avx512";
    case Isa::kAvx2: return "avx2";
    case Isa::kPortable: return "portable";
  }
  return "?";
}

std::uint16_t FloatToHalf(float f) noexcept {
  std::uint32_t x;
  std::memcpy(&x, &f, 4);
  const std::uint32_t sign = (x >> 16) & 0x8000u;
  const std::uint32_t a = x & 0x7FFFFFFFu;
  if (a >= 0x7F800000u) return static_cast<std::uint16_t>(sign | (a > 0x7F800000u ? 0x7E00u : 0x7C00u));
  if (a >= 0x477FF000u) return static_cast<std::uint16_t>(sign | 0x7C00u);  // rounds past 65504
  if (a < 0x38800000u) {
    // Below 2^-14: subnormal half, units of 2^-24 (exact scaling, round to nearest even).
    float v;
    std::memcpy(&v, &a, 4);
    return static_cast<std::uint16_t>(sign | static_cast<std::uint32_t>(std::nearbyint(v * 16777216.0f)));
  }
  // Rebias the exponent (127 -> 15) and round the mantissa from 23 to 10 bits, ties to even.
  const std::uint32_t r = a + 0xFFFu + ((a >> 13) & 1u);
  return static_cast<std::uint16_t>(sign | ((r - 0x38000000u) >> 13));
}

float HalfToFloat(std::uint16_t h) noexcept {
  const std::uint32_t e = (h >> 10) & 0x1Fu, m = h & 0x3FFu;
  float v;
  if (e == 0) {
    v = static_cast<float>(m) * (1.0f / 16777216.0f);
  } else if (e == 31) {
    v = m != 0 ? std::nanf("") : HUGE_VALF;
  } else {
    const std::uint32_t x = ((e + 112u) << 23) | (m << 13);
    std::memcpy(&v, &x, 4);
  }
  return (h & 0x8000u) ? -v : v;
}

void PlanarColumns::Build(std::int32_t rows, std::int32_t cols, PlanarType type,
                          const std::function<Eigen::Matrix3d(std::int32_t, std::int32_t)>& block) {
  rows_ = rows;
  cols_ = cols;
  type_ = type;
  const std::int64_t chunks = NumChunks(rows);
  stride_ = chunks * kChunkScalars;
  if (type == PlanarType::kInt16) stride_ = (stride_ + 31) / 32 * 32;  // 64-byte columns
  const auto total = static_cast<std::size_t>(stride_ * cols);
  f64_.clear();
  f32_.clear();
  f16_.clear();
  i16_.clear();
  scale_.clear();
  double chunk[kChunkScalars];
  if (type == PlanarType::kFloat64) f64_.assign(total, 0.0);
  if (type == PlanarType::kFloat32) f32_.assign(total, 0.0f);
  if (type == PlanarType::kFloat16) f16_.assign(total, 0);
  if (type == PlanarType::kInt16) i16_.assign(total, 0);
  if (type == PlanarType::kFloat16 || type == PlanarType::kInt16) {
    scale_.assign(static_cast<std::size_t>(chunks * cols), 0.0f);
  }
  for (std::int32_t k = 0; k < cols; ++k) {
    for (std::int64_t q = 0; q < chunks; ++q) {
      std::fill(std::begin(chunk), std::end(chunk), 0.0);
      for (int l = 0; l < kChunkNodes; ++l) {
        const std::int64_t n = q * kChunkNodes + l;
        if (n >= rows) break;
        const Eigen::Matrix3d B = block(static_cast<std::int32_t>(n), k);
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) chunk[16 * (3 * c + r) + l] = B(r, c);
      }
      const std::size_t at = static_cast<std::size_t>(k * stride_ + q * kChunkScalars);
      if (type == PlanarType::kFloat64) {
        std::copy(std::begin(chunk), std::end(chunk), f64_.begin() + static_cast<std::ptrdiff_t>(at));
        continue;
      }
      if (type == PlanarType::kFloat32) {
        for (int i = 0; i < kChunkScalars; ++i) f32_[at + i] = static_cast<float>(chunk[i]);
        continue;
      }
      double amax = 0.0;
      for (double v : chunk) amax = std::max(amax, std::abs(v));
      if (type == PlanarType::kFloat16) {
        // Scale so that the largest entry maps to 1 (full half precision down to 2^-14 of it).
        const float s = amax > 0.0 ? static_cast<float>(amax) : 1.0f;
        scale_[static_cast<std::size_t>(k * chunks + q)] = s;
        for (int i = 0; i < kChunkScalars; ++i) f16_[at + i] = FloatToHalf(static_cast<float>(chunk[i] / s));
      } else {
        // The largest entry maps to 32767; the float scale is what the kernels multiply by.
        const float s = amax > 0.0 ? static_cast<float>(amax / 32767.0) : 1.0f;
        scale_[static_cast<std::size_t>(k * chunks + q)] = s;
        std::int16_t* col = i16_.data() + k * stride_;
        for (int l = 0; l < kChunkNodes; ++l)
          for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) {
              const double v = std::nearbyint(chunk[16 * (3 * c + r) + l] / static_cast<double>(s));
              col[Int16Offset(q, r, c, l)] = static_cast<std::int16_t>(std::clamp(v, -32767.0, 32767.0));
            }
      }
    }
  }
}

Isa PlanarColumns::KernelIsa(Isa requested) const noexcept {
  if (type_ == PlanarType::kFloat64) return Isa::kPortable;  // float64: portable (compiler-vectorized)
  if (type_ == PlanarType::kInt16 && requested == Isa::kAvx512 && !HasAvx512Vnni()) return Isa::kAvx2;
  return requested;
}

Eigen::Matrix3d PlanarColumns::Get(std::int32_t n, std::int32_t k) const noexcept {
  const std::int64_t chunks = NumChunks(rows_);
  const std::int64_t q = n / kChunkNodes, l = n % kChunkNodes;
  Eigen::Matrix3d B;
  if (type_ == PlanarType::kInt16) {
    const std::int16_t* col = i16_.data() + k * stride_;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        B(r, c) = static_cast<double>(col[Int16Offset(q, r, c, static_cast<int>(l))]) *
                  scale_[static_cast<std::size_t>(k * chunks + q)];
    return B;
  }
  const std::size_t at = static_cast<std::size_t>(k * stride_ + q * kChunkScalars + l);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) {
      const std::size_t i = at + 16 * (3 * c + r);
      switch (type_) {
        case PlanarType::kFloat64: B(r, c) = f64_[i]; break;
        case PlanarType::kFloat32: B(r, c) = f32_[i]; break;
        case PlanarType::kFloat16:
          B(r, c) = static_cast<double>(HalfToFloat(f16_[i])) * scale_[static_cast<std::size_t>(k * chunks + q)];
          break;
        case PlanarType::kInt16: break;  // above
      }
    }
  return B;
}

namespace {

constexpr int kGroup = 32;  // columns summed per pass over the output

// One pass: out (+)= sum over the group's columns. Portable: any storage type.
template <class S>
void SumPortable(const S* const* col, const float* const* scale, const double* x, int m, std::int32_t rows,
                 Eigen::Vector3d* out, bool accumulate) noexcept {
  const std::int64_t chunks = NumChunks(rows);
  for (std::int64_t q = 0; q < chunks; ++q) {
    double u[3][kChunkNodes] = {};
    for (int j = 0; j < m; ++j) {
      const S* c = col[j] + q * kChunkScalars;
      double s = 1.0;
      if (scale != nullptr) s = scale[j][q];
      for (int p = 0; p < 9; ++p) {
        const double xv = x[3 * j + p / 3] * s;
        for (int l = 0; l < kChunkNodes; ++l) {
          if constexpr (sizeof(S) == 2) {
            u[p % 3][l] += static_cast<double>(HalfToFloat(c[16 * p + l])) * xv;
          } else {
            u[p % 3][l] += static_cast<double>(c[16 * p + l]) * xv;
          }
        }
      }
    }
    const std::int64_t n0 = q * kChunkNodes;
    for (int l = 0; l < kChunkNodes && n0 + l < rows; ++l) {
      double* o = out[n0 + l].data();
      for (int r = 0; r < 3; ++r) o[r] = accumulate ? o[r] + u[r][l] : u[r][l];
    }
  }
}

// Stores 16 nodes' planar sums (x, y, z lanes) into out[0..count).
inline void StorePlanar(const float* ux, const float* uy, const float* uz, int count, Eigen::Vector3d* out,
                        bool accumulate) noexcept {
  for (int l = 0; l < count; ++l) {
    double* o = out[l].data();
    if (accumulate) {
      o[0] += ux[l];
      o[1] += uy[l];
      o[2] += uz[l];
    } else {
      o[0] = ux[l];
      o[1] = uy[l];
      o[2] = uz[l];
    }
  }
}

// int16: each column's load as integer pairs for the dot products, w01 = (g_0, g_1) and
// w2 = (g_2, 0) in 16-bit halves, g_c = round(x_c / step), step = max_c |x_c| / G with
// G = floor((2^31 - 1) / (3 * 32767)) = 21845: one column's three products per lane cannot
// overflow int32. A column's int32 sums are turned to float at once, times scale(chunk) * step,
// and summed in float like the other kernels. Non-finite loads give step NaN (a NaN field, as
// with the float kernels).
struct Int16Loads {
  std::int32_t w01[kGroup];
  std::int32_t w2[kGroup];
  float step[kGroup];
};

void QuantizeLoads(const double* x, int m, Int16Loads& out) noexcept {
  constexpr double G = 21845.0;
  static_assert(3.0 * 32767.0 * G <= 2147483647.0, "one column's sum must fit in int32");
  for (int j = 0; j < m; ++j) {
    const double* xj = x + 3 * j;
    const double amax = std::max({std::abs(xj[0]), std::abs(xj[1]), std::abs(xj[2])});
    const bool finite = std::isfinite(xj[0]) && std::isfinite(xj[1]) && std::isfinite(xj[2]);
    std::int32_t g[3] = {0, 0, 0};
    double step = 0.0;
    if (!finite) {
      step = std::numeric_limits<double>::quiet_NaN();
    } else if (amax > 0.0) {
      step = amax / G;
      for (int c = 0; c < 3; ++c) g[c] = static_cast<std::int32_t>(std::clamp(std::nearbyint(xj[c] / step), -G, G));
    }
    out.step[j] = static_cast<float>(step);
    out.w01[j] = static_cast<std::int32_t>(static_cast<std::uint32_t>(static_cast<std::uint16_t>(g[0])) |
                                           (static_cast<std::uint32_t>(static_cast<std::uint16_t>(g[1])) << 16));
    out.w2[j] = static_cast<std::int32_t>(static_cast<std::uint16_t>(g[2]));
  }
}

std::int32_t Low(std::int32_t w) noexcept { return static_cast<std::int16_t>(static_cast<std::uint32_t>(w) & 0xFFFFu); }
std::int32_t High(std::int32_t w) noexcept { return static_cast<std::int16_t>(static_cast<std::uint32_t>(w) >> 16); }

// Portable int16: the same integer sums as the SIMD kernels (exact) and the same float
// operations in the same order (a fused multiply-add per column), so the results agree.
void SumInt16Portable(const std::int16_t* const* col, const float* const* scale, const Int16Loads& g, int m,
                      std::int32_t rows, Eigen::Vector3d* out, bool accumulate) noexcept {
  const std::int64_t chunks = NumChunks(rows);
  for (std::int64_t q = 0; q < chunks; ++q) {
    float u[3][kChunkNodes] = {};
    for (int j = 0; j < m; ++j) {
      const std::int32_t g0 = Low(g.w01[j]), g1 = High(g.w01[j]), g2 = Low(g.w2[j]);
      const float f = scale[j][q] * g.step[j];
      for (int r = 0; r < 3; ++r)
        for (int l = 0; l < kChunkNodes; ++l) {
          const std::int32_t acc = col[j][Int16Offset(q, r, 0, l)] * g0 + col[j][Int16Offset(q, r, 1, l)] * g1 +
                                   col[j][Int16Offset(q, r, 2, l)] * g2;
          u[r][l] = std::fma(static_cast<float>(acc), f, u[r][l]);
        }
    }
    const int count = static_cast<int>(std::min<std::int64_t>(kChunkNodes, rows - q * kChunkNodes));
    StorePlanar(u[0], u[1], u[2], count, out + q * kChunkNodes, accumulate);
  }
}

#define HS_AVX2 __attribute__((target("avx2,fma,f16c")))
#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma,f16c")))
#define HS_AVX512VNNI __attribute__((target("avx512f,avx512vl,avx512bw,avx512vnni,fma,f16c")))

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"


template <bool kHalf>
HS_AVX2 void SumAvx2(const void* const* col, const float* const* scale, const double* x, int m, std::int32_t rows,
                     Eigen::Vector3d* out, bool accumulate) noexcept {
  const std::int64_t chunks = NumChunks(rows);
  float fx[3 * kGroup];
  for (int i = 0; i < 3 * m; ++i) fx[i] = static_cast<float>(x[i]);
  for (std::int64_t q = 0; q < chunks; ++q) {
    __m256 u[3][2];
    for (auto& r : u) r[0] = r[1] = _mm256_setzero_ps();
    for (int j = 0; j < m; ++j) {
      const float s = kHalf ? scale[j][q] : 1.0f;
      for (int c = 0; c < 3; ++c) {
        const __m256 f = _mm256_set1_ps(fx[3 * j + c] * s);
        for (int r = 0; r < 3; ++r)
          for (int h = 0; h < 2; ++h) {
            const std::int64_t at = q * kChunkScalars + 16 * (3 * c + r) + 8 * h;
            __m256 v;
            if constexpr (kHalf) {
              v = _mm256_cvtph_ps(_mm_load_si128(reinterpret_cast<const __m128i*>(static_cast<const std::uint16_t*>(col[j]) + at)));
            } else {
              v = _mm256_load_ps(static_cast<const float*>(col[j]) + at);
            }
            u[r][h] = _mm256_fmadd_ps(v, f, u[r][h]);
          }
      }
    }
    alignas(32) float t[3][16];
    for (int r = 0; r < 3; ++r) {
      _mm256_store_ps(t[r], u[r][0]);
      _mm256_store_ps(t[r] + 8, u[r][1]);
    }
    const int count = static_cast<int>(std::min<std::int64_t>(kChunkNodes, rows - q * kChunkNodes));
    StorePlanar(t[0], t[1], t[2], count, out + q * kChunkNodes, accumulate);
  }
}

// int16 without VNNI: vpmaddwd (8 lanes of a0 b0 + a1 b1) and an add.
HS_AVX2 void SumInt16Avx2(const std::int16_t* const* col, const float* const* scale, const Int16Loads& g, int m,
                          std::int32_t rows, Eigen::Vector3d* out, bool accumulate) noexcept {
  const std::int64_t chunks = NumChunks(rows);
  for (std::int64_t q = 0; q < chunks; ++q) {
    __m256 u[3][2];
    for (auto& r : u) r[0] = r[1] = _mm256_setzero_ps();
    for (int j = 0; j < m; ++j) {
      const __m256i b01 = _mm256_set1_epi32(g.w01[j]), b2 = _mm256_set1_epi32(g.w2[j]);
      const __m256 f = _mm256_set1_ps(scale[j][q] * g.step[j]);
      for (int r = 0; r < 3; ++r)
        for (int h = 0; h < 2; ++h) {
          const std::int16_t* pair = col[j] + Int16Offset(q, r, 0, 8 * h);
          const std::int16_t* single = col[j] + Int16Offset(q, r, 2, 8 * h);
          const __m256i p = _mm256_load_si256(reinterpret_cast<const __m256i*>(pair));
          const __m256i s = _mm256_cvtepu16_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(single)));
          const __m256i acc = _mm256_add_epi32(_mm256_madd_epi16(p, b01), _mm256_madd_epi16(s, b2));
          u[r][h] = _mm256_fmadd_ps(_mm256_cvtepi32_ps(acc), f, u[r][h]);
        }
    }
    alignas(32) float t[3][16];
    for (int r = 0; r < 3; ++r)
      for (int h = 0; h < 2; ++h) _mm256_store_ps(t[r] + 8 * h, u[r][h]);
    const int count = static_cast<int>(std::min<std::int64_t>(kChunkNodes, rows - q * kChunkNodes));
    StorePlanar(t[0], t[1], t[2], count, out + q * kChunkNodes, accumulate);
  }
}

// Interleaves (x, y, z) lanes of 16 nodes into 48 doubles: two-source permutes pick x and y,
// then z, for each of the three 16-float output vectors.
struct Interleave {
  __m512i a[3], b[3];
  Interleave() noexcept {
    alignas(64) std::int32_t ia[16], ib[16];
    for (int v = 0; v < 3; ++v) {
      for (int i = 0; i < 16; ++i) {
        const int g = 16 * v + i, l = g / 3, r = g % 3;
        ia[i] = r == 0 ? l : (r == 1 ? 16 + l : 0);
        ib[i] = r == 2 ? 16 + l : i;
      }
      std::memcpy(&a[v], ia, 64);
      std::memcpy(&b[v], ib, 64);
    }
  }
};

// Chunk q's sums (x, y, z lanes of 16 nodes) into out, interleaved and widened to double.
HS_AVX512 inline void StoreChunk(const Interleave& il, __m512 ux, __m512 uy, __m512 uz, std::int64_t q,
                                 std::int32_t rows, Eigen::Vector3d* out, bool accumulate) noexcept {
  const std::int64_t n0 = q * kChunkNodes;
  if (n0 + kChunkNodes <= rows) {
    double* o = out[n0].data();
    for (int v = 0; v < 3; ++v) {
      const __m512 t = _mm512_permutex2var_ps(_mm512_permutex2var_ps(ux, il.a[v], uy), il.b[v], uz);
      __m512d lo = _mm512_cvtps_pd(_mm512_castps512_ps256(t));
      __m512d hi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(t), 1)));
      if (accumulate) {
        lo = _mm512_add_pd(lo, _mm512_loadu_pd(o + 16 * v));
        hi = _mm512_add_pd(hi, _mm512_loadu_pd(o + 16 * v + 8));
      }
      _mm512_storeu_pd(o + 16 * v, lo);
      _mm512_storeu_pd(o + 16 * v + 8, hi);
    }
  } else {
    alignas(64) float t[3][16];
    _mm512_store_ps(t[0], ux);
    _mm512_store_ps(t[1], uy);
    _mm512_store_ps(t[2], uz);
    StorePlanar(t[0], t[1], t[2], static_cast<int>(rows - n0), out + n0, accumulate);
  }
}

template <bool kHalf>
HS_AVX512 void SumAvx512(const void* const* col, const float* const* scale, const double* x, int m,
                         std::int32_t rows, Eigen::Vector3d* out, bool accumulate) noexcept {
  static const Interleave il;
  const std::int64_t chunks = NumChunks(rows);
  float fx[3 * kGroup];
  for (int i = 0; i < 3 * m; ++i) fx[i] = static_cast<float>(x[i]);
  for (std::int64_t q = 0; q < chunks; ++q) {
    __m512 ux = _mm512_setzero_ps(), uy = _mm512_setzero_ps(), uz = _mm512_setzero_ps();
    for (int j = 0; j < m; ++j) {
      const float s = kHalf ? scale[j][q] : 1.0f;
      const std::int64_t base = q * kChunkScalars;
#define HS_LOADP(p)                                                                                      \
  (kHalf ? _mm512_cvtph_ps(_mm256_load_si256(                                                          \
               reinterpret_cast<const __m256i*>(static_cast<const std::uint16_t*>(col[j]) + base + 16 * (p)))) \
         : _mm512_load_ps(static_cast<const float*>(col[j]) + base + 16 * (p)))
      const __m512 f0 = _mm512_set1_ps(fx[3 * j] * s), f1 = _mm512_set1_ps(fx[3 * j + 1] * s),
                   f2 = _mm512_set1_ps(fx[3 * j + 2] * s);
      ux = _mm512_fmadd_ps(HS_LOADP(0), f0, ux);
      uy = _mm512_fmadd_ps(HS_LOADP(1), f0, uy);
      uz = _mm512_fmadd_ps(HS_LOADP(2), f0, uz);
      ux = _mm512_fmadd_ps(HS_LOADP(3), f1, ux);
      uy = _mm512_fmadd_ps(HS_LOADP(4), f1, uy);
      uz = _mm512_fmadd_ps(HS_LOADP(5), f1, uz);
      ux = _mm512_fmadd_ps(HS_LOADP(6), f2, ux);
      uy = _mm512_fmadd_ps(HS_LOADP(7), f2, uy);
      uz = _mm512_fmadd_ps(HS_LOADP(8), f2, uz);
#undef HS_LOADP
    }
    StoreChunk(il, ux, uy, uz, q, rows, out, accumulate);
  }
}

// int16 with AVX-512 VNNI: per column and chunk, three vpdpwssd on the pair planes and three on
// the zero-extended single planes (each (X(r, 2), 0) against (g_2, 0)), then one conversion and
// FMA per row into the float sums.
HS_AVX512VNNI void SumInt16Avx512(const std::int16_t* const* col, const float* const* scale, const Int16Loads& g,
                                  int m, std::int32_t rows, Eigen::Vector3d* out, bool accumulate) noexcept {
  static const Interleave il;
  const std::int64_t chunks = NumChunks(rows);
  const __m512i zero = _mm512_setzero_si512();
  for (std::int64_t q = 0; q < chunks; ++q) {
    __m512 ux = _mm512_setzero_ps(), uy = _mm512_setzero_ps(), uz = _mm512_setzero_ps();
    const std::int64_t pairs = Int16Offset(q, 0, 0, 0), singles = Int16Offset(q, 0, 2, 0);
    for (int j = 0; j < m; ++j) {
      const std::int16_t* p = col[j] + pairs;
      const std::int16_t* s = col[j] + singles;
      const __m512i b01 = _mm512_set1_epi32(g.w01[j]), b2 = _mm512_set1_epi32(g.w2[j]);
      const __m512 f = _mm512_set1_ps(scale[j][q] * g.step[j]);
      __m512i ax = _mm512_dpwssd_epi32(zero, _mm512_load_si512(p), b01);
      __m512i ay = _mm512_dpwssd_epi32(zero, _mm512_load_si512(p + 32), b01);
      __m512i az = _mm512_dpwssd_epi32(zero, _mm512_load_si512(p + 64), b01);
      ax = _mm512_dpwssd_epi32(ax, _mm512_cvtepu16_epi32(_mm256_load_si256(reinterpret_cast<const __m256i*>(s))), b2);
      ay = _mm512_dpwssd_epi32(ay, _mm512_cvtepu16_epi32(_mm256_load_si256(reinterpret_cast<const __m256i*>(s + 16))), b2);
      az = _mm512_dpwssd_epi32(az, _mm512_cvtepu16_epi32(_mm256_load_si256(reinterpret_cast<const __m256i*>(s + 32))), b2);
      ux = _mm512_fmadd_ps(_mm512_cvtepi32_ps(ax), f, ux);
      uy = _mm512_fmadd_ps(_mm512_cvtepi32_ps(ay), f, uy);
      uz = _mm512_fmadd_ps(_mm512_cvtepi32_ps(az), f, uz);
    }
    StoreChunk(il, ux, uy, uz, q, rows, out, accumulate);
  }
}

#pragma GCC diagnostic pop

}  // namespace

void PlanarColumns::SumColumns(std::span<const std::int32_t> k, std::span<const Eigen::Vector3d> x,
                               Eigen::Vector3d* out, Isa isa) const noexcept {
  struct Ctx {
    std::span<const std::int32_t> k;
    std::span<const Eigen::Vector3d> x;
  } ctx{k, x};
  Sum(std::min(k.size(), x.size()),
      [](const void* c, std::size_t i, const Eigen::Vector3d** xi) {
        const Ctx& t = *static_cast<const Ctx*>(c);
        *xi = &t.x[i];
        return t.k[i];
      },
      &ctx, out, isa);
}

void PlanarColumns::SumColumns(std::span<const NodeLoad> loads, Eigen::Vector3d* out, Isa isa) const noexcept {
  Sum(loads.size(),
      [](const void* c, std::size_t i, const Eigen::Vector3d** xi) {
        const NodeLoad& l = static_cast<const NodeLoad*>(c)[i];
        *xi = &l.f_N;
        return l.slot;
      },
      loads.data(), out, isa);
}

void PlanarColumns::Sum(std::size_t count, Getter get, const void* ctx, Eigen::Vector3d* out,
                        Isa isa) const noexcept {
  const std::int64_t chunks = NumChunks(rows_);
  const void* col[kGroup];
  const float* scale[kGroup];
  double xs[3 * kGroup];
  bool accumulate = false;
  std::size_t i = 0;
  isa = KernelIsa(isa);
  const bool int16 = type_ == PlanarType::kInt16;
  auto flush = [&](int m) {
    if (m == 0 && accumulate) return;
    if (int16) {
      Int16Loads g;
      QuantizeLoads(xs, m, g);
      const auto* c16 = reinterpret_cast<const std::int16_t* const*>(col);
      switch (isa) {
        case Isa::kAvx512: SumInt16Avx512(c16, scale, g, m, rows_, out, accumulate); break;
        case Isa::kAvx2: SumInt16Avx2(c16, scale, g, m, rows_, out, accumulate); break;
        case Isa::kPortable: SumInt16Portable(c16, scale, g, m, rows_, out, accumulate); break;
      }
      accumulate = true;
      return;
    }
    switch (isa) {
      case Isa::kAvx512:
        if (type_ == PlanarType::kFloat16) {
          SumAvx512<true>(col, scale, xs, m, rows_, out, accumulate);
        } else {
          SumAvx512<false>(col, scale, xs, m, rows_, out, accumulate);
        }
        break;
      case Isa::kAvx2:
        if (type_ == PlanarType::kFloat16) {
          SumAvx2<true>(col, scale, xs, m, rows_, out, accumulate);
        } else {
          SumAvx2<false>(col, scale, xs, m, rows_, out, accumulate);
        }
        break;
      case Isa::kPortable:
        if (type_ == PlanarType::kFloat64) {
          SumPortable(reinterpret_cast<const double* const*>(col), nullptr, xs, m, rows_, out, accumulate);
        } else if (type_ == PlanarType::kFloat32) {
          SumPortable(reinterpret_cast<const float* const*>(col), nullptr, xs, m, rows_, out, accumulate);
        } else {
          SumPortable(reinterpret_cast<const std::uint16_t* const*>(col), scale, xs, m, rows_, out, accumulate);
        }
        break;
    }
    accumulate = true;
  };
  int m = 0;
  for (; i < count; ++i) {
    const Eigen::Vector3d* xi = nullptr;
    const std::int32_t ki = get(ctx, i, &xi);
    if (ki < 0 || ki >= cols_) continue;
    const std::int64_t at = ki * stride_;
    switch (type_) {
      case PlanarType::kFloat64: col[m] = f64_.data() + at; break;
      case PlanarType::kFloat32: col[m] = f32_.data() + at; break;
      case PlanarType::kFloat16:
        col[m] = f16_.data() + at;
        scale[m] = scale_.data() + ki * chunks;
        break;
      case PlanarType::kInt16:
        col[m] = i16_.data() + at;
        scale[m] = scale_.data() + ki * chunks;
        break;
    }
    for (int c = 0; c < 3; ++c) xs[3 * m + c] = (*xi)[c];
    if (++m == kGroup) {
      flush(m);
      m = 0;
    }
  }
  flush(m);
}

}  // namespace handshare::fem::detail
