#pragma once
/// @file
/// Broad and mid phase of fingertip collision: an FCL bounding-volume hierarchy (OBBRSS) over a
/// rigid triangle mesh, built once at setup, answering "which triangles does this ball touch?".
/// The real-time query walks FCL's BVH nodes itself (ball against each node's OBB, exact
/// ball-triangle distance at the leaves) with a fixed-size stack: fcl::collide() of a shape
/// against a mesh allocates on every call in FCL 0.7 (computeBV -> Sphere::getBoundVertices
/// returns a std::vector, RSS fitting allocates), so it is kept only as a setup-time
/// cross-check (QueryBallFcl, with its request built once). The exact proxy geometry is done
/// on the returned triangles (proxy.hpp). FCL types stay inside the .cpp (pimpl).
///
/// The walk itself runs over a compact copy of FCL's tree (same topology, nodes in depth-first
/// order, 32 bytes each): a float axis-aligned box per node, rounded outward and tested with a
/// slack far above float round-off, so it never rejects a node the ball reaches; the leaves
/// keep the exact double ball-triangle test. The triangles returned and their order are the
/// ones of the walk over FCL's oriented boxes (QueryBallObb, kept as the reference the tests
/// compare against): pruning only skips subtrees without a hit, and both walks visit leaves
/// left to right.

#include <array>
#include <cstdint>
#include <vector>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "handshare/contact/geometry.hpp"
#include "handshare/contact/tri_mesh.hpp"

namespace handshare::contact {

/// Result of one ball query.
struct BallQueryResult {
  std::int32_t count = 0;   ///< triangle ids written.
  bool truncated = false;   ///< more triangles touched the ball than fit.
};

class MeshCollider {
 public:
  /// Builds the BVH (setup; allocates). @param max_candidates  most triangles one query returns.
  /// @throws std::invalid_argument for an invalid mesh (TriMesh::Validate) or max_candidates < 1.
  MeshCollider(std::shared_ptr<const TriMesh> mesh, std::int32_t max_candidates);
  ~MeshCollider();
  MeshCollider(MeshCollider&&) noexcept;
  MeshCollider& operator=(MeshCollider&&) noexcept;

  /// Ids of the triangles within distance r of c_O (mesh frame O), in BVH order.
  /// Real-time: noexcept, no allocation. exact = false: without the leaves' exact distance, every
  /// triangle whose plane and bounding disc do not put it beyond r (a superset, in the same
  /// order; for callers that test each triangle anyway).
  BallQueryResult QueryBall(const Eigen::Vector3d& c_O_m, double r_m, std::span<std::int32_t> triangle_ids,
                            bool exact = true) const noexcept;
  /// The same answer by walking FCL's own nodes (ball against each node's OBB): the previous
  /// real-time path, kept as the reference for tests. Real-time safe as well.
  BallQueryResult QueryBallObb(const Eigen::Vector3d& c_O_m, double r_m,
                               std::span<std::int32_t> triangle_ids) const noexcept;

  /// The same through fcl::collide (FCL's sphere-triangle test). Allocates inside FCL: tests
  /// and setup only.
  BallQueryResult QueryBallFcl(const Eigen::Vector3d& c_O_m, double r_m,
                               std::span<std::int32_t> triangle_ids);

  const TriMesh& mesh() const noexcept { return *mesh_; }

  /// Triangle t prepared for the sweep (its vertices, the mesh's values, copied at setup).
  const SweepTriangle& triangle(std::int32_t t) const noexcept { return tri_[static_cast<std::size_t>(t)]; }
  /// All of them, by id.
  const SweepTriangle* triangles() const noexcept { return tri_.data(); }
  /// Triangle t's plane: unit normal (winding order) and offset, n . p = w on the plane; NaN for
  /// a degenerate triangle (so that every plane-distance shortcut is skipped for it).
  const Eigen::Vector4d& triangle_plane(std::int32_t t) const noexcept {
    return tri_plane_[static_cast<std::size_t>(t)];
  }
  /// Triangle t's bounding disc in its plane: centre (the centroid) and radius (to the farthest
  /// vertex); NaN for a degenerate triangle. With the plane it bounds the distance to the
  /// triangle from below (the proxy's shortcuts skip exact tests with it).
  const Eigen::Vector4d& triangle_disc(std::int32_t t) const noexcept {
    return tri_disc_[static_cast<std::size_t>(t)];
  }
  std::int32_t max_candidates() const noexcept { return max_candidates_; }
  /// Number unique to this collider among all built in the process (keys caches of results
  /// that depend on the mesh only).
  std::uint64_t id() const noexcept { return id_; }
  /// Bounding sphere of the mesh in O (centre of the vertices' box, radius to the farthest).
  const Eigen::Vector3d& bound_center_O_m() const noexcept { return bound_c_; }
  double bound_radius_m() const noexcept { return bound_r_; }

 private:
  struct Impl;
  void BuildFlatTree();
  // Compact tree node (BuildFlatTree's copy of FCL's tree): float box; internal nodes have
  // their left child next (i + 1) and the right one at `right`; leaves have right = -1 - triangle.
  struct FlatNode {
    float lo[3];
    float hi[3];
    std::int32_t right;
    std::int32_t pad;
  };
  // The walk's tree: the compact tree with up to three levels collapsed into one node of up to
  // eight children (boxes in structure-of-arrays form, so one node's eight box tests are a few
  // vector operations), children in the compact tree's left-to-right order. child >= 0: another
  // wide node; < 0: -1 - triangle. Unused slots have empty boxes (lo = +inf, hi = -inf).
  static constexpr int kWide = 8;
  struct alignas(32) WideNode {
    float lo[3][kWide];
    float hi[3][kWide];
    std::int32_t child[kWide];
  };
  // Collapses the compact tree (a setup-time step, not kept) into wide_.
  void BuildWideTree(const std::vector<FlatNode>& nodes);
  std::unique_ptr<Impl> impl_;
  std::vector<WideNode> wide_;
  std::vector<SweepTriangle> tri_;
  std::vector<Eigen::Vector4d> tri_plane_;
  std::vector<Eigen::Vector4d> tri_disc_;
  double coord_scale_m_ = 0.0;  // largest |coordinate| of the mesh (float slack of the boxes)
  std::shared_ptr<const TriMesh> mesh_;
  std::int32_t max_candidates_ = 0;
  std::uint64_t id_ = 0;
  Eigen::Vector3d bound_c_ = Eigen::Vector3d::Zero();
  double bound_r_ = 0.0;
};

}  // namespace handshare::contact
