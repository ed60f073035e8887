#include "handshare/web_console/gltf_export.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include <nlohmann/json.hpp>

#include "handshare/scene/scene.hpp"

namespace handshare::web_console {
namespace {

std::uint32_t Word(const std::string& b, std::size_t at) {
  std::uint32_t w = 0;
  std::memcpy(&w, b.data() + at, 4);
  return w;  // glTF is little-endian, as this machine
}

TEST(ExportGlb, AnAssetMeshBecomesBinaryGltf2WithItsTriangles) {
  const std::string glb = ExportGlb(std::filesystem::path(HANDSHARE_SOURCE_SCENES) / "../meshes/button.obj").glb;
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

// The view moves vertex k of the glTF by the displacement the world server sent for node id k
// (LoadMesh's vertex k): every asset mesh keeps LoadMesh's vertices, in its order, through the
// export (assimp's glTF exporter joins identical vertices and drops unused ones on its own).
TEST(ExportGlb, EveryAssetMeshKeepsItsVerticesInLoadMeshOrder) {
  int meshes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(HANDSHARE_SOURCE_SCENES) / "../meshes")) {
    if (entry.path().extension() != ".obj") continue;
    SCOPED_TRACE(entry.path().string());
    const GlbMesh exported = ExportGlb(entry.path());
    const scene::Mesh mesh = scene::LoadMesh(entry.path());
    const auto positions = GlbPositions(exported.glb);
    ASSERT_EQ(positions.size(), mesh.vertices_m.size());
    EXPECT_EQ(exported.vertex_count, mesh.vertices_m.size());
    for (std::size_t v = 0; v < positions.size(); ++v) {
      for (int k = 0; k < 3; ++k) ASSERT_EQ(positions[v][static_cast<std::size_t>(k)], static_cast<float>(mesh.vertices_m[v][k])) << v;
    }
    ++meshes;
  }
  EXPECT_GE(meshes, 9);  // the triceratops' parts and the water flea's body among them
}

TEST(GlbPositions, ABlobThatIsNotAGlbIsAnError) {
  EXPECT_THROW(GlbPositions("glTF"), std::runtime_error);
  std::string glb = ExportGlb(std::filesystem::path(HANDSHARE_SOURCE_SCENES) / "../meshes/arrow.obj").glb;
  glb.resize(glb.size() - 4);  // its BIN chunk cut short
  EXPECT_THROW(GlbPositions(glb), std::runtime_error);
}

TEST(ExportGlb, AMissingFileIsAnError) {
  EXPECT_THROW(ExportGlb("/nonexistent/mesh.obj"), std::runtime_error);
}

}  // namespace
}  // namespace handshare::web_console
