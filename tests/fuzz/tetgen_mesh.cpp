// Fuzz target: a TetGen mesh (base.node + base.ele) read by fem::ReadTetgen. One input holds
// both files: the .node text, a line "%%ele", then the .ele text (no such line: an empty .ele).
#include <algorithm>
#include <string_view>

#include "fuzz_support.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kSplit = "\n%%ele\n";
  const auto at = all.find(kSplit);
  const auto node = all.substr(0, std::min(at, all.size()));
  const auto ele = at == std::string_view::npos ? std::string_view{} : all.substr(at + kSplit.size());
  handshare::fuzz::WriteInput("mesh.ele", reinterpret_cast<const std::uint8_t*>(ele.data()), ele.size());
  const auto file =
      handshare::fuzz::WriteInput("mesh.node", reinterpret_cast<const std::uint8_t*>(node.data()), node.size());
  handshare::fuzz::ExpectOnly<handshare::fem::FemError>([&] { handshare::fem::ReadTetgen(file); });
  return 0;
}
