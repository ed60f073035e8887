#pragma once
/// @file
/// Exact point/sphere queries against one triangle, used by the god-object proxy. All functions
/// are real-time safe (noexcept, no allocation). Positions in any one frame [m].

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace handshare::contact {

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) noexcept;

/// Lower bound of the squared distance from a point to a triangle, from the triangle's bounding
/// disc (centre in its plane, radius; MeshCollider::triangle_disc) and the point's signed
/// distance h to that plane: a point whose foot lies rho from the centre is at least
/// sqrt(h^2 + max(0, rho - radius)^2) from every point of the disc. A NaN disc gives NaN (every
/// "bound > limit" test false). The plane test alone passes the tilted neighbours of a face
/// (their planes pass close to the point); their discs lie aside. Round-off: the centroid lies in
/// the plane to ~1e-16 of the coordinates; rho's error is largest where q - h^2 cancels, and
/// there rho < radius anyway.
inline double DiscDistanceBound2(const Eigen::Vector4d& disc, const Eigen::Vector3d& x, double h) noexcept {
  const double q = (x - disc.head<3>()).squaredNorm();
  const double lateral = std::max(0.0, std::sqrt(std::max(0.0, q - h * h)) - disc.w());
  return h * h + lateral * lateral;
}

/// Signed distance from x to a plane (unit normal, offset w: n . p = w on it; NaN stays NaN).
inline double PlaneDistance(const Eigen::Vector4d& plane, const Eigen::Vector3d& x) noexcept {
  return plane.x() * x.x() + plane.y() * x.y() + plane.z() * x.z() - plane.w();
}

/// True when a triangle's plane or its bounding disc puts all of it farther than `far` from x
/// (at plane distance h): the exact tests can be skipped. Never for a degenerate (NaN) one.
inline bool BeyondTriangle(const Eigen::Vector4d& disc, const Eigen::Vector3d& x, double h, double far) noexcept {
  return std::abs(h) > far || DiscDistanceBound2(disc, x, h) > far * far;
}

/// First time of impact s in [0, 1] of a sphere of radius R_m whose centre moves from x to
/// x + d against the triangle (a, b, c) (both sides; face, edges and vertices), or a value > 1
/// if it does not touch it on the way. Features the sphere already overlaps at s = 0 and
/// features it moves along or away from (approach below kMinApproach_m over the whole motion)
/// are ignored: the caller keeps those as constraints.
double SweepSphereTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                           const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c) noexcept;

/// What SweepSphereTriangle computes from the triangle alone, computed once per mesh triangle
/// (MeshCollider) by the same expressions, so that the sweep against it gives the same bits.
struct SweepTriangle {
  Eigen::Vector3d v[3];    ///< vertices a, b, c
  Eigen::Vector3d n;       ///< unit winding normal (b - a) x (c - a) / |.|; valid if has_face
  Eigen::Vector3d ed[3];   ///< edge e: v[(e + 1) % 3] - v[e]
  double len2[3] = {0.0, 0.0, 0.0};  ///< |ed[e]|^2
  bool has_face = false;   ///< |(b - a) x (c - a)| > 0
  /// The vertices this triangle sweeps for its mesh (bit k: v[k]), read by
  /// SweepSphereTriangleOwned: a vertex is shared by several triangles and gives the same root in
  /// each, so one of them (its owner, MeshCollider) sweeps it. All three by default.
  std::uint8_t own_vertices = 7;
};
SweepTriangle MakeSweepTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c) noexcept;

/// SweepSphereTriangle against a prepared triangle (the six-argument form prepares it and calls
/// this one: one code path, identical results).
double SweepSphereTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                           const SweepTriangle& tri) noexcept;

/// SweepSphereTriangle with only the vertices in tri.own_vertices: over a set of a mesh's
/// triangles that holds each reachable vertex's owner, the smallest result is the same bits as
/// with every vertex (each vertex's root is computed from the same numbers in every triangle).
double SweepSphereTriangleOwned(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                                const SweepTriangle& tri) noexcept;

/// The smallest SweepSphereTriangleOwned over the triangles tris[ids[0..n)] (2 if n = 0): eight
/// at a time where the processor has AVX-512, each lane doing the one-triangle sweep's
/// operations in its order, so the result is the same bits as the fold one at a time.
/// `vector` false: one at a time (tests).
double SweepSphereTrianglesOwned(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double R_m,
                                 const SweepTriangle* tris, const std::int32_t* ids, std::int32_t n,
                                 bool vector = true) noexcept;

/// Writes to out, in order, the ids among ids[0..n) of the triangles of `tris` that may lie
/// within r of x: every one whose distance is at most r, and others only within round-off of r
/// (the distance is computed exactly in eight lanes where the processor has AVX-512 and kept
/// with a relative slack of 1e-9; elsewhere every id is kept). Returns how many. out holds n + 8.
std::int32_t TrianglesWithin(const Eigen::Vector3d& x, double r, const SweepTriangle* tris, const std::int32_t* ids,
                             std::int32_t n, std::int32_t* out, bool vector = true) noexcept;

/// Approach (over one sweep) below which a feature is treated as tangent, not hit [m]: far below
/// any motion a hand makes in one haptic step, far above round-off at these scales.
inline constexpr double kMinApproach_m = 1e-13;

}  // namespace handshare::contact
