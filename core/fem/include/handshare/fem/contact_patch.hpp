#pragma once
/// @file
/// A fingertip is a patch, not a point: a single-node constraint has a stiffness of about
/// 1.1 E h that vanishes as the mesh is refined. These functions turn a fingertip (a sphere of
/// radius R pressed to depth delta, or a flat punch of radius a) into the set of surface nodes
/// under it with their imposed displacements, so that force against depth converges with
/// refinement. Built offline (spatial grid); queries are real-time safe (noexcept, no allocation).

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// Result of a patch query.
struct PatchResult {
  std::int32_t count = 0;          ///< contacts written.
  bool truncated = false;          ///< more nodes were under the fingertip than fit in `out`
                                   ///< (the closest ones were kept).
  double contact_radius_m = 0.0;   ///< a = sqrt(2 R delta) (sphere) or the punch radius.
};

/// Finds the compliance nodes under a fingertip.
class ContactPatchFinder {
 public:
  /// Indexes the compliance nodes' reference positions and outward normals (from `surface`;
  /// nodes not on the surface get the zero normal) in a uniform hash grid.
  /// @throws InputError if the compliance was computed for a different node count.
  ContactPatchFinder(const TetMesh& mesh, const Surface& surface, const Compliance& compliance);

  /// Spherical fingertip: contact point p_W on the undeformed surface, outward normal n_out
  /// (unit), radius R_m, depth_m >= 0. Nodes within the geometric contact radius
  /// a = sqrt(2 R delta) of p (measured in the tangent plane) get u = -(delta - r^2 / (2R)) n_out
  /// (the paraboloid of Hertz theory). With push_only, the nodes near the rim that would pull
  /// are released by the solver, which leaves the Hertz contact radius sqrt(R delta).
  PatchResult Sphere(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_out, double R_m,
                     double depth_m, ContactMode mode, std::span<ContactInput> out) const noexcept;

  /// Rigid flat punch of radius a_m: nodes with r < a_m get u = -delta n_out.
  PatchResult FlatPunch(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_out, double a_m,
                        double depth_m, ContactMode mode, std::span<ContactInput> out) const noexcept;

  /// Reference position and outward normal of a slot.
  const Eigen::Vector3d& position_m(std::int32_t slot) const noexcept { return p_m_[slot]; }
  const Eigen::Vector3d& normal(std::int32_t slot) const noexcept { return n_[slot]; }

 private:
  template <class DepthFn>
  PatchResult Collect(const Eigen::Vector3d& p_W, const Eigen::Vector3d& n_out, double a_m,
                      ContactMode mode, std::span<ContactInput> out,
                      const DepthFn& depth_at_r) const noexcept;

  std::vector<std::int32_t> mesh_node_of_slot_;
  std::vector<Eigen::Vector3d> p_mesh_m_;  // every mesh node (to rank kept nodes by distance)
  std::vector<Eigen::Vector3d> p_m_;
  std::vector<Eigen::Vector3d> n_;
  double cell_m_ = 1.0;
  Eigen::Vector3d origin_m_ = Eigen::Vector3d::Zero();
  // Sorted (cell key, slot) pairs: the hash grid without buckets.
  std::vector<std::int64_t> keys_;
  std::vector<std::int32_t> slots_;
};

}  // namespace handshare::fem
