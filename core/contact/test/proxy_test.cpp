// The proxy (IHIP) must stay on the surface: a fingertip driven through a 1 mm plate at 0.5 m/s
// at 1 kHz (faces, edges, corners, oblique) never drags it through, and the penetration vector and
// force point the right way.
#include <gtest/gtest.h>

#include <cmath>

#include "handshare/contact/haptic_world.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;       // HIRO II fingertip radius
constexpr double kHalfT = 0.0005;  // plate: 1 mm thick
constexpr double kHalfW = 0.05;    // 10 cm wide
constexpr double kDt = 1e-3;       // 1 kHz
constexpr double kSpeed = 0.5;     // m/s

struct PlateRun {
  double min_proxy_z = 1e9;        // lowest proxy centre seen
  double max_proxy_below = -1e9;   // proxy centre below the plate's top + R (should not happen)
  int wrong_direction = 0;         // steps with force not along +z-ish or e not pointing down
  int contact_steps = 0;
};

// Drives fingertip 0 from `from` to `to` at kSpeed and checks every step.
PlateRun DriveThrough(const Shape& plate, const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  HapticWorld w;
  RigidMaterial mat;
  mat.mu_static = 0.0;
  mat.mu_kinetic = 0.0;
  w.AddStatic(plate, mat, Eigen::Isometry3d::Identity());
  w.Init();
  PlateRun run;
  const double len = (to - from).norm();
  const int steps = static_cast<int>(std::ceil(len / (kSpeed * kDt)));
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector3d p = from + (to - from) * (static_cast<double>(k) / steps);
    const auto tips = test::OneFinger(p);
    w.Step(kDt, tips);
    const FingerResult& r = w.fingers()[0];
    run.min_proxy_z = std::min(run.min_proxy_z, r.p_WP_m.z());
    if (!r.in_contact) continue;
    ++run.contact_steps;
    // The proxy is a sphere of radius R on the top side: its centre never comes closer than R to
    // the plate (1 um skin), and once the fingertip is below the top, it is above it.
    const double gap = r.p_WP_m.z() - kHalfT;
    const bool over_plate = std::abs(r.p_WP_m.x()) <= kHalfW && std::abs(r.p_WP_m.y()) <= kHalfW;
    if (over_plate) run.max_proxy_below = std::max(run.max_proxy_below, (kR - gap));
    if (r.f_E_W_N.z() < 0.0 || r.e_PE_W_m.z() > 0.0 ||
        std::abs(r.f_E_W_N.normalized().dot(-r.e_PE_W_m.normalized())) < 0.99) {
      ++run.wrong_direction;  // force on the fingertip pushes up, e points from proxy down to E
    }
  }
  return run;
}

Shape Plate() { return Shape::Box({2 * kHalfW, 2 * kHalfW, 2 * kHalfT}); }

TEST(Proxy, NeverPassesThroughOneMillimetrePlateAtHalfMetrePerSecond) {
  // Straight down through the middle, from 3 cm above to 5 cm below.
  const PlateRun run = DriveThrough(Plate(), {0.01, 0.02, 0.03}, {0.01, 0.02, -0.05});
  EXPECT_GT(run.contact_steps, 100);
  // Proxy centre stays R above the top (a 1 um skin; 1e-9 m round-off).
  EXPECT_LE(run.max_proxy_below, 1e-9);
  EXPECT_GE(run.min_proxy_z, kHalfT + kR - 1e-9);
  EXPECT_EQ(run.wrong_direction, 0);
}

TEST(Proxy, NeverPassesThroughThePlateAtAnEdgeOrACorner) {
  // The fingertip overhangs the edge (centre 2 mm inside it), then the corner.
  for (const Eigen::Vector3d& xy : {Eigen::Vector3d(kHalfW - 0.002, 0.0, 0.0),
                                   Eigen::Vector3d(kHalfW - 0.002, kHalfW - 0.002, 0.0),
                                   Eigen::Vector3d(kHalfW - 0.0001, 0.01, 0.0)}) {
    const PlateRun run = DriveThrough(Plate(), xy + Eigen::Vector3d(0, 0, 0.03), xy + Eigen::Vector3d(0, 0, -0.05));
    EXPECT_GT(run.contact_steps, 100);
    EXPECT_LE(run.max_proxy_below, 1e-9) << xy.transpose();
    EXPECT_GE(run.min_proxy_z, kHalfT - 1e-9) << "proxy went under the plate at " << xy.transpose();
  }
}

TEST(Proxy, ObliqueAndSlidingMotionsStayOnTop) {
  // Oblique dive through the plate, then a slide under it past the edge: the proxy follows on
  // top and wraps around the edge (it never crosses the 1 mm of material).
  HapticWorld w;
  w.AddStatic(Plate(), RigidMaterial{1000.0, 0.0, 0.0, 0.0}, Eigen::Isometry3d::Identity());
  w.Init();
  Eigen::Vector3d p(0.0, 0.0, 0.02);
  const Eigen::Vector3d path[] = {{0.02, 0.0, -0.01}, {0.07, 0.0, -0.01}, {0.07, 0.0, -0.03}};
  bool wrapped = false;
  for (const Eigen::Vector3d& target : path) {
    while ((target - p).norm() > 1e-9) {
      const Eigen::Vector3d step = target - p;
      p += step * std::min(1.0, kSpeed * kDt / step.norm());
      w.Step(kDt, test::OneFinger(p));
      const FingerResult& r = w.fingers()[0];
      const Eigen::Vector3d x = r.p_WP_m;
      // Distance from the proxy centre to the plate (a box): never below R.
      const Eigen::Vector3d q = x.cwiseMax(Eigen::Vector3d(-kHalfW, -kHalfW, -kHalfT))
                                    .cwiseMin(Eigen::Vector3d(kHalfW, kHalfW, kHalfT));
      ASSERT_GE((x - q).norm(), kR - 1e-9) << "proxy inside the plate at " << x.transpose();
      // Under the plate only after wrapping round the edge (x beyond the plate).
      if (x.z() < 0.0) {
        ASSERT_GT(x.x(), kHalfW - 1e-9) << "proxy popped through at " << x.transpose();
        wrapped = true;
      }
    }
  }
  EXPECT_TRUE(wrapped);  // the fingertip ended under and beyond the plate: the proxy followed
  EXPECT_FALSE(w.fingers()[0].in_contact);  // and is free again (fingertip 2 cm below, 2 cm out)
}

TEST(Proxy, FastDiveThroughTheEdgeOfAFineMeshPlateAndAVertexOfASphere) {
  // A triangulated plate with many small triangles (edges everywhere) and a coarse icosphere
  // (sharp vertices): same invariant, proxy never overlaps.
  auto fine = std::make_shared<TriMesh>();
  const int n = 40;
  for (int s = 0; s < 2; ++s)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        fine->p_O_m.emplace_back(-kHalfW + 2 * kHalfW * i / n, -kHalfW + 2 * kHalfW * j / n, s ? kHalfT : -kHalfT);
  auto id = [&](int s, int i, int j) { return static_cast<std::int32_t>(s * (n + 1) * (n + 1) + j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      fine->triangles.push_back({id(1, i, j), id(1, i + 1, j), id(1, i + 1, j + 1)});
      fine->triangles.push_back({id(1, i, j), id(1, i + 1, j + 1), id(1, i, j + 1)});
      fine->triangles.push_back({id(0, i, j), id(0, i + 1, j + 1), id(0, i + 1, j)});
      fine->triangles.push_back({id(0, i, j), id(0, i, j + 1), id(0, i + 1, j + 1)});
    }
  // Straight through a shared edge and a shared vertex of the top triangulation.
  for (const Eigen::Vector3d& xy : {Eigen::Vector3d(0.0025, 0.001, 0), Eigen::Vector3d(0.0, 0.0, 0)}) {
    const PlateRun run = DriveThrough(Shape::Mesh(fine), xy + Eigen::Vector3d(0, 0, 0.02), xy + Eigen::Vector3d(0, 0, -0.04));
    EXPECT_GT(run.contact_steps, 80);
    EXPECT_LE(run.max_proxy_below, 1e-9);
    EXPECT_EQ(run.wrong_direction, 0);
  }
  // Icosahedron (no subdivision): dive at a vertex, at 0.5 m/s, to 3 cm past the centre.
  HapticWorld w;
  const double r = 0.03;
  w.AddStatic(Shape::Sphere(r, 0), RigidMaterial{1000.0, 0.0, 0.0, 0.0}, Eigen::Isometry3d::Identity());
  w.Init();
  const Eigen::Vector3d v = MakeIcosphere(r, 0).p_O_m[0].normalized();
  for (int k = 0; k <= 160; ++k) {
    const Eigen::Vector3d p = v * (0.05 - kSpeed * kDt * k);
    w.Step(kDt, test::OneFinger(p));
    const FingerResult& res = w.fingers()[0];
    ASSERT_GE(res.p_WP_m.dot(v), r + kR - 1e-9) << "step " << k;  // proxy stays outside the vertex
    if (res.in_contact) {
      ASSERT_GT(res.f_E_W_N.dot(v), 0.0);
    }
  }
}

}  // namespace
}  // namespace handshare::contact
