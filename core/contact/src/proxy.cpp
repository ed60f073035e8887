#include "handshare/contact/proxy.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <Eigen/Dense>

#include "handshare/contact/geometry.hpp"

namespace handshare::contact {

namespace {
// Feasibility slack of the projection [m]: round-off of dot products of millimetre vectors.
constexpr double kFeasTol_m = 1e-12;
// Touch band above R + skin [m]: features this close are resting contacts (linearized as
// planes); farther ones are left to the exact sweep. Tangent planes of edges and vertices cut
// slightly into the free space, so a wide band would stop sliding proxies short; 1 nm is far
// above round-off (1e-17 m) and far below anything felt.
constexpr double kTouchBand_m = 1e-9;
// Two constraint normals closer than this (1 - cos) are one plane (the tighter one is kept).
constexpr double kSameNormal = 1e-9;
// Slack of the plane-distance shortcuts [m]: a triangle whose plane is farther than a distance
// plus this from a point is farther than that distance from the point; 1e-10 m is seven orders
// above the round-off of the plane distance (1e-17 m at these sizes) and far below kTouchBand_m.
constexpr double kPlaneSlack_m = 1e-10;
// Gathers reach this many skins beyond R + skin (features about to enter the touch band).
constexpr double kGatherMarginSkins = 4.0;
// A neighbourhood reaches this far beyond the gather that made it [m]: the next gathers of a
// proxy moving up to this far (a few steps of a fingertip at speed) are served from it.
constexpr double kNeighbourSlack_m = 2e-3;
// Slack of the neighbourhood's containment test [m]: far above the round-off of distances at
// these sizes (1e-17 m), far below anything it decides.
constexpr double kNeighbourRoundoff_m = 1e-9;
// Slack of the neighbourhood's cull [m]: its float planes and discs, relative to the centre,
// and its float arithmetic (a few dozen roundings of 2^-24) are off by less than
// kCullFloatSlackPerExtent times the largest magnitude among them (about 1e-8 m for a
// fingertip's neighbourhood on a table-top mesh); the triangles it keeps beyond the touch band
// (by up to this) only cost the exact tests that reject them.
constexpr double kCullFloatSlack_m = 1e-6;
constexpr double kCullFloatSlackPerExtent = 4e-6;

// DiscDistanceBound2 for every point of the segment x + s d, s in [0, 1], with plane distances h0
// at x and h1 at x + d: the smallest |h| on it, and the foot of the segment nearest to the
// disc's centre.
inline double SegmentDiscBound2(const Eigen::Vector4d& plane, const Eigen::Vector4d& disc, const Eigen::Vector3d& x,
                                const Eigen::Vector3d& d, double h0, double h1) noexcept {
  const double h = (h0 > 0.0) != (h1 > 0.0) ? 0.0 : std::min(std::abs(h0), std::abs(h1));
  const Eigen::Vector3d n = plane.head<3>();
  const Eigen::Vector3d foot = x - h0 * n;          // in the plane
  const Eigen::Vector3d along = d - (h1 - h0) * n;  // the segment's foot runs along this
  const Eigen::Vector3d to_c = disc.head<3>() - foot;
  const double a2 = along.squaredNorm();
  const double s = a2 > 0.0 ? std::clamp(to_c.dot(along) / a2, 0.0, 1.0) : 0.0;
  const double lateral = std::max(0.0, (to_c - s * along).norm() - disc.w());
  return h * h + lateral * lateral;
}
}  // namespace

ProxySolver::ProxySolver(std::int32_t max_candidates)
    : candidates_(static_cast<std::size_t>(std::max<std::int32_t>(max_candidates, 1))), ends_(kEndEntries) {
  for (Neighbourhood& h : hoods_) {
    for (auto& v : h.soa) v.resize(candidates_.size());
    h.ids.resize(candidates_.size());
  }
  sweep_ids_.resize(candidates_.size() + 8);
  candidates_.resize(candidates_.size() + 16);  // the vector cull stores whole groups of 16
}

namespace {
// The segment cull of a neighbourhood's triangles (SegmentDiscBound2 against lim), written to
// keep: out[k] = ids[i] for each triangle kept. The triangles' planes and discs are floats
// relative to the neighbourhood's centre (as are x and d here), whose round-off the caller's
// lim covers with the neighbourhood's slack. Keeps every triangle whose bound is not beyond lim
// (a NaN one too: every comparison is false for it).
std::int32_t CullScalar(const std::array<const float*, 8>& q, const std::int32_t* ids, std::int32_t n,
                        const Eigen::Vector3d& x, const Eigen::Vector3d& d, double lim, std::int32_t* out) noexcept {
  std::int32_t k = 0;
  for (std::int32_t i = 0; i < n; ++i) {
    const Eigen::Vector4d plane(q[0][i], q[1][i], q[2][i], q[3][i]);
    const Eigen::Vector4d disc(q[4][i], q[5][i], q[6][i], q[7][i]);
    const double h0 = PlaneDistance(plane, x);
    const double h1 = h0 + (plane.x() * d.x() + plane.y() * d.y() + plane.z() * d.z());
    out[k] = ids[i];
    const bool beyond = (h0 > lim && h1 > lim) || (h0 < -lim && h1 < -lim) ||
                        SegmentDiscBound2(plane, disc, x, d, h0, h1) > lim * lim;
    k += !beyond;
  }
  return k;
}

#if defined(__x86_64__)
#define HS_AVX512_CULL __attribute__((target("avx512f,avx512vl,fma")))
// GCC 12 reads the intrinsics' unspecified pass-through operand (_mm512_undefined_ps) as
// possibly uninitialised; it is never read.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
// CullScalar sixteen triangles at a time (the same bound in float; its round-off is covered by
// the same slack).
HS_AVX512_CULL std::int32_t CullAvx512(const std::array<const float*, 8>& q, const std::int32_t* ids,
                                       std::int32_t n, const Eigen::Vector3d& x, const Eigen::Vector3d& d,
                                       double lim, std::int32_t* out) noexcept {
  const __m512 xx = _mm512_set1_ps(static_cast<float>(x.x())), xy = _mm512_set1_ps(static_cast<float>(x.y())),
               xz = _mm512_set1_ps(static_cast<float>(x.z()));
  const __m512 dx = _mm512_set1_ps(static_cast<float>(d.x())), dy = _mm512_set1_ps(static_cast<float>(d.y())),
               dz = _mm512_set1_ps(static_cast<float>(d.z()));
  const auto flim = static_cast<float>(lim);
  const __m512 vlim = _mm512_set1_ps(flim), vnlim = _mm512_set1_ps(-flim), vlim2 = _mm512_set1_ps(flim * flim);
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f), shrink = _mm512_set1_ps(1.0f - 0x1p-12f);
  std::int32_t k = 0;
  for (std::int32_t i = 0; i < n; i += 16) {
    const auto live = static_cast<__mmask16>(n - i >= 16 ? 0xFFFFu : (1u << (n - i)) - 1u);
    const __m512 nx = _mm512_maskz_loadu_ps(live, q[0] + i), ny = _mm512_maskz_loadu_ps(live, q[1] + i);
    const __m512 nz = _mm512_maskz_loadu_ps(live, q[2] + i), w = _mm512_maskz_loadu_ps(live, q[3] + i);
    const __m512 cx = _mm512_maskz_loadu_ps(live, q[4] + i), cy = _mm512_maskz_loadu_ps(live, q[5] + i);
    const __m512 cz = _mm512_maskz_loadu_ps(live, q[6] + i), cr = _mm512_maskz_loadu_ps(live, q[7] + i);
    const __m512 h0 = _mm512_sub_ps(_mm512_fmadd_ps(nz, xz, _mm512_fmadd_ps(ny, xy, _mm512_mul_ps(nx, xx))), w);
    const __m512 dh = _mm512_fmadd_ps(nz, dz, _mm512_fmadd_ps(ny, dy, _mm512_mul_ps(nx, dx)));
    const __m512 h1 = _mm512_add_ps(h0, dh);
    // Plane beyond on one side at both ends.
    const __mmask16 above = _mm512_cmp_ps_mask(h0, vlim, _CMP_GT_OQ) & _mm512_cmp_ps_mask(h1, vlim, _CMP_GT_OQ);
    const __mmask16 below = _mm512_cmp_ps_mask(h0, vnlim, _CMP_LT_OQ) & _mm512_cmp_ps_mask(h1, vnlim, _CMP_LT_OQ);
    // Smallest |h| on the segment (0 where it crosses the plane).
    const __mmask16 cross = _mm512_cmp_ps_mask(h0, zero, _CMP_GT_OQ) ^ _mm512_cmp_ps_mask(h1, zero, _CMP_GT_OQ);
    const __m512 h = _mm512_maskz_min_ps(static_cast<__mmask16>(~cross), _mm512_abs_ps(h0), _mm512_abs_ps(h1));
    // The segment's foot in the plane and the disc's centre relative to it.
    const __m512 fx = _mm512_fnmadd_ps(h0, nx, xx), fy = _mm512_fnmadd_ps(h0, ny, xy), fz = _mm512_fnmadd_ps(h0, nz, xz);
    const __m512 ax = _mm512_fnmadd_ps(dh, nx, dx), ay = _mm512_fnmadd_ps(dh, ny, dy), az = _mm512_fnmadd_ps(dh, nz, dz);
    const __m512 tx = _mm512_sub_ps(cx, fx), ty = _mm512_sub_ps(cy, fy), tz = _mm512_sub_ps(cz, fz);
    const __m512 a2 = _mm512_fmadd_ps(az, az, _mm512_fmadd_ps(ay, ay, _mm512_mul_ps(ax, ax)));
    const __m512 ta = _mm512_fmadd_ps(tz, az, _mm512_fmadd_ps(ty, ay, _mm512_mul_ps(tx, ax)));
    const __mmask16 moving = _mm512_cmp_ps_mask(a2, zero, _CMP_GT_OQ);
    const __m512 s = _mm512_min_ps(_mm512_max_ps(_mm512_maskz_div_ps(moving, ta, a2), zero), one);
    const __m512 lx = _mm512_fnmadd_ps(s, ax, tx), ly = _mm512_fnmadd_ps(s, ay, ty), lz = _mm512_fnmadd_ps(s, az, tz);
    // |l| from below: l2 / sqrt(l2) with the 2^-14 estimate of 1 / sqrt, scaled down past its
    // error (a smaller lateral distance keeps more: the cull stays conservative); l2 = 0 gives
    // NaN, and the max below takes 0 for it.
    const __m512 l2 = _mm512_fmadd_ps(lz, lz, _mm512_fmadd_ps(ly, ly, _mm512_mul_ps(lx, lx)));
    const __m512 l = _mm512_mul_ps(_mm512_mul_ps(l2, _mm512_rsqrt14_ps(l2)), shrink);
    const __m512 lat = _mm512_max_ps(_mm512_sub_ps(l, cr), zero);
    const __m512 b2 = _mm512_fmadd_ps(lat, lat, _mm512_mul_ps(h, h));
    const __mmask16 far = _mm512_cmp_ps_mask(b2, vlim2, _CMP_GT_OQ);
    const auto keep = static_cast<__mmask16>(live & ~(above | below | far));
    // Compressed in a register and stored whole (out has 16 spare entries past n).
    const __m512i vid = _mm512_maskz_compress_epi32(keep, _mm512_maskz_loadu_epi32(live, ids + i));
    _mm512_storeu_si512(out + k, vid);
    k += __builtin_popcount(keep);
  }
  return k;
}
#pragma GCC diagnostic pop
#endif

std::int32_t Cull(const std::array<const float*, 8>& q, const std::int32_t* ids, std::int32_t n,
                  const Eigen::Vector3d& x, const Eigen::Vector3d& d, double lim, std::int32_t* out,
                  bool vector) noexcept {
#if defined(__x86_64__)
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (vector && avx512) return CullAvx512(q, ids, n, x, d, lim, out);
#endif
  return CullScalar(q, ids, n, x, d, lim, out);
}
}  // namespace

bool ProxySolver::GatherFromNeighbourhood(const MeshCollider& collider, const Eigen::Vector3d& x,
                                          const Eigen::Vector3d& d, double r_ball, double r) noexcept {
  const Eigen::Vector3d c = x + 0.5 * d;
  for (Neighbourhood& h : hoods_) {
    if (h.collider_id != collider.id() || !((c - h.c).norm() + r_ball <= h.r - kNeighbourRoundoff_m)) continue;
    h.used = ++hood_clock_;
    std::array<const float*, 8> q{};
    for (std::size_t a = 0; a < q.size(); ++a) q[a] = h.soa[a].data();
    num_candidates_ = Cull(q, h.ids.data(), h.n, x - h.c, d, r + h.slack, candidates_.data(), vector_cull_);
    last_gather_truncated_ = false;
    return true;
  }
  return false;
}

bool ProxySolver::FillNeighbourhood(const MeshCollider& collider, const Eigen::Vector3d& c, double r) noexcept {
  Neighbourhood* h = &hoods_[0];
  for (Neighbourhood& q : hoods_) {
    if (q.used < h->used) h = &q;
  }
  h->collider_id = 0;
  const std::int32_t cap = std::min<std::int32_t>(static_cast<std::int32_t>(h->ids.size()), collider.max_candidates());
  const BallQueryResult q =
      collider.QueryBall(c, r + kNeighbourSlack_m, std::span<std::int32_t>(h->ids.data(), static_cast<std::size_t>(cap)),
                         /*exact=*/false);
  if (q.truncated) return false;
  double extent = r + kNeighbourSlack_m;  // the largest magnitude the cull meets
  for (std::int32_t i = 0; i < q.count; ++i) {
    const std::int32_t t = h->ids[static_cast<std::size_t>(i)];
    const auto u = static_cast<std::size_t>(i);
    // Relative to the centre: the plane's offset n . c less, the disc's centre less c, its
    // radius rounded up.
    const Eigen::Vector4d& pl = collider.triangle_plane(t);
    const Eigen::Vector4d& di = collider.triangle_disc(t);
    const Eigen::Vector3d dc = di.head<3>() - c;
    const float rel[8] = {static_cast<float>(pl.x()), static_cast<float>(pl.y()), static_cast<float>(pl.z()),
                          static_cast<float>(pl.w() - pl.head<3>().dot(c)), static_cast<float>(dc.x()),
                          static_cast<float>(dc.y()), static_cast<float>(dc.z()),
                          std::nextafter(static_cast<float>(di.w()), std::numeric_limits<float>::infinity())};
    for (std::size_t a = 0; a < 8; ++a) h->soa[a][u] = rel[a];
    const double e = std::abs(pl.w() - pl.head<3>().dot(c)) + dc.norm() + di.w();
    if (e > extent) extent = e;  // (a NaN one, of a degenerate triangle, is kept by the cull anyway)
  }
  h->collider_id = collider.id();
  h->slack = kCullFloatSlack_m + kCullFloatSlackPerExtent * extent;
  h->c = c;
  h->r = r + kNeighbourSlack_m;
  h->n = q.count;
  h->used = ++hood_clock_;
  return true;
}

std::size_t ProxySolver::EndSlot(const Eigen::Vector3d& x) noexcept {
  std::uint64_t h = 0;
  for (int k = 0; k < 3; ++k) {
    std::uint64_t b = 0;
    std::memcpy(&b, &x[k], sizeof b);
    h = (h ^ b) * 0x9E3779B97F4A7C15ull;
  }
  return static_cast<std::size_t>(h >> 58) % kEndEntries;
}

bool ProxySolver::Gather(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x,
                         const Eigen::Vector3d& d) noexcept {
  const double Rs = params.radius_m + params.skin_m;
  const Eigen::Vector3d center = x + 0.5 * d;
  const double radius = 0.5 * d.norm() + Rs + kGatherMarginSkins * params.skin_m;
  // From a neighbourhood: the triangles within the touch band of the segment (what the sweep
  // can hit and what the constraints along it are made of), culled already.
  const double cull = Rs + kTouchBand_m + kNeighbourRoundoff_m;
  culled_ = !reference_ && (GatherFromNeighbourhood(collider, x, d, radius, cull) ||
                            (FillNeighbourhood(collider, center, radius) &&
                             GatherFromNeighbourhood(collider, x, d, radius, cull)));
  if (culled_) return num_candidates_ > 0;
  const std::int32_t cap = std::min<std::int32_t>(static_cast<std::int32_t>(candidates_.size()) - 16,
                                                  collider.max_candidates());
  const std::span<std::int32_t> ids(candidates_.data(), static_cast<std::size_t>(cap));
  const BallQueryResult r = reference_ ? collider.QueryBallObb(center, radius, ids) : collider.QueryBall(center, radius, ids);
  num_candidates_ = r.count;
  last_gather_truncated_ = r.truncated;
  truncated_ = truncated_ || r.truncated;
  return r.count > 0;
}

int ProxySolver::CollectConstraints(const MeshCollider& collider, const ProxyParams& params,
                                    const Eigen::Vector3d& x) noexcept {
  const double R = params.radius_m;
  const double touch = R + params.skin_m + kTouchBand_m;
  int m = 0;
  touching_.n = 0;
  // A neighbourhood's candidates are first reduced to those within the touch band of x (the
  // distances in lanes; the same triangles in the same order for the exact tests below).
  const std::int32_t* cand = candidates_.data();
  std::int32_t num = num_candidates_;
  if (culled_) {
    num = TrianglesWithin(x, touch, collider.triangles(), cand, num, sweep_ids_.data(), vector_cull_);
    cand = sweep_ids_.data();
  }
  for (std::int32_t i = 0; i < num; ++i) {
    const std::int32_t t = cand[static_cast<std::size_t>(i)];
    // The distance to a triangle is at least the distance to its plane, and to its disc: a
    // plane or a disc beyond the touch band skips the exact closest point (same constraints,
    // see kPlaneSlack_m).
    if (!reference_ &&
        BeyondTriangle(collider.triangle_disc(t), x, PlaneDistance(collider.triangle_plane(t), x), touch + kPlaneSlack_m)) {
      continue;
    }
    const auto& P = collider.triangle(t).v;
    const Eigen::Vector3d c = ClosestPointOnTriangle(x, P[0], P[1], P[2]);
    const double dist = (x - c).norm();
    // Overlapped features (dist < R: the proxy started inside them) are ignored until it leaves.
    if (!(dist < touch) || dist < R) continue;
    const Eigen::Vector3d n = (x - c) / dist;
    const double b = n.dot(c) + R + params.skin_m;
    int j = 0;
    while (j < m && cons_[static_cast<std::size_t>(j)].n.dot(n) < 1.0 - kSameNormal) ++j;
    if (j < m) {  // same plane: keep the tighter one
      Constraint& k = cons_[static_cast<std::size_t>(j)];
      if (b > k.b) {
        k = Constraint{n, c, b, dist, t};
      } else if (dist < k.dist) {
        k.c = c;
        k.dist = dist;
        k.tri = t;
      }
      touching_.Add(t, j);
      continue;
    }
    if (m == kMaxConstraints) {  // keep the closest ones
      int worst = 0;
      for (int q = 1; q < m; ++q) {
        if (cons_[static_cast<std::size_t>(q)].dist > cons_[static_cast<std::size_t>(worst)].dist) worst = q;
      }
      if (dist < cons_[static_cast<std::size_t>(worst)].dist) {
        cons_[static_cast<std::size_t>(worst)] = Constraint{n, c, b, dist, t};
        touching_.DropConstraint(worst);  // swept again, as every triangle without a plane
        touching_.Add(t, worst);
      }
      continue;
    }
    touching_.Add(t, m);
    cons_[static_cast<std::size_t>(m++)] = Constraint{n, c, b, dist, t};
  }
  // The constraints are a function of (mesh, x, R, skin) alone when the candidates held every
  // triangle within R + skin + margin of x (an untruncated gather of a ball that contains that
  // one): remembered so that the next gather at the same point can be skipped.
  cons_site_ = last_gather_truncated_ ? Site{} : Site{collider.id(), params.radius_m, params.skin_m, x};
  cons_m_ = m;
  return m;
}

bool ProxySolver::Site::Is(const MeshCollider& collider, const ProxyParams& params,
                           const Eigen::Vector3d& at) const noexcept {
  return collider_id != 0 && collider_id == collider.id() && radius_m == params.radius_m && skin_m == params.skin_m &&
         std::memcmp(x.data(), at.data(), sizeof(double) * 3) == 0;
}

int ProxySolver::ConstraintsAt(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x) noexcept {
  if (!reference_ && cons_site_.Is(collider, params, x)) return cons_m_;
  Gather(collider, params, x, Eigen::Vector3d::Zero());
  return CollectConstraints(collider, params, x);
}

void ProxySolver::LoadEnd(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& x) noexcept {
  if (reference_ || cons_site_.Is(collider, params, x)) return;
  const EndEntry& e = ends_[EndSlot(x)];
  if (!e.site.Is(collider, params, x)) return;
  std::copy(e.cons.begin(), e.cons.begin() + e.m, cons_.begin());
  touching_ = e.touching;
  cons_m_ = e.m;
  cons_site_ = e.site;
}

void ProxySolver::StoreEnd() noexcept {
  if (reference_ || cons_site_.collider_id == 0) return;
  EndEntry& end = ends_[EndSlot(cons_site_.x)];
  end.site = cons_site_;
  end.m = cons_m_;
  std::copy(cons_.begin(), cons_.begin() + cons_m_, end.cons.begin());
  end.touching = touching_;
}

Eigen::Vector3d ProxySolver::Project(const Eigen::Vector3d& goal, const Eigen::Vector3d& x,
                                     int m) const noexcept {
  // Minimize |t - goal|^2 subject to n_i . t >= b_i. At the optimum at most 3 independent planes
  // are active and t is the projection of goal onto their intersection; among all such
  // projections that are feasible, the nearest to goal is the optimum (it is the projection onto
  // a convex set). m <= 8: at most 1 + 8 + 28 + 56 candidates, usually m <= 2.
  auto feasible = [&](const Eigen::Vector3d& t) {
    for (int i = 0; i < m; ++i) {
      const Constraint& k = cons_[static_cast<std::size_t>(i)];
      if (k.n.dot(t) < k.b - kFeasTol_m) return false;
    }
    return true;
  };
  if (feasible(goal)) return goal;
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_t = x;
  auto consider = [&](const Eigen::Vector3d& t) {
    if (!t.allFinite() || !feasible(t)) return;
    const double d2 = (t - goal).squaredNorm();
    if (d2 < best) {
      best = d2;
      best_t = t;
    }
  };
  for (int i = 0; i < m; ++i) {
    const Constraint& a = cons_[static_cast<std::size_t>(i)];
    consider(goal + (a.b - a.n.dot(goal)) * a.n);
  }
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) {
      const Constraint& a = cons_[static_cast<std::size_t>(i)];
      const Constraint& b = cons_[static_cast<std::size_t>(j)];
      const double c = a.n.dot(b.n);
      const double det = 1.0 - c * c;
      if (det < 1e-10) continue;
      const double ra = a.b - a.n.dot(goal), rb = b.b - b.n.dot(goal);
      const double la = (ra - c * rb) / det, lb = (rb - c * ra) / det;
      consider(goal + la * a.n + lb * b.n);
    }
  }
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) {
      for (int k = j + 1; k < m; ++k) {
        Eigen::Matrix3d N;
        N.row(0) = cons_[static_cast<std::size_t>(i)].n.transpose();
        N.row(1) = cons_[static_cast<std::size_t>(j)].n.transpose();
        N.row(2) = cons_[static_cast<std::size_t>(k)].n.transpose();
        const double det = N.determinant();
        if (std::abs(det) < 1e-8) continue;
        const Eigen::Vector3d rhs(cons_[static_cast<std::size_t>(i)].b, cons_[static_cast<std::size_t>(j)].b,
                                  cons_[static_cast<std::size_t>(k)].b);
        consider(N.inverse() * rhs);  // the vertex of three planes (goal drops out)
      }
    }
  }
  return best_t;
}

Eigen::Vector3d ProxySolver::Move(const MeshCollider& collider, const ProxyParams& params,
                                  const Eigen::Vector3d& x0, const Eigen::Vector3d& goal,
                                  bool* truncated, std::int32_t* iterations) noexcept {
  cons_site_ = Site{};  // a call from outside Step starts from a fresh gather
  return MoveFrom(collider, params, x0, goal, truncated, iterations);
}

Eigen::Vector3d ProxySolver::MoveFrom(const MeshCollider& collider, const ProxyParams& params,
                                      const Eigen::Vector3d& x0, const Eigen::Vector3d& goal,
                                      bool* truncated, std::int32_t* iterations) noexcept {
  truncated_ = false;
  const double Rs = params.radius_m + params.skin_m;
  Eigen::Vector3d x = x0;
  // Constraints at the start: the triangles within R + skin of the proxy (already at hand when
  // the last collection was at x0 from an untruncated gather).
  int m = ConstraintsAt(collider, params, x);
  std::int32_t it = 0;
  for (; it < params.max_iterations; ++it) {
    Eigen::Vector3d t = Project(goal, x, m);
    Eigen::Vector3d d = t - x;
    const double len = d.norm();
    if (!(len > 1e-12)) break;
    if (len > params.max_step_m) d *= params.max_step_m / len;
    // Sweep against every triangle near the segment (the ball around it covers all points
    // within R + skin of it); no triangle: free motion.
    double s = 2.0;
    if (Gather(collider, params, x, d) && culled_) {
      // A neighbourhood's candidates have been through the plane and disc tests below (up to the
      // touch band) and hold every reachable vertex's owner: the touching ones out (below), the
      // rest swept at once.
      std::int32_t k = 0;
      for (std::int32_t i = 0; i < num_candidates_; ++i) {
        const std::int32_t tri = candidates_[static_cast<std::size_t>(i)];
        sweep_ids_[static_cast<std::size_t>(k)] = tri;
        k += touching_.Has(tri) ? 0 : 1;
      }
      s = SweepSphereTrianglesOwned(x, d, Rs, collider.triangles(), sweep_ids_.data(), k, vector_cull_);
    } else if (num_candidates_ > 0) {
      // A triangle whose plane stays farther than Rs from both ends of the segment, on one side,
      // is farther than Rs from every point of it: no touch in [0, 1] (the exact sweep could
      // only return a root beyond 1, and only min(s, 1) is used), so it is skipped.
      const double lim = Rs + kPlaneSlack_m;
      for (std::int32_t i = 0; i < num_candidates_; ++i) {
        const std::int32_t tri = candidates_[static_cast<std::size_t>(i)];
        const Eigen::Vector4d& pl = collider.triangle_plane(tri);
        const double h0 = PlaneDistance(pl, x);
        const double h1 = h0 + (pl.x() * d.x() + pl.y() * d.y() + pl.z() * d.z());
        if (!reference_ && ((h0 > lim && h1 > lim) || (h0 < -lim && h1 < -lim))) continue;
        // Nor one whose disc stays farther than Rs from the segment (a neighbour beside it).
        if (!reference_ && SegmentDiscBound2(pl, collider.triangle_disc(tri), x, d, h0, h1) > lim * lim) continue;
        // A triangle in the touch band at x is a constraint: its plane n . t >= n . c + R + skin
        // at its closest point c bounds the whole triangle grown by R + skin (the triangle lies in
        // n . (q - c) <= 0), x and t both satisfy it, so the straight move between them cannot
        // enter it. Sweeping it would instead see the features that rest exactly at R + skin
        // (an edge or vertex next to the face the proxy slides on, in round-off of the touch)
        // as hit at s = 0 by any move that grazes them: the freeze at shared edges and vertices.
        if (touching_.Has(tri)) continue;
        if (reference_) {
          const auto& P = collider.triangle(tri).v;
          s = std::min(s, SweepSphereTriangle(x, d, Rs, P[0], P[1], P[2]));
        } else if (!last_gather_truncated_) {
          // Every triangle the segment can reach is a candidate here, so is each reachable
          // vertex's owner (it holds the vertex), unless it is a constraint, whose vertices the
          // move cannot reach either (above): each vertex once.
          s = std::min(s, SweepSphereTriangleOwned(x, d, Rs, collider.triangle(tri)));
        } else {
          s = std::min(s, SweepSphereTriangle(x, d, Rs, collider.triangle(tri)));
        }
      }
    }
    x += std::min(s, 1.0) * d;
    m = CollectConstraints(collider, params, x);
  }
  if (truncated) *truncated = truncated_;
  if (iterations) *iterations = it;
  return x;
}

namespace {

// Step's first stage: a proxy that has not started (or is not finite) starts at the goal; one
// far from the mesh's bounding sphere at both ends is free, at the goal. True: free (state and
// out are set).
bool StartOrFree(const MeshCollider& collider, const ProxyParams& params, const Eigen::Vector3d& goal,
                 ProxyState& state, ProxyContact& out) noexcept {
  if (!state.initialized || !state.x_O_m.allFinite()) {
    state.x_O_m = goal;
    state.initialized = true;
    state.in_contact = false;
    state.free_tracked = false;
  }
  const Eigen::Vector3d& x0 = state.x_O_m;
  const double reach = collider.bound_radius_m() + params.radius_m + params.max_step_m;
  if ((x0 - collider.bound_center_O_m()).norm() > reach &&
      (goal - collider.bound_center_O_m()).norm() > reach) {
    state.x_O_m = goal;
    state.free_tracked = false;
    state.in_contact = false;
    out.x_O_m = goal;
    return true;
  }
  return false;
}

// Step's last stage: the contact at the final proxy x from its m constraints. Normal: the
// touching feature nearest to the proxy (the others in the band are tilted neighbours); among
// features touching equally (a concave corner) the one pressed hardest. (A template: the
// solver's constraint type is its own.)
template <class Constraint>
void ContactAt(const Constraint* cons, int m, const Eigen::Vector3d& x, const Eigen::Vector3d& goal, double skin_m,
               ProxyContact& out) noexcept {
  if (m <= 0) return;
  int best = 0;
  for (int i = 1; i < m; ++i) {
    if (cons[i].dist < cons[best].dist) best = i;
  }
  const Constraint& k = cons[best];
  out.p_O_m = k.c;
  out.n_O = k.n;
  out.triangle = k.tri;
  double depth = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < m; ++i) {
    const Constraint& q = cons[i];
    if (q.dist > k.dist + 1e-9) continue;
    const double di = q.n.dot(x - goal);
    if (di > depth) {
      depth = di;
      out.p_O_m = q.c;
      out.n_O = q.n;
      out.triangle = q.tri;
    }
  }
  // Depth of the fingertip sphere below the surface (the proxy rests skin_m above it).
  out.depth_m = std::max(0.0, depth - skin_m);
  out.touching = depth > skin_m;
}

}  // namespace

// The stages: start (or free), the frictionless god-object's move, Coulomb on the proxy about
// it, and the contact where the proxy ends.
ProxyContact ProxySolver::Step(const MeshCollider& collider, const ProxyParams& params,
                               const FrictionParams& friction, const Eigen::Vector3d& goal,
                               ProxyState& state) noexcept {
  ProxyContact out;
  out.x_O_m = state.x_O_m;
  cons_site_ = Site{};  // set again below only from this collider's own results
  if (!goal.allFinite()) return out;
  if (StartOrFree(collider, params, goal, state, out)) return out;
  const Eigen::Vector3d x0 = state.x_O_m;
  bool trunc = false;
  std::int32_t iters = 0;
  Eigen::Vector3d x = x0;
  Eigen::Vector3d x_free = x0;
  bool slipped = false;
  const bool frictional = state.in_contact && friction.mu_static > 0.0;
  // The frictionless god-object: from where it was with friction (it is tracked alongside the
  // held proxy), else from the proxy itself. Where a Step ended, the constraints are known.
  const Eigen::Vector3d xf0 = frictional && state.free_tracked && state.x_free_O_m.allFinite() ? state.x_free_O_m : x0;
  LoadEnd(collider, params, xf0);
  x_free = MoveFrom(collider, params, xf0, goal, &trunc, &iters);
  x = x_free;
  const Eigen::Vector3d e = x_free - goal;  // frictionless reaction direction (normal cone)
  const double e_norm = e.norm();
  if (frictional && e_norm > 0.0) {
    // Coulomb on the proxy, about the frictionless god-object's contact (Salisbury et al.
    // 1995): would the force with the proxy held at x0 lie in the static cone about its normal?
    // That god-object is tracked from step to step, so it is where the surface puts it however
    // long the proxy has been held. (Restarted from the held proxy each step, as before, it got
    // no farther than max_iterations rounds of at most max_step_m: a fingertip that had drawn
    // the proxy's spring longer than that stayed "inside the cone" of a point a few mm from the
    // proxy, and the proxy stayed for good -- another freeze.)
    const Eigen::Vector3d n = e / e_norm;
    const Eigen::Vector3d f0 = x0 - goal;
    const Eigen::Vector3d ft = f0 - f0.dot(n) * n;
    const double fn = f0.dot(n) - params.skin_m;  // spring length from the surface
    const double ft_norm = ft.norm();
    const double mu = state.sliding ? friction.mu_kinetic : friction.mu_static;
    if (fn > 0.0 && ft_norm <= mu * fn * (1.0 + 1e-9)) {
      x = x0;
      out.sticking = true;
    } else if (fn > 0.0 && ft_norm > 0.0) {
      slipped = true;
      // Slip: back from the frictionless position toward x0 until the tangential force is
      // mu_kinetic times the normal one (the kinetic cone's boundary), as a constrained move.
      const double alpha = std::min(1.0, friction.mu_kinetic * fn / ft_norm);
      if (alpha > 0.0) {
        StoreEnd();  // the constraints at x_free, for its next Step
        std::int32_t it2 = 0;
        bool tr2 = false;
        x = MoveFrom(collider, params, x_free, x_free + alpha * (x0 - x_free), &tr2, &it2);
        trunc = trunc || tr2;
        iters += it2;
      }
    }
  }
  if (out.sticking) {
    StoreEnd();  // at x_free
    LoadEnd(collider, params, x0);
  }
  // Contact geometry at the final proxy (its neighbourhood is in the last gather, re-query to
  // be exact when the proxy stuck at x0).
  // x is where the last Move ended unless the proxy stuck at x0: then the constraints at hand
  // are reused, else collected there.
  const int m = ConstraintsAt(collider, params, x);
  if (cons_site_.Is(collider, params, x)) StoreEnd();  // for the next Step from x
  out.truncated = trunc || truncated_;
  out.iterations = iters;
  out.x_O_m = x;
  state.x_O_m = x;
  ContactAt(cons_.data(), m, x, goal, params.skin_m, out);
  if (!out.touching) out.sticking = false;
  state.in_contact = out.touching;
  state.sliding = out.touching && slipped;
  // Tracked while the proxy is held or slides; otherwise the god-object is the proxy.
  state.free_tracked = out.touching && friction.mu_static > 0.0;
  state.x_free_O_m = state.free_tracked ? x_free : x;
  return out;
}

}  // namespace handshare::contact
