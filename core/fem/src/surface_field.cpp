// Surface displacement kernels: u_n = sum_j C_{n,k_j} f_j on the packed symmetric storage, and
// u_n = sum_j T_{n,k_j} e_j on full column storage (the paper's T^d). Memory-bound; the AVX-512
// versions (float32 only) are selected at run time, so the library still runs on any x86-64.

#include "handshare/fem/surface_field.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cstring>
#include <utility>

#include "handshare/fem/error.hpp"
#include "compressed_blocks.hpp"
#include "kernels.hpp"
#include "planar_columns.hpp"

namespace handshare::fem {

bool CpuHasAvx512() noexcept {
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return has;
}

namespace {

// ---- portable kernels

// One pass per load: the part n <= k of packed column k is contiguous; for n > k the block
// (k, n) sits in packed column n at row k, 9 (n + 1) scalars further on for every n.
template <class S>
void ApplyPackedGeneric(const S* data, std::int32_t N, std::span<const NodeLoad> loads,
                        Eigen::Vector3d* out) noexcept {
  for (std::int32_t n = 0; n < N; ++n) out[n].setZero();
  for (const NodeLoad& l : loads) {
    const std::int32_t k = l.slot;
    if (k < 0 || k >= N) continue;
    const double f0 = l.f_N[0], f1 = l.f_N[1], f2 = l.f_N[2];
    const S* blk = data + 9 * Compliance::PackedIndex(0, k);
    for (std::int32_t n = 0; n <= k; ++n, blk += 9) {  // C_nk, column-major
      double* o = out[n].data();
      o[0] += blk[0] * f0 + blk[3] * f1 + blk[6] * f2;
      o[1] += blk[1] * f0 + blk[4] * f1 + blk[7] * f2;
      o[2] += blk[2] * f0 + blk[5] * f1 + blk[8] * f2;
    }
    if (k + 1 >= N) continue;
    const S* b = data + 9 * Compliance::PackedIndex(k, k + 1);
    for (std::int32_t n = k + 1; n < N; ++n) {  // C_nk = (stored C_kn)^T
      double* o = out[n].data();
      o[0] += b[0] * f0 + b[1] * f1 + b[2] * f2;
      o[1] += b[3] * f0 + b[4] * f1 + b[5] * f2;
      o[2] += b[6] * f0 + b[7] * f1 + b[8] * f2;
      b += 9 * static_cast<std::int64_t>(n + 1);
    }
  }
}

// ---- AVX-512 kernels (float32 storage)
//
// "Expanded" accumulation: E[9n + e] += X[9n + e] * f_{e / 3} over a contiguous run of
// column-major blocks is a plain element-wise FMA with a period-9 pattern (9 registers cover
// lcm(9, 16) = 144 floats); the 9 -> 3 reduction u_r = E[r] + E[3 + r] + E[6 + r] is done once
// per node at the end.

#define HS_AVX512 __attribute__((target("avx512f,avx512vl,fma")))

// GCC 12 reports its own _mm512_undefined_* placeholders inside the intrinsics as
// "may be used uninitialized" (a known false positive); silence it for these kernels only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

HS_AVX512 void ExpandedFma(float* E, const float* x, std::int64_t len, float f0, float f1,
                           float f2) noexcept {
  // P[t] lane l = f_{((16 t + l) mod 9) / 3}: built by permuting (f0, f1, f2).
  const __m512 f = _mm512_setr_ps(f0, f1, f2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
  __m512 P[9];
  for (int t = 0; t < 9; ++t) {
    alignas(64) std::int32_t idx[16];
    for (int l = 0; l < 16; ++l) idx[l] = ((16 * t + l) % 9) / 3;
    P[t] = _mm512_permutexvar_ps(_mm512_load_si512(idx), f);
  }
  std::int64_t i = 0;
  for (; i + 144 <= len; i += 144) {
    for (int t = 0; t < 9; ++t) {
      const __m512 acc = _mm512_load_ps(E + i + 16 * t);  // E is 64-byte aligned
      _mm512_store_ps(E + i + 16 * t, _mm512_fmadd_ps(_mm512_loadu_ps(x + i + 16 * t), P[t], acc));
    }
  }
  for (int t = 0; i < len; i += 16, ++t) {
    const std::int64_t rest = len - i;
    const __mmask16 m = rest >= 16 ? static_cast<__mmask16>(0xFFFF) : static_cast<__mmask16>((1u << rest) - 1u);
    const __m512 acc = _mm512_maskz_loadu_ps(m, E + i);
    _mm512_mask_storeu_ps(E + i, m, _mm512_fmadd_ps(_mm512_maskz_loadu_ps(m, x + i), P[t], acc));
  }
}

// out[n] (+)= reduce(E[9n .. 9n+8] + transpose(strided partial sums)).
HS_AVX512 void ApplyPackedAvx512(const float* data, std::int32_t N, std::span<const NodeLoad> all,
                                 Eigen::Vector3d* out, float* E) noexcept {
  constexpr int kChunk = 32;
  const __mmask16 m9 = 0x1FF;
  const __m512i transpose = _mm512_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i sh3 = _mm512_setr_epi32(3, 4, 5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
  const __m512i sh6 = _mm512_setr_epi32(6, 7, 8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
  for (std::int32_t n = 0; n < N; ++n) out[n].setZero();
  for (std::size_t c0 = 0; c0 < all.size(); c0 += kChunk) {
    // This chunk's loads, sorted by slot (insertion sort: m is small).
    std::int32_t k[kChunk];
    __m512 pstr[kChunk];
    int m = 0;
    std::memset(E, 0, sizeof(float) * 9 * static_cast<std::size_t>(N));
    for (std::size_t i = c0; i < std::min(all.size(), c0 + kChunk); ++i) {
      const NodeLoad& l = all[i];
      if (l.slot < 0 || l.slot >= N) continue;
      const float f0 = static_cast<float>(l.f_N[0]), f1 = static_cast<float>(l.f_N[1]),
                  f2 = static_cast<float>(l.f_N[2]);
      // n <= k: contiguous, expanded accumulation.
      ExpandedFma(E, data + 9 * Compliance::PackedIndex(0, l.slot), 9ll * (l.slot + 1), f0, f1, f2);
      // n > k: stored C_kn (column-major) times f: lane 3r + a multiplies f_a.
      const __m512 p = _mm512_setr_ps(f0, f1, f2, f0, f1, f2, f0, f1, f2, 0, 0, 0, 0, 0, 0, 0);
      int q = m++;
      while (q > 0 && k[q - 1] > l.slot) {
        k[q] = k[q - 1];
        pstr[q] = pstr[q - 1];
        --q;
      }
      k[q] = l.slot;
      pstr[q] = p;
    }
    int strided = 0;  // loads [0, strided) have k < n
    for (std::int32_t n = 0; n < N; ++n) {
      while (strided < m && k[strided] < n) ++strided;
      __m512 zs = _mm512_setzero_ps();
      const float* coln = data + 9 * Compliance::PackedIndex(0, n);
      for (int q = 0; q < strided; ++q) {
        zs = _mm512_fmadd_ps(_mm512_maskz_loadu_ps(m9, coln + 9 * k[q]), pstr[q], zs);
      }
      const __m512 z = _mm512_add_ps(_mm512_maskz_loadu_ps(m9, E + 9 * static_cast<std::size_t>(n)),
                                     _mm512_permutexvar_ps(transpose, zs));
      const __m512 s = _mm512_add_ps(z, _mm512_add_ps(_mm512_permutexvar_ps(sh3, z), _mm512_permutexvar_ps(sh6, z)));
      const __m256d d = _mm256_cvtps_pd(_mm512_castps512_ps128(s));
      double* o = out[n].data();
      _mm256_mask_storeu_pd(o, 0x7, _mm256_add_pd(d, _mm256_maskz_loadu_pd(0x7, o)));
    }
  }
}

#pragma GCC diagnostic pop

}  // namespace

namespace detail {

float* Align64(std::vector<float>& v) noexcept {
  auto p = reinterpret_cast<std::uintptr_t>(v.data());
  return reinterpret_cast<float*>((p + 63) & ~static_cast<std::uintptr_t>(63));
}

}  // namespace detail

SurfaceField::SurfaceField(std::shared_ptr<const Compliance> compliance, bool allow_simd)
    : SurfaceField(std::move(compliance), SurfaceFieldOptions{.allow_simd = allow_simd}) {}

SurfaceField::SurfaceField(std::shared_ptr<const Compliance> compliance, const SurfaceFieldOptions& options)
    : compliance_(std::move(compliance)), options_(options) {
  if (!compliance_) throw InputError("", 0, "compliance", "null");
  const Compliance& C = *compliance_;
  const detail::Isa best = options.allow_simd ? detail::BestIsa() : detail::Isa::kPortable;
  if (options.layout == SurfaceFieldLayout::kColumns) {
    detail::PlanarType type = detail::PlanarType::kFloat32;
    switch (options.precision) {
      case Precision::kFloat64: type = detail::PlanarType::kFloat64; break;
      case Precision::kFloat32: type = detail::PlanarType::kFloat32; break;
      case Precision::kFloat16: type = detail::PlanarType::kFloat16; break;
      case Precision::kInt16: type = detail::PlanarType::kInt16; break;
      default: throw InputError("", 0, "precision", "must be int16, float16, float32 or float64");
    }
    columns_ = std::make_unique<detail::PlanarColumns>();
    columns_->Build(C.num_nodes(), C.num_nodes(), type,
                    [&](std::int32_t n, std::int32_t k) { return C.Block(n, k); });
    isa_ = static_cast<std::uint8_t>(columns_->KernelIsa(best));
  } else if (C.storage() == ComplianceStorage::kCompressed) {
    isa_ = static_cast<std::uint8_t>(best);
    expanded_.assign(C.compressed()->scratch_floats(), 0.0f);
  } else {
    // Packed: the AVX-512 kernel for float32, else portable.
    const bool simd = best == detail::Isa::kAvx512 && C.precision() == Precision::kFloat32;
    isa_ = static_cast<std::uint8_t>(simd ? detail::Isa::kAvx512 : detail::Isa::kPortable);
    if (simd) expanded_.assign(9 * static_cast<std::size_t>(C.num_nodes()) + 32, 0.0f);
  }
  simd_ = static_cast<detail::Isa>(isa_) != detail::Isa::kPortable;
}

SurfaceField::~SurfaceField() = default;
SurfaceField::SurfaceField(SurfaceField&&) noexcept = default;
SurfaceField& SurfaceField::operator=(SurfaceField&&) noexcept = default;

const char* SurfaceField::kernel_name() const noexcept { return detail::IsaName(static_cast<detail::Isa>(isa_)); }

std::size_t SurfaceField::storage_bytes() const noexcept {
  return expanded_.size() * sizeof(float) + (columns_ ? columns_->storage_bytes() : 0);
}

bool SurfaceField::Evaluate(std::span<const NodeLoad> loads, std::span<Eigen::Vector3d> u_m) noexcept {
  const Compliance& C = *compliance_;
  const std::int32_t N = C.num_nodes();
  if (u_m.size() != static_cast<std::size_t>(N)) return false;
  const auto isa = static_cast<detail::Isa>(isa_);
  if (columns_) {
    columns_->SumColumns(loads, u_m.data(), isa);
  } else if (C.storage() == ComplianceStorage::kCompressed) {
    C.compressed()->Apply(loads, u_m.data(), detail::Align64(expanded_), isa);
  } else if (simd_) {
    ApplyPackedAvx512(C.data_f32(), N, loads, u_m.data(), detail::Align64(expanded_));
  } else if (C.precision() == Precision::kFloat32) {
    ApplyPackedGeneric(C.data_f32(), N, loads, u_m.data());
  } else {
    ApplyPackedGeneric(C.data_f64(), N, loads, u_m.data());
  }
  return true;
}

}  // namespace handshare::fem
