// Fuzz target: an Abaqus/CalculiX .inp volume mesh read by fem::ReadAbaqusInp.
#include "fuzz_support.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = handshare::fuzz::WriteInput("mesh.inp", data, size);
  handshare::fuzz::ExpectOnly<handshare::fem::FemError>([&] { handshare::fem::ReadAbaqusInp(file); });
  return 0;
}
