#pragma once
/// @file
/// Triangle meshes of rigid objects (in the object frame O) and the shapes the scenes use:
/// spheres and boxes are meshed once at setup so that one proxy algorithm serves every shape.
/// Setup only: everything here allocates.

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace handshare::contact {

/// A triangle soup or closed mesh, counter-clockwise seen from outside where that applies.
struct TriMesh {
  std::vector<Eigen::Vector3d> p_O_m;               ///< vertices in the object frame O [m].
  std::vector<std::array<std::int32_t, 3>> triangles;

  /// @throws std::invalid_argument if empty, an index is out of range, a coordinate is not
  ///         finite, or a triangle has zero area.
  void Validate() const;
  std::int32_t num_triangles() const noexcept { return static_cast<std::int32_t>(triangles.size()); }
};

/// Icosphere of the given radius centred at O: 20 * 4^subdivisions triangles (3: 1,280;
/// 4: 5,120). The facets lie inside the sphere by at most about radius * 1.2 / 4^subdivisions.
TriMesh MakeIcosphere(double radius_m, int subdivisions);

/// Box of the given full edge lengths centred at O, 12 triangles (2 per face).
TriMesh MakeBoxMesh(const Eigen::Vector3d& size_m);

/// Icosphere whose radius is modulated by smooth bumps, r = R (1 + bump * sin(k x) sin(k y)
/// sin(k z) / R ...): a procedural, non-convex "bumpy sphere" for benchmarks.
/// 20 * 4^subdivisions triangles (5: 20,480).
TriMesh MakeBumpySphere(double radius_m, double bump_m, int subdivisions);

}  // namespace handshare::contact
