#include "handshare/contact/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace handshare::contact {

Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) noexcept {
  // Voronoi regions of the vertices, edges and face, in that order.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

namespace {

// Smallest root in [0, 1] of |m + s d|^2 = R^2 for a point starting outside (|m| > R) and
// approaching; > 1 if none.
double SweepPoint(const Eigen::Vector3d& m, const Eigen::Vector3d& d, double R) noexcept {
  const double c = m.squaredNorm() - R * R;
  if (c < 0.0) return 2.0;  // already overlapping: a constraint, not a hit
  const double half_b = m.dot(d);
  // Tangent or moving away (the first test is the second's answer for half_b >= 0, without the
  // square root).
  if (half_b >= 0.0 || half_b >= -kMinApproach_m * m.norm()) return 2.0;
  const double a = d.squaredNorm();
  const double disc = half_b * half_b - a * c;
  if (disc < 0.0) return 2.0;
  return std::max(0.0, (-half_b - std::sqrt(disc)) / a);
}

// SweepSphereTriangle sweeping only the vertices in `vertices` (bit k: v[k]).
double Sweep(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m, const SweepTriangle& tri,
             unsigned vertices) noexcept {
  const Eigen::Vector3d& a = tri.v[0];
  const Eigen::Vector3d& b = tri.v[1];
  const Eigen::Vector3d& c = tri.v[2];
  double best = 2.0;
  // Face interior: the plane offset by R on the side the centre starts on.
  if (tri.has_face) {
    Eigen::Vector3d n = tri.n;
    const Eigen::Vector3d& n_tri = tri.n;  // winding normal, for the inside test
    double h0 = n.dot(x - a);
    if (h0 < 0.0) {
      n = -n;
      h0 = -h0;
    }
    const double vn = n.dot(d);
    if (h0 >= R_m && vn < -kMinApproach_m) {
      const double s = (h0 - R_m) / -vn;
      if (s <= 1.0) {
        // Touch point on the plane; inside the triangle (barycentric signs of the sub-areas)?
        const Eigen::Vector3d q = x + s * d - R_m * n;
        const double wa = (b - q).cross(c - q).dot(n_tri);
        const double wb = (c - q).cross(a - q).dot(n_tri);
        const double wc = (a - q).cross(b - q).dot(n_tri);
        if (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) best = s;
      }
    }
  }
  // Edges: infinite cylinders of radius R, hit point must project inside the segment.
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3d& p0 = tri.v[e];
    const Eigen::Vector3d& ed = tri.ed[e];
    const double len2 = tri.len2[e];
    if (!(len2 > 0.0)) continue;
    const Eigen::Vector3d m = x - p0;
    const double t0 = m.dot(ed) / len2, dt = d.dot(ed) / len2;
    // The centre's foot on the edge's line moves from t0 to t0 + dt: a touch of the cylinder
    // that projects inside the edge needs that range to meet [0, 1] (the ends are the vertices').
    if ((t0 < 0.0 && t0 + dt < 0.0) || (t0 > 1.0 && t0 + dt > 1.0)) continue;
    const Eigen::Vector3d m_perp = m - t0 * ed;
    const Eigen::Vector3d d_perp = d - dt * ed;
    if (d_perp.squaredNorm() <= 0.0) continue;
    const double s = SweepPoint(m_perp, d_perp, R_m);
    if (s < best) {
      const double t = (m + s * d).dot(ed) / len2;
      if (t >= 0.0 && t <= 1.0) best = s;
    }
  }
  // Vertices: spheres of radius R.
  for (int k = 0; k < 3; ++k) {
    if ((vertices & (1u << k)) == 0) continue;
    const double s = SweepPoint(x - tri.v[k], d, R_m);
    if (s < best) best = s;
  }
  return best;
}
}  // namespace

SweepTriangle MakeSweepTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c) noexcept {
  SweepTriangle t;
  t.v[0] = a;
  t.v[1] = b;
  t.v[2] = c;
  Eigen::Vector3d n = (b - a).cross(c - a);
  const double nn = n.norm();
  t.has_face = nn > 0.0;
  if (t.has_face) n /= nn;
  t.n = n;
  for (int e = 0; e < 3; ++e) {
    t.ed[e] = t.v[(e + 1) % 3] - t.v[e];
    t.len2[e] = t.ed[e].squaredNorm();
  }
  return t;
}

double SweepSphereTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                           const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c) noexcept {
  return SweepSphereTriangle(x, d, R_m, MakeSweepTriangle(a, b, c));
}

double SweepSphereTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                           const SweepTriangle& tri) noexcept {
  return Sweep(x, d, R_m, tri, 7u);
}

double SweepSphereTriangleOwned(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                                const SweepTriangle& tri) noexcept {
  return Sweep(x, d, R_m, tri, tri.own_vertices);
}

namespace {
#if defined(__x86_64__)
// Sweep (own vertices, from 2) in eight lanes. Every value is computed with the scalar code's
// operations in its order (Eigen's 3-vector dot is (x0 y0 + x1 y1) + x2 y2), with no fused
// multiply-add (contraction is off for this function), and each branch of the scalar code is a
// lane mask: each lane's result is the scalar result's bits.
#define HS_AVX512_SWEEP __attribute__((target("avx512f,avx512vl"), optimize("fp-contract=off")))
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wattributes"

struct V3 {
  __m512d x, y, z;
};

HS_AVX512_SWEEP inline __m512d Dot(const V3& a, const V3& b) {
  return _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(a.x, b.x), _mm512_mul_pd(a.y, b.y)), _mm512_mul_pd(a.z, b.z));
}
HS_AVX512_SWEEP inline V3 Sub(const V3& a, const V3& b) {
  return {_mm512_sub_pd(a.x, b.x), _mm512_sub_pd(a.y, b.y), _mm512_sub_pd(a.z, b.z)};
}
HS_AVX512_SWEEP inline V3 Cross(const V3& a, const V3& b) {
  return {_mm512_sub_pd(_mm512_mul_pd(a.y, b.z), _mm512_mul_pd(a.z, b.y)),
          _mm512_sub_pd(_mm512_mul_pd(a.z, b.x), _mm512_mul_pd(a.x, b.z)),
          _mm512_sub_pd(_mm512_mul_pd(a.x, b.y), _mm512_mul_pd(a.y, b.x))};
}
// a - s b and a + s b, per component.
HS_AVX512_SWEEP inline V3 SubScaled(const V3& a, __m512d s, const V3& b) {
  return {_mm512_sub_pd(a.x, _mm512_mul_pd(s, b.x)), _mm512_sub_pd(a.y, _mm512_mul_pd(s, b.y)),
          _mm512_sub_pd(a.z, _mm512_mul_pd(s, b.z))};
}
HS_AVX512_SWEEP inline V3 AddScaled(const V3& a, __m512d s, const V3& b) {
  return {_mm512_add_pd(a.x, _mm512_mul_pd(s, b.x)), _mm512_add_pd(a.y, _mm512_mul_pd(s, b.y)),
          _mm512_add_pd(a.z, _mm512_mul_pd(s, b.z))};
}

HS_AVX512_SWEEP inline __m512d NegateWhere(__m512d v, __mmask8 k) {
  const __m512i bits = _mm512_castpd_si512(v);
  return _mm512_castsi512_pd(_mm512_mask_xor_epi64(bits, k, bits, _mm512_set1_epi64(INT64_MIN)));
}

// SweepPoint in lanes: the root where the scalar one returns it, 2 elsewhere.
HS_AVX512_SWEEP inline __m512d SweepPointLanes(const V3& m, const V3& d, double R, __mmask8 live) {
  const __m512d two = _mm512_set1_pd(2.0), zero = _mm512_setzero_pd();
  const __m512d m2 = Dot(m, m);
  const __m512d c = _mm512_sub_pd(m2, _mm512_set1_pd(R * R));
  __mmask8 ok = live & _mm512_cmp_pd_mask(c, zero, _CMP_NLT_UQ);  // !(c < 0)
  const __m512d half_b = Dot(m, d);
  ok &= _mm512_cmp_pd_mask(half_b, zero, _CMP_NGE_UQ);  // !(half_b >= 0)
  // (The square roots and the division only where some lane needs them: the divider is the
  // pass's bottleneck.)
  if (!ok) return two;
  ok &= _mm512_cmp_pd_mask(half_b, _mm512_mul_pd(_mm512_set1_pd(-kMinApproach_m), _mm512_sqrt_pd(m2)), _CMP_NGE_UQ);
  const __m512d a = Dot(d, d);
  const __m512d disc = _mm512_sub_pd(_mm512_mul_pd(half_b, half_b), _mm512_mul_pd(a, c));
  ok &= _mm512_cmp_pd_mask(disc, zero, _CMP_NLT_UQ);  // !(disc < 0)
  if (!ok) return two;
  // std::max(0.0, v) is (0 < v) ? v : 0, as max_pd(v, 0) is (v > 0) ? v : 0.
  const __m512d root = _mm512_max_pd(
      _mm512_div_pd(_mm512_sub_pd(_mm512_sub_pd(zero, half_b), _mm512_sqrt_pd(disc)), a), zero);
  return _mm512_mask_mov_pd(two, ok, root);
}

// Eight triangles tris[ids[i..i+8)] gathered field by field (lanes past n read nothing, hold 0).
struct TriangleLanes {
  static_assert(sizeof(SweepTriangle) % sizeof(double) == 0, "triangles gathered as doubles");
  static constexpr int kStride = static_cast<int>(sizeof(SweepTriangle) / sizeof(double));
  const double* base;
  __mmask8 live;
  __m256i id;
  __m256i idx;
  __mmask8 has_face = 0;

  HS_AVX512_SWEEP TriangleLanes(const SweepTriangle* tris, const std::int32_t* ids, std::int32_t n, std::int32_t i)
      : base(reinterpret_cast<const double*>(tris)),
        live(static_cast<__mmask8>(n - i >= 8 ? 0xFF : (1u << (n - i)) - 1u)),
        id(_mm256_maskz_loadu_epi32(live, ids + i)),
        idx(_mm256_mullo_epi32(id, _mm256_set1_epi32(kStride))) {
    for (int q = 0; q < 8; ++q) {
      if (live & (1u << q)) has_face |= static_cast<__mmask8>(tris[ids[i + q]].has_face ? 1u << q : 0u);
    }
  }
  HS_AVX512_SWEEP __m512d Field(std::size_t offset_bytes) const {
    return _mm512_mask_i32gather_pd(_mm512_setzero_pd(), live, idx, base + offset_bytes / sizeof(double), 8);
  }
  HS_AVX512_SWEEP V3 Vec(std::size_t offset_bytes) const {
    return V3{Field(offset_bytes), Field(offset_bytes + 8), Field(offset_bytes + 16)};
  }
  HS_AVX512_SWEEP V3 Vertex(int k) const { return Vec(offsetof(SweepTriangle, v) + 24 * static_cast<std::size_t>(k)); }
  HS_AVX512_SWEEP V3 Normal() const { return Vec(offsetof(SweepTriangle, n)); }
};

HS_AVX512_SWEEP double SweepOwnedAvx512(const Eigen::Vector3d& x_in, const Eigen::Vector3d& d_in, double R,
                                        const SweepTriangle* tris, const std::int32_t* ids, std::int32_t n) {
  const V3 x{_mm512_set1_pd(x_in.x()), _mm512_set1_pd(x_in.y()), _mm512_set1_pd(x_in.z())};
  const V3 d{_mm512_set1_pd(d_in.x()), _mm512_set1_pd(d_in.y()), _mm512_set1_pd(d_in.z())};
  const __m512d vR = _mm512_set1_pd(R), zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
  __m512d best_all = _mm512_set1_pd(2.0);
  for (std::int32_t i = 0; i < n; i += 8) {
    const TriangleLanes lanes(tris, ids, n, i);
    const __mmask8 live = lanes.live, has_face = lanes.has_face;
    const V3 v[3] = {lanes.Vertex(0), lanes.Vertex(1), lanes.Vertex(2)};
    // The owned vertices, lane by lane.
    __mmask8 own[3] = {0, 0, 0};
    for (int q = 0; q < 8; ++q) {
      if (!(live & (1u << q))) continue;
      const SweepTriangle& t = tris[ids[i + q]];
      for (int k = 0; k < 3; ++k) own[k] |= static_cast<__mmask8>(t.own_vertices & (1u << k) ? 1u << q : 0u);
    }
    __m512d best = _mm512_set1_pd(2.0);
    // Face interior.
    {
      const V3 n_tri = lanes.Normal();
      __m512d h0 = Dot(n_tri, Sub(x, v[0]));
      const __mmask8 flip = _mm512_cmp_pd_mask(h0, zero, _CMP_LT_OQ);
      // n = -n, h0 = -h0 where h0 < 0 (the sign bit flipped, as unary minus does).
      const V3 nf{NegateWhere(n_tri.x, flip), NegateWhere(n_tri.y, flip), NegateWhere(n_tri.z, flip)};
      h0 = NegateWhere(h0, flip);
      const __m512d vn = Dot(nf, d);
      __mmask8 hit = has_face & _mm512_cmp_pd_mask(h0, vR, _CMP_GE_OQ) &
                     _mm512_cmp_pd_mask(vn, _mm512_set1_pd(-kMinApproach_m), _CMP_LT_OQ);
      const __m512d s = hit ? _mm512_div_pd(_mm512_sub_pd(h0, vR), _mm512_sub_pd(zero, vn)) : one;
      hit &= _mm512_cmp_pd_mask(s, one, _CMP_LE_OQ);
      if (hit) {
        const V3 q = SubScaled(AddScaled(x, s, d), vR, nf);
        const __m512d wa = Dot(Cross(Sub(v[1], q), Sub(v[2], q)), n_tri);
        const __m512d wb = Dot(Cross(Sub(v[2], q), Sub(v[0], q)), n_tri);
        const __m512d wc = Dot(Cross(Sub(v[0], q), Sub(v[1], q)), n_tri);
        hit &= _mm512_cmp_pd_mask(wa, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(wb, zero, _CMP_GE_OQ) &
               _mm512_cmp_pd_mask(wc, zero, _CMP_GE_OQ);
        best = _mm512_mask_mov_pd(best, hit, s);
      }
    }
    // Edges.
    for (int e = 0; e < 3; ++e) {
      // ed and len2 as MakeSweepTriangle computes them (the same bits, two gathers fewer a field).
      const V3 ed = Sub(v[(e + 1) % 3], v[e]);
      const __m512d len2 = Dot(ed, ed);
      __mmask8 go = live & _mm512_cmp_pd_mask(len2, zero, _CMP_GT_OQ);
      const V3 m = Sub(x, v[e]);
      const __m512d t0 = _mm512_div_pd(Dot(m, ed), len2), dt = _mm512_div_pd(Dot(d, ed), len2);
      const __m512d t1 = _mm512_add_pd(t0, dt);
      const __mmask8 before = _mm512_cmp_pd_mask(t0, zero, _CMP_LT_OQ) & _mm512_cmp_pd_mask(t1, zero, _CMP_LT_OQ);
      const __mmask8 after = _mm512_cmp_pd_mask(t0, one, _CMP_GT_OQ) & _mm512_cmp_pd_mask(t1, one, _CMP_GT_OQ);
      go &= static_cast<__mmask8>(~(before | after));
      const V3 m_perp = SubScaled(m, t0, ed), d_perp = SubScaled(d, dt, ed);
      go &= _mm512_cmp_pd_mask(Dot(d_perp, d_perp), zero, _CMP_NLE_UQ);  // !(|d_perp|^2 <= 0)
      if (!go) continue;
      const __m512d s = SweepPointLanes(m_perp, d_perp, R, go);
      go &= _mm512_cmp_pd_mask(s, best, _CMP_LT_OQ);
      if (!go) continue;
      const __m512d t = _mm512_div_pd(Dot(AddScaled(m, s, d), ed), len2);
      go &= _mm512_cmp_pd_mask(t, zero, _CMP_GE_OQ) & _mm512_cmp_pd_mask(t, one, _CMP_LE_OQ);
      best = _mm512_mask_mov_pd(best, go, s);
    }
    // Own vertices.
    for (int k = 0; k < 3; ++k) {
      const __mmask8 go = live & own[k];
      if (!go) continue;
      const __m512d s = SweepPointLanes(Sub(x, v[k]), d, R, go);
      best = _mm512_mask_mov_pd(best, go & _mm512_cmp_pd_mask(s, best, _CMP_LT_OQ), s);
    }
    best_all = _mm512_mask_min_pd(best_all, live, best_all, best);
  }
  return _mm512_reduce_min_pd(best_all);
}
// Squared distance from x to eight triangles: the plane's where the foot lies inside all three
// edges (or the triangle is degenerate: then the edges' only), else the nearest edge segment's.
HS_AVX512_SWEEP std::int32_t WithinAvx512(const Eigen::Vector3d& x_in, double r, const SweepTriangle* tris,
                                          const std::int32_t* ids, std::int32_t n, std::int32_t* out) {
  const V3 x{_mm512_set1_pd(x_in.x()), _mm512_set1_pd(x_in.y()), _mm512_set1_pd(x_in.z())};
  const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
  const double rs = r * (1.0 + 1e-9);
  const __m512d r2 = _mm512_set1_pd(rs * rs);
  std::int32_t k = 0;
  for (std::int32_t i = 0; i < n; i += 8) {
    const TriangleLanes lanes(tris, ids, n, i);
    const __mmask8 live = lanes.live;
    const V3 nrm = lanes.Normal();
    const V3 v[3] = {lanes.Vertex(0), lanes.Vertex(1), lanes.Vertex(2)};
    __m512d d2 = _mm512_set1_pd(std::numeric_limits<double>::infinity());
    __mmask8 inside = lanes.has_face;
    for (int e = 0; e < 3; ++e) {
      const V3& p0 = v[e];
      const V3 ed = Sub(v[(e + 1) % 3], v[e]);
      const __m512d len2 = Dot(ed, ed);
      const V3 m = Sub(x, p0);
      // The foot is inside edge e's side where (ed x m) . n >= 0 (winding order).
      inside &= _mm512_cmp_pd_mask(Dot(Cross(ed, m), nrm), zero, _CMP_GE_OQ);
      // Point-segment distance (a zero-length edge: its start point).
      const __mmask8 has_len = _mm512_cmp_pd_mask(len2, zero, _CMP_GT_OQ);
      const __m512d t = _mm512_min_pd(
          _mm512_max_pd(_mm512_maskz_div_pd(has_len, Dot(m, ed), len2), zero), one);
      const V3 diff = SubScaled(m, t, ed);
      d2 = _mm512_min_pd(d2, Dot(diff, diff));
    }
    const __m512d h = Dot(nrm, Sub(x, v[0]));
    d2 = _mm512_mask_mov_pd(d2, inside, _mm512_mul_pd(h, h));
    // Kept: within r (with the slack), and any lane whose distance is NaN.
    const auto keep = static_cast<__mmask8>(live & _mm512_cmp_pd_mask(d2, r2, _CMP_NGT_UQ));
    const __m256i kept = _mm256_maskz_compress_epi32(keep, lanes.id);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + k), kept);
    k += __builtin_popcount(keep);
  }
  return k;
}
#pragma GCC diagnostic pop
#endif
}  // namespace

std::int32_t TrianglesWithin(const Eigen::Vector3d& x, double r, const SweepTriangle* tris, const std::int32_t* ids,
                             std::int32_t n, std::int32_t* out, bool vector) noexcept {
#if defined(__x86_64__)
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (vector && avx512) return WithinAvx512(x, r, tris, ids, n, out);
#endif
  std::copy(ids, ids + n, out);
  return n;
}

double SweepSphereTrianglesOwned(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                                 const SweepTriangle* tris, const std::int32_t* ids, std::int32_t n,
                                 bool vector) noexcept {
#if defined(__x86_64__)
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (vector && avx512) return SweepOwnedAvx512(x, d, R_m, tris, ids, n);
#endif
  double s = 2.0;
  for (std::int32_t i = 0; i < n; ++i) s = std::min(s, SweepSphereTriangleOwned(x, d, R_m, tris[ids[i]]));
  return s;
}

}  // namespace handshare::contact
