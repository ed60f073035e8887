// Exact sphere sweep and closest point against brute-force sampling, and the FCL ball query
// against a brute-force scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <iterator>
#include <map>
#include <set>

#include "handshare/contact/geometry.hpp"
#include "handshare/contact/mesh_collider.hpp"
#include "handshare/contact/tri_mesh.hpp"

namespace handshare::contact {
namespace {

double DistToTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Vector3d& c) {
  return (p - ClosestPointOnTriangle(p, a, b, c)).norm();
}

TEST(Geometry, ClosestPointIsNoFartherThanAnySampledPointOfTheTriangle) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Eigen::Vector3d p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const double d = DistToTriangle(p, a, b, c);
    double best = 1e9;
    for (int i = 0; i <= 60; ++i) {
      for (int j = 0; i + j <= 60; ++j) {
        const Eigen::Vector3d q = a + (b - a) * (i / 60.0) + (c - a) * (j / 60.0);
        best = std::min(best, (p - q).norm());
      }
    }
    // Sampling grid of 1/60 of the edges: the true minimum is at most that far below a sample.
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - 2.0 * 2.0 * std::sqrt(3.0) / 60.0);
  }
}

TEST(Geometry, SweptSphereStopsExactlyAtFirstTouch) {
  // Oracle: bisection on the exact distance along the path (the distance is continuous; we
  // start outside and the sweep claims the first time it reaches R).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double R = 0.3;
  int hits = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Vector3d a(u(rng), u(rng), 0.2 * u(rng)), b(u(rng), u(rng), 0.2 * u(rng)),
        c(u(rng), u(rng), 0.2 * u(rng));
    const Eigen::Vector3d x(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const Eigen::Vector3d d(3 * u(rng), 3 * u(rng), 3 * u(rng));
    if (DistToTriangle(x, a, b, c) <= R) continue;
    const double s = SweepSphereTriangle(x, d, R, a, b, c);
    // Dense scan for the first sample that is inside R.
    double first = 2.0;
    for (int k = 0; k <= 4000; ++k) {
      if (DistToTriangle(x + (k / 4000.0) * d, a, b, c) < R) {
        first = k / 4000.0;
        break;
      }
    }
    if (s <= 1.0) {
      ++hits;
      EXPECT_NEAR(DistToTriangle(x + s * d, a, b, c), R, 1e-9) << trial;
      // No sample before s is inside (step 1/4000 of the path).
      EXPECT_GE(first, s - 1.0 / 4000.0) << trial;
    } else {
      EXPECT_EQ(first, 2.0) << "missed a touch at s = " << first << " trial " << trial;
    }
  }
  EXPECT_GT(hits, 40);  // enough touching paths for the check to mean something
}

TEST(Geometry, FclBallQueryFindsEveryTriangleThatTheBallTouches) {
  auto mesh = std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.004, 4));
  MeshCollider collider(mesh, 4096);
  std::vector<std::int32_t> ids(4096);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng));
    const double r = 0.003 + 0.01 * (trial % 5);
    const BallQueryResult res = collider.QueryBall(c, r, ids);
    ASSERT_FALSE(res.truncated);
    std::set<std::int32_t> got(ids.begin(), ids.begin() + res.count);
    // FCL's own sphere-mesh collide agrees (its sphere-triangle test, our traversal).
    std::vector<std::int32_t> ids_fcl(4096);
    const BallQueryResult res_fcl = collider.QueryBallFcl(c, r, ids_fcl);
    std::set<std::int32_t> got_fcl(ids_fcl.begin(), ids_fcl.begin() + res_fcl.count);
    std::vector<std::int32_t> diff;
    std::set_symmetric_difference(got.begin(), got.end(), got_fcl.begin(), got_fcl.end(), std::back_inserter(diff));
    for (std::int32_t t : diff) {
      const auto& tr = mesh->triangles[static_cast<std::size_t>(t)];
      // Only triangles within FCL's tolerance of the sphere surface may differ.
      EXPECT_NEAR(DistToTriangle(c, mesh->p_O_m[tr[0]], mesh->p_O_m[tr[1]], mesh->p_O_m[tr[2]]), r, 1e-6);
    }
    for (std::int32_t t = 0; t < mesh->num_triangles(); ++t) {
      const auto& tr = mesh->triangles[static_cast<std::size_t>(t)];
      const double d = DistToTriangle(c, mesh->p_O_m[tr[0]], mesh->p_O_m[tr[1]], mesh->p_O_m[tr[2]]);
      // FCL's sphere-triangle test: exact up to its own tolerance; 1 um either way is ignored.
      if (d < r - 1e-6) {
        EXPECT_TRUE(got.count(t)) << "triangle " << t << " at " << d << " < " << r;
      }
      if (d > r + 1e-6) {
        EXPECT_FALSE(got.count(t)) << "triangle " << t << " at " << d << " > " << r;
      }
    }
  }
}

// The disc bound that lets the proxy and the ball query skip exact tests (DiscDistanceBound2 on
// MeshCollider::triangle_disc) is a lower bound: points near a bumpy sphere (where the bound is
// tight: the tilted neighbours of the face under the point) and far from it.
TEST(Geometry, TheDiscBoundIsNeverAboveTheDistanceToTheTriangle) {
  auto mesh = std::make_shared<const TriMesh>(MakeBumpySphere(0.05, 0.004, 3));
  const MeshCollider collider(mesh, 64);
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  int tight = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    const Eigen::Vector3d p = dir * (trial % 2 ? 0.05 + 0.01 * std::abs(g(rng)) : 0.1 * std::abs(g(rng)));
    for (std::int32_t t = 0; t < mesh->num_triangles(); ++t) {
      const auto& tr = mesh->triangles[static_cast<std::size_t>(t)];
      const double d = DistToTriangle(p, mesh->p_O_m[tr[0]], mesh->p_O_m[tr[1]], mesh->p_O_m[tr[2]]);
      const Eigen::Vector4d& pl = collider.triangle_plane(t);
      const double h = pl.head<3>().dot(p) - pl.w();
      const double bound2 = DiscDistanceBound2(collider.triangle_disc(t), p, h);
      ASSERT_LE(bound2, d * d * (1.0 + 1e-12) + 1e-24) << "triangle " << t << " trial " << trial;
      if (bound2 > 0.25 * d * d) ++tight;
    }
  }
  // And it bounds: most pairs get more than half the distance (a bound of 0 would pass above).
  EXPECT_GT(tight, 400 * mesh->num_triangles() / 2);
}

TEST(Geometry, MeshesAreValidAndClosed) {
  for (const TriMesh& m : {MakeIcosphere(0.02, 3), MakeBoxMesh({0.1, 0.1, 0.001}), MakeBumpySphere(0.05, 0.004, 5)}) {
    EXPECT_NO_THROW(m.Validate());
    std::map<std::pair<int, int>, int> edges;
    for (const auto& t : m.triangles) {
      for (int e = 0; e < 3; ++e) ++edges[{t[e], t[(e + 1) % 3]}];
    }
    for (const auto& [e, n] : edges) {
      EXPECT_EQ(n, 1);
      EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "open or inconsistently wound edge";
    }
  }
  EXPECT_EQ(MakeBumpySphere(0.05, 0.004, 5).num_triangles(), 20480);
  EXPECT_THROW(MakeBoxMesh({0.1, -1.0, 0.1}), std::invalid_argument);
}

}  // namespace
}  // namespace handshare::contact
