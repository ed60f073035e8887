// Fuzz target: a Gmsh MSH 2.2 volume mesh read by fem::ReadGmshMsh.
#include "fuzz_support.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = handshare::fuzz::WriteInput("mesh.msh", data, size);
  handshare::fuzz::ExpectOnly<handshare::fem::FemError>([&] { handshare::fem::ReadGmshMsh(file); });
  return 0;
}
