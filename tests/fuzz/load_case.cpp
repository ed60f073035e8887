// Fuzz target: a load case of fem_solve / fem_precompute (JSON) read by cli::ReadLoadCase
// against a fixed mesh (one tetrahedron, ids 1-4, node set "BASE": nodes 1-3).
#include <string>

#include "cli_common.hpp"
#include "fuzz_support.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"

namespace {
const handshare::fem::TetMesh& Mesh() {
  static const handshare::fem::TetMesh mesh = [] {
    const std::string inp =
        "*NODE, NSET=base\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n*NODE\n4, 0, 0, 1\n"
        "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n";
    return handshare::fem::ReadAbaqusInp(handshare::fuzz::WriteInput(
        "tet.inp", reinterpret_cast<const std::uint8_t*>(inp.data()), inp.size()));
  }();
  return mesh;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto& mesh = Mesh();
  const auto file = handshare::fuzz::WriteInput("load.json", data, size);
  handshare::fuzz::ExpectOnly<handshare::fem::FemError>([&] {
    handshare::fem::cli::ReadLoadCase(file, mesh, true);
    handshare::fem::cli::ReadLoadCase(file, mesh, false);
  });
  return 0;
}
