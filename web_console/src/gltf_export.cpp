#include "handshare/web_console/gltf_export.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/scene.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "handshare/scene/scene.hpp"

namespace handshare::web_console {

namespace {

std::uint32_t Word(const std::string& b, std::size_t at) {
  std::uint32_t w = 0;
  std::memcpy(&w, b.data() + at, 4);
  return w;  // glTF is little-endian, as every machine this runs on
}

// One mesh, one material, one node: the mesh as LoadMesh has it, with area-weighted normals
// (the graphics node's AreaWeightedNormals: the sum of the triangles' cross products).
std::unique_ptr<aiScene> SceneOf(const scene::Mesh& mesh) {
  auto out = std::make_unique<aiScene>();
  out->mRootNode = new aiNode();
  out->mRootNode->mNumMeshes = 1;
  out->mRootNode->mMeshes = new unsigned int[1]{0};
  out->mNumMaterials = 1;
  out->mMaterials = new aiMaterial*[1]{new aiMaterial()};
  out->mNumMeshes = 1;
  out->mMeshes = new aiMesh*[1]{new aiMesh()};
  aiMesh& m = *out->mMeshes[0];
  m.mMaterialIndex = 0;
  m.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const auto n = static_cast<unsigned int>(mesh.vertices_m.size());
  m.mNumVertices = n;
  m.mVertices = new aiVector3D[n];
  m.mNormals = new aiVector3D[n];
  std::vector<Eigen::Vector3d> normals(n, Eigen::Vector3d::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices_m[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d c = (mesh.vertices_m[static_cast<std::size_t>(t[1])] - a).cross(
        mesh.vertices_m[static_cast<std::size_t>(t[2])] - a);
    for (const auto v : t) normals[static_cast<std::size_t>(v)] += c;
  }
  for (unsigned int v = 0; v < n; ++v) {
    const Eigen::Vector3d& p = mesh.vertices_m[v];
    m.mVertices[v] = aiVector3D(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    const Eigen::Vector3d u = normals[v].norm() > 0.0 ? normals[v].normalized() : Eigen::Vector3d::UnitZ();
    m.mNormals[v] = aiVector3D(static_cast<float>(u.x()), static_cast<float>(u.y()), static_cast<float>(u.z()));
  }
  m.mNumFaces = static_cast<unsigned int>(mesh.triangles.size());
  m.mFaces = new aiFace[m.mNumFaces];
  for (unsigned int f = 0; f < m.mNumFaces; ++f) {
    m.mFaces[f].mNumIndices = 3;
    m.mFaces[f].mIndices = new unsigned int[3];
    for (int k = 0; k < 3; ++k) m.mFaces[f].mIndices[k] = static_cast<unsigned int>(mesh.triangles[f][static_cast<std::size_t>(k)]);
  }
  return out;
}

}  // namespace

GlbMesh ExportGlb(const std::filesystem::path& mesh_file) {
  scene::Mesh mesh;
  try {
    mesh = scene::LoadMesh(mesh_file);
  } catch (const std::exception& e) {
    throw std::runtime_error("web_console: cannot read the mesh " + mesh_file.string() + ": " + e.what());
  }
  const std::unique_ptr<aiScene> scene = SceneOf(mesh);
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), "glb2");
  if (blob == nullptr) {
    throw std::runtime_error("web_console: cannot export " + mesh_file.string() + " to glTF: " +
                             exporter.GetErrorString());
  }
  GlbMesh out{std::string(static_cast<const char*>(blob->data), blob->size), mesh.vertices_m.size()};
  // The exporter joins identical vertices and drops unused ones: the view's vertex k must still
  // be LoadMesh's vertex k, or a deformation would move the wrong vertices.
  const auto positions = GlbPositions(out.glb);
  if (positions.size() != mesh.vertices_m.size()) {
    throw std::runtime_error("web_console: the glTF of " + mesh_file.string() + " has " +
                             std::to_string(positions.size()) + " vertices, the mesh " +
                             std::to_string(mesh.vertices_m.size()) + ": the view could not deform it");
  }
  for (std::size_t v = 0; v < positions.size(); ++v) {
    for (int k = 0; k < 3; ++k) {
      if (positions[v][static_cast<std::size_t>(k)] != static_cast<float>(mesh.vertices_m[v][k])) {
        throw std::runtime_error("web_console: the glTF of " + mesh_file.string() + " has vertex " +
                                 std::to_string(v) + " elsewhere than the mesh: the export reordered its vertices");
      }
    }
  }
  return out;
}

std::vector<std::array<float, 3>> GlbPositions(const std::string& glb) {
  const auto fail = [](const std::string& what) { return std::runtime_error("not a binary glTF 2.0 mesh: " + what); };
  if (glb.size() < 28 || glb.compare(0, 4, "glTF") != 0 || Word(glb, 4) != 2u || Word(glb, 8) != glb.size()) {
    throw fail("no glTF 2 header of the blob's length");
  }
  const std::size_t json_bytes = Word(glb, 12);
  if (Word(glb, 16) != 0x4E4F534Au || 20 + json_bytes + 8 > glb.size()) throw fail("no JSON chunk");
  const std::size_t bin_at = 20 + json_bytes;
  const std::size_t bin_bytes = Word(glb, bin_at);
  if (Word(glb, bin_at + 4) != 0x004E4942u || bin_at + 8 + bin_bytes > glb.size()) throw fail("no BIN chunk");
  const auto j = nlohmann::json::parse(glb.substr(20, json_bytes), nullptr, false);
  if (j.is_discarded()) throw fail("its JSON chunk does not parse");
  try {
    const auto& accessor = j.at("accessors").at(j.at("meshes").at(0).at("primitives").at(0).at("attributes").at("POSITION").get<std::size_t>());
    if (accessor.at("componentType") != 5126 || accessor.at("type") != "VEC3") throw fail("positions are not float VEC3");
    const auto& view = j.at("bufferViews").at(accessor.at("bufferView").get<std::size_t>());
    const std::size_t count = accessor.at("count");
    const std::size_t stride = view.value("byteStride", std::size_t{12});
    const std::size_t at = bin_at + 8 + view.value("byteOffset", std::size_t{0}) + accessor.value("byteOffset", std::size_t{0});
    if (stride < 12 || (count > 0 && at + (count - 1) * stride + 12 > bin_at + 8 + bin_bytes)) {
      throw fail("positions outside the BIN chunk");
    }
    std::vector<std::array<float, 3>> out(count);
    for (std::size_t v = 0; v < count; ++v) std::memcpy(out[v].data(), glb.data() + at + v * stride, 12);
    return out;
  } catch (const nlohmann::json::exception& e) {
    throw fail(std::string("its JSON lacks a mesh's positions (") + e.what() + ")");
  }
}

}  // namespace handshare::web_console
