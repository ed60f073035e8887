#pragma once
/// @file
/// Surface meshes through assimp, and tetrahedralization of a closed surface by the external
/// `tetgen` program (GPL: it is run as a separate process, never linked), whose output is read
/// with mesh_io.hpp's ReadTetgen. ReadVolumeMesh, the one entry for any mesh file, is here
/// because a surface file is tetrahedralized: this file uses mesh_io.hpp, never the other way.
/// Every reader throws InputError naming the file, line and field on bad input.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// A closed triangle surface: welded vertices and triangles.
struct SurfaceMeshData {
  std::vector<Eigen::Vector3d> p_m;
  std::vector<std::array<std::int32_t, 3>> triangles;
};

/// Reads a surface mesh (OBJ, STL, PLY, OFF, ... anything assimp reads), triangulates polygons,
/// applies node transforms and welds vertices with bitwise-identical positions.
/// @throws InputError if assimp fails or the file has no triangles.
SurfaceMeshData ReadSurfaceMesh(const std::filesystem::path& file);

/// Throws InputError (naming `source`) unless every edge is shared by exactly two triangles.
void CheckClosed(const SurfaceMeshData& surface, const std::string& source);

/// Options of the external tetgen run.
struct TetgenOptions {
  /// Quality bound -q: maximum radius-edge ratio (TetGen's default 2.0; smaller is better
  /// shaped and has more nodes). 0 disables -q.
  double max_radius_edge_ratio = 1.5;
  /// Volume bound -a [m^3]; 0 means none.
  double max_volume_m3 = 0.0;
  /// Program to run (looked up in PATH).
  std::string program = "tetgen";
};

/// Tetrahedralizes a closed surface with the external tetgen program (in a temporary directory)
/// and reads its output.
/// @throws InputError if the surface is not closed; FemError if tetgen is missing or fails
///         (with the end of its log).
TetMesh TetrahedralizeSurface(const SurfaceMeshData& surface, const TetgenOptions& options,
                              const std::string& source);

/// ReadSurfaceMesh + TetrahedralizeSurface.
TetMesh TetrahedralizeSurfaceFile(const std::filesystem::path& surface_file,
                                  const TetgenOptions& options = {});

/// Reads a volume mesh by extension: .msh (Gmsh), .node/.ele (TetGen), .inp (Abaqus); surface
/// formats (.obj, .stl, .ply, .off) are tetrahedralized with default TetgenOptions.
TetMesh ReadVolumeMesh(const std::filesystem::path& file);

}  // namespace handshare::fem
