#pragma once
/// @file
/// Volumetric meshes of linear (4-node) tetrahedra, their boundary surface, and structured
/// box meshes for tests and benchmarks. Not real-time: everything here allocates.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace handshare::fem {

/// Node indices (0-based, into TetMesh::positions_m()) of a 4-node tetrahedron. Positive
/// orientation: det[p1-p0, p2-p0, p3-p0] > 0 (the Gmsh, TetGen and Abaqus C3D4 convention).
using Tet = std::array<std::int32_t, 4>;
/// Node indices of a triangle; on a Surface, counter-clockwise seen from outside.
using Triangle = std::array<std::int32_t, 3>;

/// Signed volume [m^3] of the tetrahedron (a, b, c, d): det[b-a, c-a, d-a] / 6.
double SignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) noexcept;

/// A mesh of linear tetrahedra in its reference (undeformed) configuration.
/// Invariants, checked by the constructor: finite coordinates, unique node ids, element indices
/// in range, every element with strictly positive volume.
class TetMesh {
 public:
  TetMesh() = default;

  /// Takes the nodes and elements and checks the invariants.
  /// @param p_m       node positions [m].
  /// @param tets      elements, indices into p_m.
  /// @param node_ids  ids as written in the source file (empty: 1..n).
  /// @param source    file name, used in error messages.
  /// @throws InputError naming the source and the offending node or element.
  TetMesh(std::vector<Eigen::Vector3d> p_m, std::vector<Tet> tets,
          std::vector<std::int64_t> node_ids = {}, std::string source = {});

  const std::vector<Eigen::Vector3d>& positions_m() const noexcept { return p_m_; }
  const std::vector<Tet>& tets() const noexcept { return tets_; }
  /// Node ids as in the source file (index -> id).
  const std::vector<std::int64_t>& node_ids() const noexcept { return node_ids_; }
  std::int32_t num_nodes() const noexcept { return static_cast<std::int32_t>(p_m_.size()); }
  std::int32_t num_tets() const noexcept { return static_cast<std::int32_t>(tets_.size()); }
  const std::string& source() const noexcept { return source_; }

  /// Index of the node with file id `id`, or nullopt.
  std::optional<std::int32_t> IndexOfId(std::int64_t id) const;
  /// Index of the node with file id `id`.
  /// @throws InputError "unknown node id" naming `field`.
  std::int32_t IndexOfIdOrThrow(std::int64_t id, const std::string& field) const;

  /// Named node sets (Abaqus *NSET, Gmsh physical groups, TetGen boundary markers).
  const std::map<std::string, std::vector<std::int32_t>, std::less<>>& node_sets() const noexcept {
    return node_sets_;
  }
  /// Adds (or replaces) a node set; indices must be in range.
  void SetNodeSet(std::string name, std::vector<std::int32_t> nodes);
  /// The node set `name`, or nullptr.
  const std::vector<std::int32_t>* FindNodeSet(std::string_view name) const;

  /// True for nodes that belong to at least one element (others have no stiffness).
  const std::vector<bool>& used_nodes() const noexcept { return used_; }
  /// Total volume [m^3].
  double Volume() const noexcept;

 private:
  std::vector<Eigen::Vector3d> p_m_;
  std::vector<Tet> tets_;
  std::vector<std::int64_t> node_ids_;
  std::unordered_map<std::int64_t, std::int32_t> index_of_id_;
  std::map<std::string, std::vector<std::int32_t>, std::less<>> node_sets_;
  std::vector<bool> used_;
  std::string source_;
};

/// The boundary of a TetMesh: faces that belong to exactly one element.
struct Surface {
  /// Boundary triangles, outward orientation (counter-clockwise seen from outside).
  std::vector<Triangle> triangles;
  /// Sorted mesh indices of the nodes on the boundary.
  std::vector<std::int32_t> nodes;
  /// Unit outward normal (area-weighted mean of the adjacent triangles), one per entry of nodes.
  std::vector<Eigen::Vector3d> normals;
};

/// Extracts the boundary surface.
/// @throws InputError if a face is shared by more than two elements or two elements overlap.
Surface ExtractSurface(const TetMesh& mesh);

/// Structured mesh on the tensor grid xs x ys x zs [m] (strictly increasing), every hexahedral
/// cell split into 6 tetrahedra around its main diagonal (Kuhn split; conforming). Node index
/// i + nx*(j + ny*k), node id index+1.
TetMesh MakeGridMesh(std::span<const double> xs_m, std::span<const double> ys_m,
                     std::span<const double> zs_m);

/// Uniform structured box [0,size] with cells[0] x cells[1] x cells[2] hexahedra (6 tets each).
TetMesh MakeBoxMesh(const Eigen::Vector3d& size_m, const std::array<int, 3>& cells);

/// Indices of the nodes whose coordinate `axis` (0,1,2) is within tol_m of value_m.
std::vector<std::int32_t> NodesOnPlane(const TetMesh& mesh, int axis, double value_m,
                                       double tol_m = 1e-9);

}  // namespace handshare::fem
