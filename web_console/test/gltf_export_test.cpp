#include "handshare/web_console/gltf_export.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include <nlohmann/json.hpp>

namespace handshare::web_console {
namespace {

std::uint32_t Word(const std::string& b, std::size_t at) {
  std::uint32_t w = 0;
  std::memcpy(&w, b.data() + at, 4);
  return w;  // glTF is little-endian, as this machine
}

TEST(ExportGlb, AnAssetMeshBecomesBinaryGltf2WithItsTriangles) {
  const std::string glb = ExportGlb(std::filesystem::path(HANDSHARE_SOURCE_SCENES) / "../meshes/button.obj");
  ASSERT_GT(glb.size(), 20u);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  EXPECT_EQ(Word(glb, 4), 2u);           // version 2
  EXPECT_EQ(Word(glb, 8), glb.size());   // the header's length is the blob's
  const std::uint32_t json_bytes = Word(glb, 12);
  EXPECT_EQ(Word(glb, 16), 0x4E4F534Au);  // "JSON" chunk
  const auto j = nlohmann::json::parse(glb.substr(20, json_bytes));
  EXPECT_EQ(j["asset"]["version"], "2.0");
  ASSERT_FALSE(j["meshes"].empty());
  EXPECT_EQ(j["meshes"][0]["primitives"][0]["mode"], 4);  // triangles
}

TEST(ExportGlb, AMissingFileIsAnError) {
  EXPECT_THROW(ExportGlb("/nonexistent/mesh.obj"), std::runtime_error);
}

}  // namespace
}  // namespace handshare::web_console
