#include "handshare/web_console/gltf_export.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <stdexcept>

namespace handshare::web_console {

std::string ExportGlb(const std::filesystem::path& mesh_file) {
  Assimp::Importer importer;
  // Triangles with normals: what three.js draws lit.
  const aiScene* scene = importer.ReadFile(mesh_file.string(), aiProcess_Triangulate | aiProcess_GenSmoothNormals |
                                                                   aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mNumMeshes == 0) {
    throw std::runtime_error("web_console: cannot read the mesh " + mesh_file.string() + ": " +
                             importer.GetErrorString());
  }
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(scene, "glb2");
  if (blob == nullptr) {
    throw std::runtime_error("web_console: cannot export " + mesh_file.string() + " to glTF: " +
                             exporter.GetErrorString());
  }
  return std::string(static_cast<const char*>(blob->data), blob->size);
}

}  // namespace handshare::web_console
