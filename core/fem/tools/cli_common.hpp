#pragma once
// Shared by the FEM command-line tools: load case JSON and exit-code mapping.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/static_solver.hpp"

namespace handshare::fem::cli {

/// A load case file:
/// {"E_Pa": 1e4, "nu": 0.3, "fixed_nodes": [ids], "fixed_nset": "NAME" (optional),
///  "imposed": [{"node": id, "u_m": [x, y, z]}], "forces": [{"node": id, "f_N": [x, y, z]}]}
/// Node ids are the ids of the mesh file.
struct LoadCase {
  Material material;
  StaticProblem problem;  // node indices (resolved)
};

/// @param require_imposed  fem_solve needs "imposed"; fem_precompute ignores it.
/// @throws InputError naming the file and the field.
LoadCase ReadLoadCase(const std::filesystem::path& file, const TetMesh& mesh, bool require_imposed);

/// Runs body; maps exceptions to messages on stderr and exit codes (1 = bad input or failure).
int RunMain(const char* program, const std::function<int()>& body);

}  // namespace handshare::fem::cli
