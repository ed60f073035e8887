#pragma once
/// @file
/// CalculiX (`ccx`, Debian package calculix-ccx) as an independent oracle on the same mesh:
/// writes a C3D4 deck of a TetMesh with its boundary conditions, runs ccx (a separate process,
/// GPL, never linked) and reads the displacements and reaction forces it prints. Offline only:
/// tests and tools, never the haptic thread.
///
/// Three models of the same solid: linear elasticity (what the project's solvers compute),
/// the same material with geometric nonlinearity (`*STEP, NLGEOM`: St. Venant-Kirchhoff, exact
/// for large rotations at small strain), and a compressible neo-Hookean solid with the same
/// small-strain moduli (`*HYPERELASTIC, NEO HOOKE`, C10 = G / 2 = E / (4 (1 + nu)),
/// D1 = 2 / K = 6 (1 - 2 nu) / E), which ccx always solves with geometric nonlinearity.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/static_solver.hpp"

namespace handshare::fem {

/// The constitutive and kinematic model ccx is asked to solve.
enum class CcxModel : std::uint8_t {
  kLinear,     ///< small strain, linear elastic (one increment).
  kNlgeom,     ///< linear elastic material, geometric nonlinearity (St. Venant-Kirchhoff).
  kNeoHooke,   ///< compressible neo-Hooke of the same small-strain E and nu, nonlinear geometry.
};

/// "linear", "nlgeom", "neo_hooke".
const char* CcxModelName(CcxModel model) noexcept;

/// One static load case for ccx. Nodes are mesh indices; the deck names them by their ids.
struct CcxCase {
  Material material;
  CcxModel model = CcxModel::kLinear;
  std::vector<std::int32_t> fixed;   ///< all three components held at zero.
  std::vector<NodalValue> imposed;   ///< prescribed displacements [m], all three components.
  std::vector<NodalValue> forces;    ///< nodal forces [N].
  /// Nonlinear models: first and largest increment as a fraction of the step (ccx's automatic
  /// incrementation cuts back below the first when an increment does not converge).
  double initial_increment = 0.1;
  double max_increment = 0.1;
  int max_increments = 400;
  int timeout_s = 600;  ///< a run still going after this is ended (not converged).
};

/// The moduli a neo-Hookean material gets from small-strain E and nu: {C10 [Pa], D1 [1/Pa]}.
std::array<double, 2> NeoHookeConstants(const Material& material) noexcept;

/// Writes the deck: every node used by an element, numbered index + 1 (ccx counts from 1; the
/// mesh's own ids may start at 0), at 12 significant digits (ccx cuts fields longer than 20
/// characters), C3D4 elements numbered from 1 (turned to positive volume), node sets NFIX and NIMP, the
/// material, one static step, and the displacements of every node and the reactions at NIMP
/// printed to job.dat at the end of the step.
/// @throws FemError if the file cannot be written; InputError for a node out of range.
void WriteCalculixInput(const std::filesystem::path& file, const TetMesh& mesh, const CcxCase& c);

/// What ccx printed: deck node id (mesh index + 1) -> value, of the last increment it printed.
struct CcxTables {
  std::map<std::int64_t, Eigen::Vector3d> u_m;         ///< "displacements (vx,vy,vz)"
  std::map<std::int64_t, Eigen::Vector3d> reaction_N;  ///< "forces (fx,fy,fz)"
};

/// Reads job.dat's displacement and force tables (later increments replace earlier ones).
/// @throws InputError if the file cannot be read.
CcxTables ReadCalculixDat(const std::filesystem::path& file);

/// A ccx run's outcome, by mesh index.
struct CcxResult {
  bool converged = false;            ///< ccx exited 0 and reached the end of the step.
  double step_fraction = 0.0;        ///< how far the step got (1 when converged).
  int increments = 0;                ///< increments ccx took (job.sta).
  std::string message;               ///< why it did not converge (end of its log), else empty.
  std::vector<Eigen::Vector3d> u_m;  ///< per mesh node (zero for nodes ccx did not print).
  std::vector<Eigen::Vector3d> reaction_N;  ///< per entry of CcxCase::imposed.
};

/// Writes `dir`/job.inp, runs `ccx -i job` there on one thread, reads job.dat and job.sta.
/// A run that did not converge is returned with converged = false and the tables as far as ccx
/// got (nothing is thrown for it).
/// @throws FemError if ccx is missing or `dir` cannot be written.
CcxResult RunCalculix(const TetMesh& mesh, const CcxCase& c, const std::filesystem::path& dir,
                      const std::string& program = "ccx");

}  // namespace handshare::fem
