// Property: on random smooth meshes (icospheres) and bumpy ones (haptic_bench's bumpy sphere,
// randomly sized and turned), along random smooth fingertip paths that go in and out of the
// surface (from 2 cm outside to about 1.5 cm inside, ~0.05-0.15 m/s round the object), the proxy
// is never farther from the fingertip than the surface makes it, over 20,000 steps per case,
// with and without friction.
//
// The bound, per step (fingertip centre g, proxy x):
//   D  = an upper bound on g's distance from the free space (the points outside the surface and
//        at least R + skin from it): the first point q = g + t u (u radial, outward; the meshes
//        are star-shaped about O) found free by bisection (20 halvings) gives D = t; 0 if g is.
//   Frictionless, a converged god-object sits at a local minimum of |x - g| over the free space.
//   For depths under the surface's reach (the offset surface's radii of curvature: >= 48 mm on
//   the spheres, ~25 mm in the bumps; paths reach ~18 mm deep) that is the nearest free point up
//   to the facets: the proxy keeps the face it is on while the fingertip's foot stays on it,
//   though a neighbour across a convex edge of dihedral angle theta may be nearer, by at most
//   the factor cos(theta) (worst with the fingertip straight under the edge, square to the face
//   the proxy is on: d_other = d cos(theta)). So |x - g| <= D / cos(theta).
//   With Coulomb friction (mu_s), a proxy held at x0 satisfies the static test about the
//   frictionless god-object x_f's normal n (ProxySolver::Step): |f_t| <= mu_s f_n with
//   f_n = (x0 - g) . n = |x_f - g| + h, h = (x0 - x_f) . n the height of x0 over the tangent plane
//   at x_f, and f_t = l, the lateral distance of x0 from x_f. So
//   |x0 - g| <= (D / cos(theta) + h) sqrt(1 + mu_s^2), with l <= mu_s (D / cos(theta) + h) and
//   h <= l sin(turn), turn = how far the surface normal turns between x_f and x0, concave turns
//   only (over convex ones x0 lies under the tangent plane): at most one crease alpha plus l over
//   the smallest concave radius rho, h <= l min(1, alpha + l / rho). A slipping proxy ends
//   between x_f and x0 on the kinetic cone (mu_k <= mu_s): the same bound.
//   theta, alpha, rho are the mesh's, taken over the triangles within the gap (+ R + skin + 1 mm)
//   of g, where the proxy, x_f and the nearest free point are (the bumpy sphere's fold at its
//   poles, ~1.4 rad, only counts there).
//   Plus 5 um: the skin (1 um), a proxy that has not converged in its 4 rounds while the
//   fingertip moves 0.1-0.2 mm a step round curved facets, the bisection's resolution.
// A frozen proxy ends 10-14 cm away: before the touch-band fix (a578fdd) all four cases failed
// that way, after it (d86768d) the two with friction.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <span>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/contact/geometry.hpp"
#include "handshare/contact/mesh_collider.hpp"
#include "handshare/contact/proxy.hpp"
#include "handshare/contact/tri_mesh.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;
constexpr double kSkin = 1e-6;
constexpr double kRs = kR + kSkin;
constexpr double kTol = 5e-6;
constexpr int kSteps = 20000;

struct Case {
  std::string name;
  std::shared_ptr<const TriMesh> mesh;
  double r_nominal = 0.05;  // the paths' reference radius
  FrictionParams friction;
  std::uint32_t seed = 1;
};

// Per triangle: the largest convex and concave dihedral angles over its edges, and the smallest
// concave radius of curvature (centroid distance / angle across a concave edge).
struct Dihedral {
  double convex = 0.0, concave = 0.0, concave_radius = std::numeric_limits<double>::infinity();
};
std::vector<Dihedral> Dihedrals(const TriMesh& m) {
  std::vector<Dihedral> out(static_cast<std::size_t>(m.num_triangles()));
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> first;
  auto normal = [&](std::int32_t t) {
    const auto& T = m.triangles[static_cast<std::size_t>(t)];
    return Eigen::Vector3d((m.p_O_m[T[1]] - m.p_O_m[T[0]]).cross(m.p_O_m[T[2]] - m.p_O_m[T[0]]).normalized());
  };
  auto centroid = [&](std::int32_t t) {
    const auto& T = m.triangles[static_cast<std::size_t>(t)];
    return Eigen::Vector3d((m.p_O_m[T[0]] + m.p_O_m[T[1]] + m.p_O_m[T[2]]) / 3.0);
  };
  for (std::int32_t t = 0; t < m.num_triangles(); ++t) {
    const auto& T = m.triangles[static_cast<std::size_t>(t)];
    for (int e = 0; e < 3; ++e) {
      const auto key = std::minmax(T[static_cast<std::size_t>(e)], T[static_cast<std::size_t>((e + 1) % 3)]);
      auto it = first.find(key);
      if (it == first.end()) {
        first.emplace(key, t);
        continue;
      }
      const std::int32_t o = it->second;
      const double a = std::acos(std::clamp(normal(t).dot(normal(o)), -1.0, 1.0));
      Dihedral& dt = out[static_cast<std::size_t>(t)];
      Dihedral& dot = out[static_cast<std::size_t>(o)];
      if (normal(t).dot(centroid(o) - centroid(t)) <= 0.0) {  // convex
        dt.convex = std::max(dt.convex, a);
        dot.convex = std::max(dot.convex, a);
      } else if (a > 0.0) {  // concave: the other centroid lies above this plane
        const double r = (centroid(o) - centroid(t)).norm() / a;
        for (Dihedral* d : {&dt, &dot}) {
          d->concave = std::max(d->concave, a);
          d->concave_radius = std::min(d->concave_radius, r);
        }
      }
    }
  }
  return out;
}

std::shared_ptr<const TriMesh> Turned(TriMesh m, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
  for (auto& p : m.p_O_m) p = q * p;
  return std::make_shared<const TriMesh>(std::move(m));
}

std::vector<Case> Cases() {
  std::vector<Case> out;
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const FrictionParams none{0.0, 0.0}, bench{0.6, 0.5};
  for (const FrictionParams& f : {none, bench}) {
    const bool fr = f.mu_static > 0.0;
    {  // smooth: an icosphere of 1,280 or 5,120 triangles, 4-6 cm
      const double r = 0.04 + 0.02 * U(rng);
      const int sub = fr ? 4 : 3;
      Case c;
      c.name = "icosphere r " + std::to_string(r) + " sub " + std::to_string(sub) + (fr ? ", friction" : "");
      c.mesh = Turned(MakeIcosphere(r, sub), rng);
      c.r_nominal = r;
      c.friction = f;
      c.seed = static_cast<std::uint32_t>(rng());
      out.push_back(c);
    }
    {  // bumpy: haptic_bench's sphere (20,480 triangles), 4.5-5.5 cm, bumps 2-3 mm
      const double r = 0.045 + 0.01 * U(rng);
      const double b = 0.002 + 0.001 * U(rng);
      Case c;
      c.name = "bumpy r " + std::to_string(r) + " bump " + std::to_string(b) + (fr ? ", friction" : "");
      c.mesh = Turned(MakeBumpySphere(r, b, 5), rng);
      c.r_nominal = r;
      c.friction = f;
      c.seed = static_cast<std::uint32_t>(rng());
      out.push_back(c);
    }
  }
  return out;
}

// A smooth random path round the object: direction from turning spherical angles, the centre
// from 2 cm outside the reference sphere (grown by R) to about 1.5 cm inside it and back, eight
// times in 20 s.
struct Path {
  Eigen::Quaterniond turn;
  double th0, a1, a2, w1, w2, p1, p2, wphi, phi0, b1, wphi2, wr, wr2, pr2;
  Path(std::mt19937& rng) {
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::normal_distribution<double> g(0.0, 1.0);
    turn = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
    th0 = 0.6 + 1.9 * U(rng);
    a1 = 0.2 + 0.2 * U(rng);
    a2 = 0.1 * U(rng);
    w1 = 0.5 + U(rng);
    w2 = 1.5 + 2.0 * U(rng);
    p1 = 6.3 * U(rng);
    p2 = 6.3 * U(rng);
    wphi = (U(rng) < 0.5 ? -1.0 : 1.0) * (1.2 + 1.6 * U(rng));  // 1.2-2.8 rad/s: ~0.05-0.15 m/s
    phi0 = 6.3 * U(rng);
    b1 = 0.5 * U(rng);
    wphi2 = 0.7 + U(rng);
    wr = 2.0 * M_PI * (0.3 + 0.2 * U(rng));
    wr2 = 2.0 * M_PI * (0.9 + 0.5 * U(rng));
    pr2 = 6.3 * U(rng);
  }
  Eigen::Vector3d At(int k, double r_ref) const {
    const double t = 1e-3 * k;
    const double th = th0 + a1 * std::sin(w1 * t + p1) + a2 * std::sin(w2 * t + p2) - a1 * std::sin(p1) - a2 * std::sin(p2);
    const double ph = phi0 + wphi * t + b1 * std::sin(wphi2 * t);
    const Eigen::Vector3d u(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const double out = 0.003 + 0.017 * std::cos(wr * t) + 0.003 * (std::sin(wr2 * t + pr2) - std::sin(pr2));
    return turn * (u * (r_ref + kRs + out));
  }
};

struct Result {
  double worst_excess = -1.0;  // largest gap - bound
  double worst_gap = 0.0, worst_bound = 0.0, max_gap = 0.0, max_depth = 0.0;
  int worst_step = -1;
  long contact_steps = 0, sticking_steps = 0;
  double theta = 0.0, alpha = 0.0;  // the largest local dihedral angles the bound used
  double worst_ratio = 0.0;         // largest gap / bound where the gap exceeds 1 mm
};

Result RunCase(const Case& c) {
  MeshCollider collider(c.mesh, 512);
  ProxySolver solver(512);
  ProxyParams params;
  params.radius_m = kR;
  params.skin_m = kSkin;
  Result res;
  const std::vector<Dihedral> dihedral = Dihedrals(*c.mesh);
  std::vector<std::int32_t> near(8192);
  // Star-shaped about O: the surface along a direction u is the ray's one crossing, between the
  // nearest triangle point and the farthest vertex.
  double r_max = 0.0, r_min = std::numeric_limits<double>::infinity();
  for (const auto& p : c.mesh->p_O_m) r_max = std::max(r_max, p.norm());
  for (const auto& T : c.mesh->triangles) {
    r_min = std::min(r_min, ClosestPointOnTriangle(Eigen::Vector3d::Zero(), c.mesh->p_O_m[T[0]], c.mesh->p_O_m[T[1]],
                                                   c.mesh->p_O_m[T[2]]).norm());
  }
  std::vector<std::int32_t> ids(512);
  auto surface_radius = [&](const Eigen::Vector3d& u) {  // Moller-Trumbore on the triangles near the ray
    const BallQueryResult q = collider.QueryBall(0.5 * (r_min + r_max) * u, 0.5 * (r_max - r_min) + 1e-6,
                                                 std::span<std::int32_t>(ids.data(), ids.size()));
    EXPECT_FALSE(q.truncated);
    double r = std::numeric_limits<double>::quiet_NaN();
    for (std::int32_t i = 0; i < q.count; ++i) {
      const SweepTriangle& T = collider.triangle(ids[static_cast<std::size_t>(i)]);
      const Eigen::Vector3d e1 = T.v[1] - T.v[0], e2 = T.v[2] - T.v[0];
      const Eigen::Vector3d pv = u.cross(e2);
      const double det = e1.dot(pv);
      if (std::abs(det) < 1e-18) continue;
      const Eigen::Vector3d tv = -T.v[0];
      const double a = tv.dot(pv) / det;
      const Eigen::Vector3d qv = tv.cross(e1);
      const double b = u.dot(qv) / det;
      if (a < -1e-12 || b < -1e-12 || a + b > 1.0 + 1e-12) continue;
      const double t = e2.dot(qv) / det;
      if (t > 0.0 && !(t >= r)) r = t;  // the first crossing (NaN compares false)
    }
    return r;
  };
  auto near_surface = [&](const Eigen::Vector3d& q) {
    return collider.QueryBall(q, kRs, std::span<std::int32_t>(ids.data(), ids.size())).count > 0;
  };
  const double mu = c.friction.mu_static;
  const double cone = std::sqrt(1.0 + mu * mu);
  std::mt19937 rng(c.seed);
  const Path path(rng);
  ProxyState st;
  for (int k = 0; k < kSteps; ++k) {
    const Eigen::Vector3d g = path.At(k, c.r_nominal);
    const ProxyContact pc = solver.Step(collider, params, c.friction, g, st);
    res.contact_steps += pc.touching ? 1 : 0;
    res.sticking_steps += pc.sticking ? 1 : 0;
    const double gap = (st.x_O_m - g).norm();
    res.max_gap = std::max(res.max_gap, gap);
    if (gap <= kTol) continue;  // within any bound
    // D: bisection along the outward ray from g between the surface (not free) and the bounding
    // sphere grown by R + skin (free): q is free when outside the surface and no triangle is
    // within R + skin of it.
    const Eigen::Vector3d u = g.normalized();
    const double r_s = surface_radius(u);
    EXPECT_TRUE(std::isfinite(r_s)) << "no surface crossing along " << u.transpose();
    double D = 0.0;
    if (g.norm() < r_s || near_surface(g)) {
      double lo = std::max(0.0, r_s - g.norm()), hi = std::max(lo, r_max + kRs + 1e-6 - g.norm());
      for (int i = 0; i < 20; ++i) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector3d q = g + mid * u;
        (q.norm() >= r_s && !near_surface(q) ? hi : lo) = mid;
      }
      D = hi;
    }
    res.max_depth = std::max(res.max_depth, D);
    // The mesh's angles where the proxy, the frictionless god-object and the nearest free point
    // can be: within the gap (plus R + skin) of the fingertip.
    double theta = 0.0, alpha = 0.0, rho = std::numeric_limits<double>::infinity();
    const BallQueryResult nq = collider.QueryBall(g, gap + kRs + 1e-3, std::span<std::int32_t>(near.data(), near.size()));
    for (std::int32_t i = 0; i < (nq.truncated ? c.mesh->num_triangles() : nq.count); ++i) {  // all when truncated
      const Dihedral& d = dihedral[static_cast<std::size_t>(nq.truncated ? i : near[static_cast<std::size_t>(i)])];
      theta = std::max(theta, d.convex);
      alpha = std::max(alpha, d.concave);
      rho = std::min(rho, d.concave_radius);
    }
    res.theta = std::max(res.theta, theta);
    res.alpha = std::max(res.alpha, alpha);
    double h = 0.0;
    if (mu > 0.0 && alpha > 0.0) {
      for (int i = 0; i < 4; ++i) {
        const double l = mu * (D / std::cos(theta) + h);
        h = l * std::min(1.0, alpha + l / rho);
      }
    }
    const double bound = (D / std::cos(theta) + h) * cone + kTol;
    if (gap > 1e-3) res.worst_ratio = std::max(res.worst_ratio, gap / bound);
    if (gap - bound > res.worst_excess || res.worst_step < 0) {
      res.worst_excess = gap - bound;
      res.worst_gap = gap;
      res.worst_bound = bound;
      res.worst_step = k;
    }
  }
  return res;
}

TEST(ProxyProperty, ProxyStaysWithinTheSurfacesHoldOnRandomMeshesAndPaths) {
  for (const Case& c : Cases()) {
    const Result r = RunCase(c);
    std::ostringstream os;
    os << c.name << ": worst at step " << r.worst_step << ", proxy " << r.worst_gap * 1e3 << " mm from the fingertip, bound "
       << r.worst_bound * 1e3 << " mm; largest gap " << r.max_gap * 1e3 << " mm, deepest " << r.max_depth * 1e3
       << " mm; gap / bound up to " << r.worst_ratio << " where the gap exceeds 1 mm; local dihedral angles up to "
       << r.theta << " convex, " << r.alpha << " concave; touching " << r.contact_steps << ", sticking " << r.sticking_steps << " of " << kSteps << " steps";
    SCOPED_TRACE(os.str());
    EXPECT_LE(r.worst_excess, 0.0);
    // The paths went well in and out, and friction held the proxy part of the time.
    EXPECT_GT(r.contact_steps, kSteps / 4);
    EXPECT_LT(r.contact_steps, kSteps * 9 / 10);
    EXPECT_GT(r.max_depth, 0.01);
    if (c.friction.mu_static > 0.0) {
      EXPECT_GT(r.sticking_steps, 100);
    }
    RecordProperty(c.name, os.str());
    std::printf("  %s\n", os.str().c_str());
  }
}

}  // namespace
}  // namespace handshare::contact
