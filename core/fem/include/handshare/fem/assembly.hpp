#pragma once
/// @file
/// Linear elasticity on 4-node tetrahedra: material, element stiffness, global assembly.
/// DOF numbering everywhere in this library: 3 * node + axis (x, y, z).

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// Isotropic linear elastic material of one object.
struct Material {
  double E_Pa = 1e4;  ///< Young's modulus [Pa], > 0.
  double nu = 0.3;    ///< Poisson's ratio, -1 < nu < 0.5.

  /// @throws InputError if E_Pa or nu is out of range or not finite.
  void Validate() const;
  /// Lame's first parameter [Pa].
  double lambda_Pa() const noexcept { return E_Pa * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)); }
  /// Shear modulus [Pa].
  double G_Pa() const noexcept { return E_Pa / (2.0 * (1.0 + nu)); }
};

/// Stiffness [N/m] of one linear tetrahedron (small strain, Hooke's law; HIRO II eq. 5,
/// K_e = V B^T D B), DOF order (p0 x,y,z, p1 x,y,z, ...). Requires positive volume.
Eigen::Matrix<double, 12, 12> TetStiffness(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                           const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                           const Material& material);

/// Global stiffness K [N/m], 3n x 3n, full symmetric storage, compressed column-major.
/// Nodes in no element get empty rows and columns.
Eigen::SparseMatrix<double> AssembleStiffness(const TetMesh& mesh, const Material& material);

}  // namespace handshare::fem
