#include "handshare/contact/geometry.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace handshare::contact
