// fem_solve MESH LOADCASE.json: static linear FEM solve (direct, CHOLMOD), JSON on stdout:
// {"displacements": {"id": [ux, uy, uz], ...}, "reactions": {"id": [fx, fy, fz], ...},
//  "support_reactions": {...}} in m and N. Reactions are listed at imposed nodes; the reactions
// at fixed nodes are under support_reactions. Exit code 1 with a message on bad input.

#include <cstdio>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "handshare/fem/surface_import.hpp"
#include "handshare/fem/static_solver.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fem_solve MESH LOADCASE.json\n"
    "  MESH: .msh (Gmsh 2.2 ASCII), .node/.ele (TetGen), .inp (C3D4), or a closed .obj/.stl/.ply\n"
    "  LOADCASE: {\"E_Pa\": 1e4, \"nu\": 0.3, \"fixed_nodes\": [ids],\n"
    "             \"imposed\": [{\"node\": id, \"u_m\": [x, y, z]}]}\n";

}  // namespace

int main(int argc, char** argv) {
  using namespace handshare::fem;
  if (argc != 3 || std::string(argv[1]) == "--help") {
    std::cerr << kUsage;
    return argc == 2 ? 0 : 2;
  }
  return cli::RunMain("fem_solve", [&] {
    const TetMesh mesh = ReadVolumeMesh(argv[1]);
    const cli::LoadCase lc = cli::ReadLoadCase(argv[2], mesh, /*require_imposed=*/true);
    const StaticSolution s = SolveStatic(mesh, lc.material, lc.problem);
    nlohmann::ordered_json out;
    auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
    auto& disp = out["displacements"] = nlohmann::ordered_json::object();
    for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
      disp[std::to_string(mesh.node_ids()[v])] = vec(s.u_m[v]);
    }
    auto& reac = out["reactions"] = nlohmann::ordered_json::object();
    for (const auto& iv : lc.problem.imposed_u_m) {
      reac[std::to_string(mesh.node_ids()[iv.node])] = vec(s.reaction_N[iv.node]);
    }
    auto& sup = out["support_reactions"] = nlohmann::ordered_json::object();
    for (std::int32_t v : lc.problem.fixed_nodes) {
      sup[std::to_string(mesh.node_ids()[v])] = vec(s.reaction_N[v]);
    }
    std::cout << out.dump(1) << "\n";
    return std::cout ? 0 : 1;
  });
}
