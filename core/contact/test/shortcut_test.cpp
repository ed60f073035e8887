// The collision shortcuts (compact float tree walk, plane-distance skips, reuse of the constraints
// where the last move ended, the sweep's per-triangle part computed once per mesh) against the
// previous exact path on random queries: the same triangles in the same order, the same times
// of impact, and the same proxy positions and contacts, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "handshare/contact/geometry.hpp"
#include "handshare/contact/mesh_collider.hpp"
#include "handshare/contact/proxy.hpp"
#include "handshare/contact/tri_mesh.hpp"

namespace handshare::contact {
namespace {

bool SameBits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

// A fine, slightly wavy plate (flat-ish faces, many coplanar neighbours) and a bumpy sphere.
std::shared_ptr<const TriMesh> WavyPlate() {
  TriMesh m;
  const int n = 40;
  const double h = 0.1 / n;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double z = (i + j) % 7 == 0 ? 2e-4 : 0.0;  // a few raised vertices: edges and kinks
      m.p_O_m.emplace_back(i * h - 0.05, j * h - 0.05, z);
    }
  }
  // Bottom layer so the mesh is closed enough for Validate; a second sheet 1 mm below.
  const int off = static_cast<int>(m.p_O_m.size());
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.p_O_m.emplace_back(i * h - 0.05, j * h - 0.05, -0.001);
  }
  auto id = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      m.triangles.push_back({off + id(i, j), off + id(i + 1, j + 1), off + id(i + 1, j)});
      m.triangles.push_back({off + id(i, j), off + id(i, j + 1), off + id(i + 1, j + 1)});
    }
  }
  return std::make_shared<const TriMesh>(std::move(m));
}

// SweepSphereTriangle as it was before the per-triangle part moved into SweepTriangle (kept here
// verbatim as the reference).
double OldSweepPoint(const Eigen::Vector3d& m, const Eigen::Vector3d& d, double R) {
  const double c = m.squaredNorm() - R * R;
  if (c < 0.0) return 2.0;
  const double half_b = m.dot(d);
  if (half_b >= -kMinApproach_m * m.norm()) return 2.0;
  const double a = d.squaredNorm();
  const double disc = half_b * half_b - a * c;
  if (disc < 0.0) return 2.0;
  return std::max(0.0, (-half_b - std::sqrt(disc)) / a);
}
double OldSweepSphereTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m, const Eigen::Vector3d& a,
                              const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  double best = 2.0;
  Eigen::Vector3d n = (b - a).cross(c - a);
  const double nn = n.norm();
  if (nn > 0.0) {
    n /= nn;
    const Eigen::Vector3d n_tri = n;
    double h0 = n.dot(x - a);
    if (h0 < 0.0) {
      n = -n;
      h0 = -h0;
    }
    const double vn = n.dot(d);
    if (h0 >= R_m && vn < -kMinApproach_m) {
      const double s = (h0 - R_m) / -vn;
      if (s <= 1.0) {
        const Eigen::Vector3d q = x + s * d - R_m * n;
        const double wa = (b - q).cross(c - q).dot(n_tri);
        const double wb = (c - q).cross(a - q).dot(n_tri);
        const double wc = (a - q).cross(b - q).dot(n_tri);
        if (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) best = s;
      }
    }
  }
  const Eigen::Vector3d* v[3] = {&a, &b, &c};
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3d& p0 = *v[e];
    const Eigen::Vector3d& p1 = *v[(e + 1) % 3];
    const Eigen::Vector3d ed = p1 - p0;
    const double len2 = ed.squaredNorm();
    if (!(len2 > 0.0)) continue;
    const Eigen::Vector3d m = x - p0;
    const Eigen::Vector3d m_perp = m - (m.dot(ed) / len2) * ed;
    const Eigen::Vector3d d_perp = d - (d.dot(ed) / len2) * ed;
    if (d_perp.squaredNorm() <= 0.0) continue;
    const double s = OldSweepPoint(m_perp, d_perp, R_m);
    if (s < best) {
      const double t = (m + s * d).dot(ed) / len2;
      if (t >= 0.0 && t <= 1.0) best = s;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const double s = OldSweepPoint(x - *v[k], d, R_m);
    if (s < best) best = s;
  }
  return best;
}

TEST(Shortcuts, PreparedTriangleSweepEqualsTheOldSweepBitForBit) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  int hits = 0, grazing = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    const Eigen::Vector3d a(u(rng), u(rng), 0.0), c(u(rng), u(rng), 0.0);
    Eigen::Vector3d b(u(rng), u(rng), 0.2 * u(rng));
    Eigen::Vector3d x(u(rng), u(rng), 0.003 + std::abs(u(rng)));
    Eigen::Vector3d d(u(rng), u(rng), -std::abs(u(rng)));
    double R = 0.004;
    if (trial % 4 == 1) {  // resting on the z = 0 plane at exactly R, moving along it (grazing)
      x.z() = R;
      d.z() = 0.0;
      ++grazing;
    }
    if (trial % 4 == 2) d *= 1e-3;           // short moves
    if (trial % 50 == 3) b = a + 0.5 * (c - a);  // degenerate (collinear) triangle
    const double old_s = OldSweepSphereTriangle(x, d, R, a, b, c);
    const double new_s = SweepSphereTriangle(x, d, R, MakeSweepTriangle(a, b, c));
    // A touch on the way (s <= 1) is the same bits; a miss is any value beyond 1 (the new sweep
    // skips an edge whose foot stays beyond one end of it, whose root could only lie beyond 1).
    if (old_s <= 1.0 || new_s <= 1.0) {
      ASSERT_EQ(std::memcmp(&old_s, &new_s, sizeof(double)), 0) << "trial " << trial << ": " << old_s << " vs " << new_s;
    }
    hits += old_s <= 1.0 ? 1 : 0;
  }
  EXPECT_GT(hits, 20000);  // many of the random sweeps touch
  EXPECT_GT(grazing, 40000);
}

// Random triangles within 1 cm of the origin, nearly flat in z, with degenerate (collinear)
// ones and ones with a zero-length edge among them: the lane passes' inputs.
std::vector<SweepTriangle> RandomLaneTriangles(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  std::vector<SweepTriangle> tris;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d a(u(rng), u(rng), 0.2 * u(rng)), c(u(rng), u(rng), 0.2 * u(rng));
    Eigen::Vector3d b(u(rng), u(rng), 0.2 * u(rng));
    if (i % 50 == 3) b = a + 0.5 * (c - a);  // degenerate (collinear)
    if (i % 97 == 5) b = a;                  // a zero-length edge
    tris.push_back(MakeSweepTriangle(a, b, c));
  }
  return tris;
}

// The batch sweep (eight triangles per AVX-512 pass) is the fold of the one-triangle sweep bit
// for bit: random triangles around random moves (grazing, short, degenerate, with any owned
// vertices), in batches of 1 to 19 so that partial groups of lanes are exercised.
TEST(Shortcuts, BatchSweepEqualsTheOneAtATimeFoldBitForBit) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  std::vector<SweepTriangle> tris = RandomLaneTriangles(rng, 4000);
  for (SweepTriangle& t : tris) t.own_vertices = static_cast<std::uint8_t>(rng() % 8);
  std::vector<std::int32_t> ids(19);
  int hits = 0, batches = 0;
  for (int trial = 0; trial < 30000; ++trial) {
    Eigen::Vector3d x(u(rng), u(rng), 0.003 + std::abs(u(rng)));
    Eigen::Vector3d d(u(rng), u(rng), -std::abs(u(rng)));
    if (trial % 4 == 1) {  // at exactly R above the z = 0 plane, moving along it
      x.z() = 0.004;
      d.z() = 0.0;
    }
    if (trial % 4 == 2) d *= 1e-3;
    const auto n = static_cast<std::int32_t>(1 + trial % 19);
    for (std::int32_t i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(rng() % tris.size());
    const double batch = SweepSphereTrianglesOwned(x, d, 0.004, tris.data(), ids.data(), n, true);
    const double fold = SweepSphereTrianglesOwned(x, d, 0.004, tris.data(), ids.data(), n, false);
    ASSERT_EQ(std::memcmp(&batch, &fold, sizeof(double)), 0) << "trial " << trial << ": " << batch << " vs " << fold;
    hits += batch <= 1.0 ? 1 : 0;
    ++batches;
  }
  EXPECT_GT(hits, batches / 10);  // many batches touch something on the way
}

// The lane distance filter of the constraint collection keeps every triangle within r of the
// point (by the exact closest point), in order, and drops the ones clearly beyond.
TEST(Shortcuts, TrianglesWithinKeepsEveryTriangleInReachAndDropsTheRest) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  const std::vector<SweepTriangle> tris = RandomLaneTriangles(rng, 2000);
  std::vector<std::int32_t> ids(21), out(21 + 8);
  long kept = 0, dropped = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    const double r = 0.002 + 0.004 * std::abs(u(rng)) / 0.01;
    const auto n = static_cast<std::int32_t>(1 + trial % 21);
    for (std::int32_t i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(rng() % tris.size());
    const std::int32_t k = TrianglesWithin(x, r, tris.data(), ids.data(), n, out.data());
    std::int32_t j = 0;  // walks out[] alongside: kept ids in their order
    for (std::int32_t i = 0; i < n; ++i) {
      const SweepTriangle& t = tris[static_cast<std::size_t>(ids[static_cast<std::size_t>(i)])];
      const double dist = (x - ClosestPointOnTriangle(x, t.v[0], t.v[1], t.v[2])).norm();
      const bool is_kept = j < k && out[static_cast<std::size_t>(j)] == ids[static_cast<std::size_t>(i)];
      if (is_kept) ++j;
      if (dist <= r) {
        ASSERT_TRUE(is_kept) << "trial " << trial << ": a triangle " << dist << " from x dropped";
      }
      if (dist > r * (1.0 + 1e-6)) {
        EXPECT_FALSE(is_kept) << "trial " << trial << ": kept at " << dist << " > " << r;
      }
      (is_kept ? kept : dropped) += 1;
    }
    ASSERT_EQ(j, k);
  }
  EXPECT_GT(kept, 1000);
  EXPECT_GT(dropped, 1000);
}

// Each vertex swept once, by its owner: over the triangles a ball around a segment reaches (the
// proxy's candidates), the first touch on the way is the same bits as with every triangle's three
// vertices.
TEST(Shortcuts, SweepingEachVertexOnceByItsOwnerFindsTheSameFirstTouch) {
  const std::shared_ptr<const TriMesh> meshes[] = {std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.003, 5)),
                                                   WavyPlate()};
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0, vertex_hits = 0;
  for (const auto& mesh : meshes) {
    MeshCollider collider(mesh, 4096);
    std::vector<std::int32_t> ids(4096);
    for (int trial = 0; trial < 4000; ++trial) {
      // A sphere of R = 8 mm starting 0-1 mm off the surface near a random vertex, moving up to
      // 2 mm in a random direction.
      const Eigen::Vector3d& v = mesh->p_O_m[static_cast<std::size_t>(rng() % mesh->p_O_m.size())];
      const Eigen::Vector3d out = mesh == meshes[0] ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d(0, 0, 1);
      const double R = 0.008;
      const Eigen::Vector3d x = v + (R + 0.001 * (0.5 + 0.5 * u(rng))) * out + 0.004 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Eigen::Vector3d d = 0.002 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const BallQueryResult r = collider.QueryBall(x + 0.5 * d, 0.5 * d.norm() + R + 1e-5, ids);
      ASSERT_FALSE(r.truncated);
      double all = 2.0, owned = 2.0, no_vertices = 2.0;
      for (std::int32_t i = 0; i < r.count; ++i) {
        const SweepTriangle& t = collider.triangle(ids[static_cast<std::size_t>(i)]);
        all = std::min(all, SweepSphereTriangle(x, d, R, t));
        owned = std::min(owned, SweepSphereTriangleOwned(x, d, R, t));
        SweepTriangle faces_and_edges = t;
        faces_and_edges.own_vertices = 0;
        no_vertices = std::min(no_vertices, SweepSphereTriangleOwned(x, d, R, faces_and_edges));
      }
      // The first touch on the way (s <= 1), or none (any value > 1: a root beyond the move).
      if (all > 1.0) all = 2.0;
      if (owned > 1.0) owned = 2.0;
      if (no_vertices > 1.0) no_vertices = 2.0;
      ASSERT_EQ(std::memcmp(&all, &owned, sizeof(double)), 0) << "trial " << trial << ": " << all << " vs " << owned;
      hits += all <= 1.0 ? 1 : 0;
      vertex_hits += all <= 1.0 && no_vertices != all ? 1 : 0;
    }
  }
  EXPECT_GT(hits, 1000);      // many sweeps touch
  EXPECT_GT(vertex_hits, 20);  // and some first at a vertex, where the owners matter
}

// The walk without the leaves' exact distance (what the proxy's neighbourhoods are filled with)
// returns every triangle the exact walk returns, in the same order, and only triangles whose
// plane-and-disc bound reaches the ball.
TEST(Shortcuts, TheInexactWalkHoldsTheExactOneInItsOrder) {
  const auto mesh = std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.003, 5));
  const MeshCollider collider(mesh, 4096);
  std::mt19937 rng(31);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::int32_t> exact(4096), loose(4096);
  long extra = 0, found = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Vector3d c = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized() * (0.05 + 0.01 * g(rng));
    const double r = 0.002 + 0.01 * std::abs(g(rng));
    const BallQueryResult e = collider.QueryBall(c, r, exact);
    const BallQueryResult l = collider.QueryBall(c, r, loose, /*exact=*/false);
    ASSERT_FALSE(e.truncated || l.truncated);
    std::int32_t k = 0;  // exact's ids as a subsequence of loose's
    for (std::int32_t i = 0; i < l.count; ++i) {
      const std::int32_t t = loose[static_cast<std::size_t>(i)];
      if (k < e.count && exact[static_cast<std::size_t>(k)] == t) {
        ++k;
        continue;
      }
      ++extra;
      const double h = PlaneDistance(collider.triangle_plane(t), c);
      EXPECT_FALSE(BeyondTriangle(collider.triangle_disc(t), c, h, r)) << "trial " << trial << " triangle " << t;
    }
    ASSERT_EQ(k, e.count) << "trial " << trial;
    found += e.count;
  }
  EXPECT_GT(found, 10000);
  EXPECT_GT(extra, 0);
}

// The smallest trees: one triangle (the wide root holds the leaf itself), two and three.
TEST(Shortcuts, TheWalkFindsTheTrianglesOfTinyMeshes) {
  for (int n = 1; n <= 3; ++n) {
    auto mesh = std::make_shared<TriMesh>();
    for (int t = 0; t < n; ++t) {
      const double x = 0.01 * t;
      const auto base = static_cast<std::int32_t>(mesh->p_O_m.size());
      mesh->p_O_m.push_back(Eigen::Vector3d(x, 0, 0));
      mesh->p_O_m.push_back(Eigen::Vector3d(x + 0.005, 0, 0));
      mesh->p_O_m.push_back(Eigen::Vector3d(x, 0.005, 0));
      mesh->triangles.push_back({base, base + 1, base + 2});
    }
    MeshCollider collider(mesh, 16);
    std::vector<std::int32_t> a(16), b(16);
    for (int t = 0; t < n; ++t) {
      // A ball over triangle t only, then one over all of them.
      const BallQueryResult one = collider.QueryBall(Eigen::Vector3d(0.01 * t + 0.001, 0.001, 0.002), 0.003, a);
      ASSERT_EQ(one.count, 1) << n << " triangles, ball over " << t;
      EXPECT_EQ(a[0], t);
    }
    const BallQueryResult all = collider.QueryBall(Eigen::Vector3d(0.01, 0, 0), 0.05, a);
    const BallQueryResult ref = collider.QueryBallObb(Eigen::Vector3d(0.01, 0, 0), 0.05, b);
    ASSERT_EQ(all.count, n);
    ASSERT_EQ(ref.count, n);
    EXPECT_EQ(a, b);
    EXPECT_EQ(collider.QueryBall(Eigen::Vector3d(1, 1, 1), 0.01, a).count, 0);
  }
}

TEST(Shortcuts, CompactTreeWalkReturnsTheObbWalksTrianglesInTheSameOrder) {
  const std::shared_ptr<const TriMesh> meshes[] = {std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.003, 5)),
                                                   WavyPlate()};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.065, 0.065);
  std::uniform_real_distribution<double> ur(0.0, 0.02);
  long total = 0, truncations = 0;
  for (const auto& mesh : meshes) {
    MeshCollider collider(mesh, 4096);
    for (int trial = 0; trial < 3000; ++trial) {
      Eigen::Vector3d c(u(rng), u(rng), u(rng));
      if (trial % 3 == 0) {  // near the surface, where the proxy queries are
        const auto& tr = mesh->triangles[static_cast<std::size_t>(rng() % mesh->triangles.size())];
        c = mesh->p_O_m[tr[0]] + Eigen::Vector3d(ur(rng), ur(rng), ur(rng)) * 0.5 - Eigen::Vector3d::Constant(0.005);
      }
      const double r = trial % 10 == 0 ? 1e-5 : 0.0005 + ur(rng);
      // Several buffer sizes so that truncation happens at the same triangle too.
      for (const std::size_t cap : {std::size_t{4096}, std::size_t{7}}) {
        std::vector<std::int32_t> a(cap, -7), b(cap, -7);
        const BallQueryResult ra = collider.QueryBall(c, r, a);
        const BallQueryResult rb = collider.QueryBallObb(c, r, b);
        ASSERT_EQ(ra.count, rb.count) << "trial " << trial;
        ASSERT_EQ(ra.truncated, rb.truncated) << "trial " << trial;
        ASSERT_EQ(a, b) << "trial " << trial;
        total += ra.count;
        truncations += ra.truncated ? 1 : 0;
      }
    }
  }
  EXPECT_GT(total, 100000);    // the queries hit many triangles
  EXPECT_GT(truncations, 500);  // and the small buffer overflowed often
}

// Random fingertip paths (sliding, pressing, diving through, jumping) with friction, two fingers
// on each of two meshes served by one solver in turn (as HapticWorld does): every Step's contact
// and proxy state equal the reference path's exactly, with the neighbourhoods culled eight
// triangles at a time (where the processor has AVX-512) and one at a time.
TEST(Shortcuts, ProxyStepsEqualTheExactPathOnRandomPaths) {
  const std::shared_ptr<const TriMesh> meshes[] = {std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.003, 5)),
                                                   WavyPlate()};
  MeshCollider colliders[] = {MeshCollider(meshes[0], 512), MeshCollider(meshes[1], 512)};
  ProxySolver fast(512), ref(512), scalar(512);
  ref.set_reference_path(true);
  scalar.set_vector_cull(false);
  ProxyParams params;
  const FrictionParams friction{0.6, 0.5};
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  long touching = 0, sticking = 0, steps = 0, iterations = 0;
  constexpr int kTips = 4;  // fingers 0, 1 on the sphere, 2, 3 on the plate
  for (int path = 0; path < 40; ++path) {
    ProxyState sf[kTips], sr[kTips], ss[kTips];  // ss: the scalar cull's
    Eigen::Vector3d goal[kTips], inward[kTips], vel[kTips];
    for (int f = 0; f < kTips; ++f) {
      // Start above the surface, then a random walk with a drift into it.
      goal[f] = f < 2 ? Eigen::Vector3d(Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized() * 0.06)
                      : Eigen::Vector3d(0.03 * g(rng), 0.03 * g(rng), 0.009);
      inward[f] = f < 2 ? Eigen::Vector3d(-goal[f].normalized()) : Eigen::Vector3d(0, 0, -1);
      vel[f] = 1e-4 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    }
    for (int k = 0; k < 400; ++k) {
      for (int f = 0; f < kTips; ++f) {
        vel[f] = 0.9 * vel[f] + 3e-5 * Eigen::Vector3d(g(rng), g(rng), g(rng)) + 2e-5 * inward[f];
        if (k % 97 == 50) vel[f] *= 20.0;  // a fast dive (up to a few mm per step)
        if (k % 131 == 70 + f) vel[f].setZero();  // held still: sticking
        goal[f] += vel[f];
        MeshCollider& collider = colliders[f / 2];
        const ProxyContact cf = fast.Step(collider, params, friction, goal[f], sf[f]);
        const ProxyContact cr = ref.Step(collider, params, friction, goal[f], sr[f]);
        const ProxyContact cs = scalar.Step(collider, params, friction, goal[f], ss[f]);
        ASSERT_TRUE(SameBits(cs.x_O_m, cr.x_O_m)) << "scalar cull, finger " << f << " path " << path << " step " << k;
        ASSERT_TRUE(SameBits(cs.n_O, cr.n_O)) << "scalar cull, finger " << f << " path " << path << " step " << k;
        ASSERT_TRUE(SameBits(cf.x_O_m, cr.x_O_m)) << "finger " << f << " path " << path << " step " << k;
        ASSERT_TRUE(SameBits(cf.p_O_m, cr.p_O_m)) << "finger " << f << " path " << path << " step " << k;
        ASSERT_TRUE(SameBits(cf.n_O, cr.n_O)) << "finger " << f << " path " << path << " step " << k;
        ASSERT_EQ(std::memcmp(&cf.depth_m, &cr.depth_m, sizeof(double)), 0);
        ASSERT_EQ(cf.touching, cr.touching);
        ASSERT_EQ(cf.sticking, cr.sticking);
        ASSERT_EQ(cf.truncated, cr.truncated);
        ASSERT_EQ(cf.triangle, cr.triangle);
        ASSERT_EQ(cf.iterations, cr.iterations);
        ASSERT_TRUE(SameBits(sf[f].x_O_m, sr[f].x_O_m));
        ASSERT_EQ(sf[f].in_contact, sr[f].in_contact);
        ASSERT_EQ(sf[f].sliding, sr[f].sliding);
        ++steps;
        touching += cf.touching ? 1 : 0;
        sticking += cf.sticking ? 1 : 0;
        iterations += cf.iterations;
      }
    }
  }
  // The paths exercised contact, sticking and multi-round moves.
  EXPECT_GT(touching, steps / 4);
  EXPECT_GT(sticking, 100);
  EXPECT_GT(iterations, steps);
}

// Meshes of any size: a 20 m box and a 2 m icosphere (triangles metres across, whose discs'
// float round-off is far above a table-top mesh's), fingertips sliding over their corners, edges
// and faces: every step equals the reference path's.
TEST(Shortcuts, ProxyStepsOnLargeMeshesEqualTheExactPath) {
  const std::shared_ptr<const TriMesh> meshes[] = {
      std::make_shared<const TriMesh>(MakeBoxMesh(Eigen::Vector3d(20.0, 20.0, 20.0))),
      std::make_shared<const TriMesh>(MakeIcosphere(2.0, 1))};
  ProxySolver fast(512), ref(512);
  ref.set_reference_path(true);
  ProxyParams params;
  const FrictionParams friction{0.6, 0.5};
  std::mt19937 rng(37);
  std::normal_distribution<double> g(0.0, 1.0);
  long touching = 0, steps = 0;
  for (const auto& mesh : meshes) {
    MeshCollider collider(mesh, 512);
    for (int path = 0; path < 60; ++path) {
      // From just outside a random vertex, drifting in and sliding along the surface.
      const Eigen::Vector3d& v = mesh->p_O_m[static_cast<std::size_t>(rng() % mesh->p_O_m.size())];
      const Eigen::Vector3d out = v.normalized();
      Eigen::Vector3d goal = v + (params.radius_m + 0.002) * out + 0.004 * Eigen::Vector3d(g(rng), g(rng), g(rng));
      ProxyState sf, sr;
      for (int k = 0; k < 200; ++k) {
        goal += 1e-4 * Eigen::Vector3d(g(rng), g(rng), g(rng)) - 3e-5 * out;
        const ProxyContact cf = fast.Step(collider, params, friction, goal, sf);
        const ProxyContact cr = ref.Step(collider, params, friction, goal, sr);
        ASSERT_TRUE(SameBits(cf.x_O_m, cr.x_O_m)) << "path " << path << " step " << k;
        ASSERT_EQ(cf.touching, cr.touching);
        ASSERT_EQ(cf.triangle, cr.triangle);
        touching += cf.touching ? 1 : 0;
        ++steps;
      }
    }
  }
  EXPECT_GT(touching, steps / 4);
}

}  // namespace
}  // namespace handshare::contact
