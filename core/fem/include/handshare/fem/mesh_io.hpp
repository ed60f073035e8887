#pragma once
/// @file
/// Readers for volumetric meshes (Gmsh 2.2 ASCII, TetGen .node/.ele, an Abaqus/CalculiX .inp
/// subset). Every reader throws InputError naming the file, line and field on bad input.
/// Surface meshes, their tetrahedralization by `tetgen` and ReadVolumeMesh (any mesh file by its
/// extension) are in surface_import.hpp, which builds on these readers; nothing here calls it.

#include <filesystem>

#include "handshare/fem/mesh.hpp"

namespace handshare::fem {

/// Gmsh MSH 2.2 ASCII: $Nodes and 4-node tetrahedra (element type 4). Lower-dimensional elements
/// are skipped, but their nodes become node sets named after their physical group
/// ($PhysicalNames name, else "physical:<tag>"). Other volume element types are rejected.
TetMesh ReadGmshMsh(const std::filesystem::path& file);

/// TetGen output: `base.node` and `base.ele` (pass either file or the base name). 4-node
/// elements only; nonzero boundary markers become node sets "marker:<m>".
TetMesh ReadTetgen(const std::filesystem::path& node_ele_or_base);

/// Abaqus/CalculiX input subset: *NODE (with optional NSET=), *ELEMENT TYPE=C3D4 (other C3D*
/// types are rejected, shells/beams skipped), *NSET (ids, other set names, GENERATE). Keywords are
/// case-insensitive, "**" starts a comment, other keywords and their data are skipped.
TetMesh ReadAbaqusInp(const std::filesystem::path& file);

}  // namespace handshare::fem
